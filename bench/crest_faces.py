"""bumpy_plate's crest and edge voxels seen face by face (docs/benchmarks.md, "plate-rows-sun 2"): through each air face
of a voxel the baked render against the core's Monte Carlo, along REFERENCE's 12 directions around the face's normal
(bake_source_function.cpp, referenceSurface's fitAround: mu 0.95, 0.7, 0.35, four azimuths each, rays from 3 voxels
out through the voxel's centre). Which face's light the bake misses, not only the voxel's sum.

Faces: those whose neighbour holds at most half the snow's density (the grid's outside is air). Per face: the Monte
Carlo's mean radiance (green) over the 12 rays, its relative standard error, and each bake's error over all 12 and per
ring of mu; sun alone by default (--light).

    PYTHONPATH=build/python /usr/bin/python3 bench/crest_faces.py [--light sun|sky|full] [--samples 1024]
        [--quality FINAL,REFERENCE] [--voxels 0,5,6:0,5,5:...]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore
from plate_err_regions import light_case

# The -x crest fin of the rows y 4-6 and the column under it, the same slope inside (x 14), the -y edge row's top
# (y 0) against the same bump phase inside (y 11).
VOXELS = "0,5,6:0,5,5:1,5,5:1,5,4:14,5,6:14,5,5:2,0,8:5,0,8:7,0,6:2,11,8:5,11,8:7,11,6"
FACES = ((1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1))
MUS = (0.95, 0.7, 0.35)


def around(n, mu, phi):
    """The unit direction at cosine mu to n, azimuth phi about it."""
    n = np.asarray(n, float)
    u = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    s = math.sqrt(1.0 - mu * mu)
    return mu * n + s * (math.cos(phi) * u + math.sin(phi) * v)


def air_faces(density, voxel):
    out = []
    for f in FACES:
        c = np.add(voxel, f)
        inside = np.all(c >= 0) and np.all(c < density.shape)
        if not inside or density[tuple(c)] <= 0.5 * density.max():
            out.append(f)
    return out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--light", default="sun", choices=("full", "sun", "sky"))
    parser.add_argument("--samples", type=int, default=1024)
    parser.add_argument("--quality", default="FINAL")
    parser.add_argument("--voxels", default=VOXELS)
    args = parser.parse_args()
    case = light_case(next(c for c in bs.cases() if c.name == "bumpy_plate"), args.light)
    h = case.voxel
    voxels = [tuple(int(v) for v in s.split(",")) for s in args.voxels.split(":")]
    rays = []  # (voxel, face, mu index, origin, direction)
    for voxel in voxels:
        centre = h * np.array(voxel, float)
        for f in air_faces(case.density, voxel):
            for k, mu in enumerate(MUS):
                for a in range(4):
                    w = around(f, mu, math.pi * (0.5 * a + 0.25 * (mu < 0.5)))
                    rays.append((voxel, f, k, centre + 3.0 * h * w, -w))
    origins = np.array([r[3] for r in rays])
    directions = np.array([r[4] for r in rays])
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "bumpy.vdb")
        bs.write_density(path, case.density, h)
        reference, error = (v[:, 1] for v in firncore.monte_carlo_radiance(
            path, case.optics, origins, directions, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
            samples=args.samples, seed=5))
        baked = {}
        for quality in args.quality.split(","):
            firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                          quality=quality, seed=0)
            baked[quality] = firncore.render_baked(path, case.optics, origins, directions,
                                                   occluders=case.occluders)[:, 1]
    print(f"bumpy_plate, {args.light} light: per air face, Monte Carlo green radiance (mean of 12 rays), each bake's "
          f"error (all; mu 0.95 / 0.7 / 0.35)")
    keys = [(r[0], r[1]) for r in rays]
    for voxel in voxels:
        density = case.density[voxel] / case.density.max()
        for f in air_faces(case.density, voxel):
            m = np.array([k == (voxel, f) for k in keys])
            ring = np.array([r[2] for r in rays])
            noise = 100 * math.sqrt((error[m] ** 2).sum()) / reference[m].sum()
            line = f"  {str(voxel):12s} ({density:.2f}) face {str(f):12s} MC {reference[m].mean():.4f} ±{noise:.1f} %"
            for quality, values in baked.items():
                err = lambda s: 100 * (values[s].sum() / reference[s].sum() - 1)
                rings = " / ".join(f"{err(m & (ring == k)):+.0f}" for k in range(3))
                line += f" | {quality} {err(m):+6.1f} % ({rings})"
            print(line, flush=True)


if __name__ == "__main__":
    main()
