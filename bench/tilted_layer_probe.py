"""A plane snow layer tilted towards or away from the sun, with bumpy_plate's snow, voxels, lights and views
(docs/benchmarks.md, bumpy-blocks): whether bumpy_plate's lit slopes read dark because they are tilted (a slanted
staircase of voxels under the sun) or because the bumps shadow and light each other.

Per tilt (degrees; positive: the top's normal leans towards the sun's azimuth): the layer's top z = depth -
tan(tilt) (x - centre) (voxels, rasterized as bake_suite.bumpy is), no plate, the reddish ground; 16 camera rays per
view on a 4 x 4 lattice (2 voxels apart) around the top's centre; the bake (FINAL, seed 0) against the core's Monte
Carlo (--paths, seed 11), green channel: mean signed and mean |error| per view, with the sun's and the camera's
cosine on the top's normal.

    PYTHONPATH=build/python:bench python3 bench/tilted_layer_probe.py [--tilts -50,-35,-20,0,20,35,50] [--sun-only]
"""

import argparse
import copy
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore

SIDE, DEPTH = 24, 6  # voxels: the layer's width and its depth at the centre


def tilted(case, tilt):
    """The case with its snow a plane layer tilted by `tilt` degrees (towards +x, the sun) and no plate; the top's
    centre (m) and unit normal."""
    slope = math.tan(math.radians(tilt))
    rise = int(math.ceil(abs(slope) * SIDE / 2))
    X, Y, Z = bake_suite.grid((SIDE, SIDE, DEPTH + 2 * rise + 3))
    centre = (SIDE - 1) / 2
    top = DEPTH + rise - slope * (X - centre)
    fill = np.clip(top - Z + 0.5, 0.0, 1.0)
    fill[:, :, 0] = 0.0
    out = copy.copy(case)
    out.density = fill * case.rho
    out.occluders = case.occluders[1:]
    n = np.array([slope, 0.0, 1.0]) / math.hypot(slope, 1.0)
    return out, np.array([centre, centre, DEPTH + rise]) * case.voxel, n


def rays(case, centre, normal):
    """16 rays per view at a 4 x 4 lattice on the top around its centre: origins, directions, view index."""
    lattice = (np.arange(4) - 1.5) * 2 * case.voxel
    along = np.cross([0.0, 1.0, 0.0], normal)
    origins, directions, view = [], [], []
    for v, (azimuth, elevation) in enumerate(case.views):
        a, e = math.radians(azimuth), math.radians(elevation)
        back = np.array([math.cos(a) * math.cos(e), math.sin(a) * math.cos(e), math.sin(e)])
        for s in lattice:
            for t in lattice:
                origins.append(centre + s * along + t * np.array([0.0, 1.0, 0.0]) + 0.5 * back)
                directions.append(-back)
                view.append(v)
    return np.array(origins), np.array(directions), np.array(view)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--tilts", default="-50,-35,-20,0,20,35,50")
    parser.add_argument("--paths", type=int, default=4096)
    parser.add_argument("--sun-only", action="store_true")
    args = parser.parse_args()
    base = bake_suite.case("bumpy_plate")
    if args.sun_only:
        base.sky = 0.0
    sun = np.array([math.cos(bake_suite.SUN_ELEVATION), 0.0, math.sin(bake_suite.SUN_ELEVATION)])
    for tilt in (float(x) for x in args.tilts.split(",")):
        case, centre, normal = tilted(base, tilt)
        o, d, view = rays(case, centre, normal)
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "tilted.vdb")
            bake_suite.write_density(path, case.density, case.voxel)
            mc, error = firncore.monte_carlo_radiance(path, case.optics, o, d, suns=case.suns(), sky=case.skies(),
                                                      occluders=case.occluders, samples=args.paths, seed=11)
            firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                          quality="FINAL", seed=0)
            baked = firncore.render_baked(path, case.optics, o, d, occluders=case.occluders)
        relative = baked[:, 1] / mc[:, 1] - 1.0
        parts = [f"{case.views[v]} cos camera {-(d[view == v][0] @ normal):+.2f}: "
                 f"bias {100 * relative[view == v].mean():+6.1f} % |e| {100 * np.abs(relative[view == v]).mean():5.1f} %"
                 for v in range(len(case.views))]
        print(f"tilt {tilt:+5.0f}  cos sun {normal @ sun:+.2f}  ref noise {100 * (error[:, 1] / mc[:, 1]).mean():.1f} %  "
              + "  ".join(parts), flush=True)


if __name__ == "__main__":
    main()
