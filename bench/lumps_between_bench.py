"""Light between small pieces left to the diffusion, against the core's Monte Carlo (branch skier-between,
docs/benchmarks.md "Light between the pieces").

Lumps as the skier sample's (1.2 cm balls on 1 cm voxels, 40 optical depths per voxel at the centre, g 0.845,
omega 0.99998), each case baked (DRAFT) and rendered against `firncore.monte_carlo_radiance`:
  cluster: lump B alone, then B at the centre of a 3 x 3 x 3 cluster (centres 6 cm apart), under a 30 degree sun,
           over a ground 3 cm under the grid that is black, then white (albedo 0.9): B seen from 14 directions,
           its disk of pixels from just outside it (no other lump in front). What the neighbours and the ground
           add to B, baked against the Monte Carlo's gain.
  pile:    the same cluster with centres 5 cm apart resting on a white ground (albedo 0.97).
  cube:    216 lumps 5 cm apart (a 30 cm cube) over a ground 1 cm under it, seen whole from the side: under a
           uniform sky over a grey ground (0.3), and under the sun over a white (0.97) and a black ground.
400 far lumps (30 cm and more away) put the cluster over the tracing budget, and light tracing is turned off
(light_tracing=False), so the diffusion takes every lump. Usage:
  PYTHONPATH=build/python /usr/bin/python3 bench/lumps_between_bench.py [--samples 128] [--folder DIR] [--cache DIR]
--cache keeps the Monte Carlo's sums (one JSON file per case and sample count) and reads them back: a change of the
bake is measured in a minute or two instead of five.
"""

import argparse
import json
import math
import os
import tempfile
import time

import numpy as np

import bake_suite

H = 0.01  # m, the lumps' voxels
OPTICS_ARGS = (16.36, (0.99998,) * 3, 0.845)


def lump():
    return bake_suite.ball(0.012, H, pad=1) * 250.0


def plane(z, albedo):
    return (np.array([[-10, -10, z], [10, -10, z], [10, 10, z], [-10, 10, z]], np.float32),
            np.array([[0, 1, 2], [0, 2, 3]], np.uint32), (albedo,) * 3)


def cluster_density(gap, neighbours):
    """Lump B with its corner at index m (and its 26 neighbours, `gap` voxels of grid between them), 400 far lumps."""
    piece = lump()
    s = piece.shape[0]
    m, far, step = 2 * s + gap, 20, s + 5
    density = np.zeros((3 * m + s, 3 * m + 60 + far * step, 3 * m + far * step))
    corners = [np.array([m, m, m])]
    if neighbours:
        corners += [corners[0] + (s + gap) * (np.array(c) - 1) for c in np.ndindex(3, 3, 3) if c != (1, 1, 1)]
    corners += [np.array([m, 3 * m + 60 + j * step, k * step]) for j in range(far) for k in range(far)]
    for c in corners:
        box = tuple(slice(a, a + s) for a in c)
        density[box] = np.maximum(density[box], piece)
    return density, (np.array([m, m, m]) + (s - 1) / 2) * H, 0.55 * s * H


def views_of(centre, radius, views, pixels):
    """Parallel rays over the lump's disk from just outside it, from `views` directions of a Fibonacci sphere."""
    k = np.arange(views) + 0.5
    z, phi = 1 - 2 * k / views, math.pi * (1 + 5 ** 0.5) * k
    origins, directions = [], []
    u = ((np.arange(pixels) + 0.5) / pixels * 2.0 - 1.0) * radius
    for back in np.stack([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z], 1):
        up = np.array([0.0, 0.0, 1.0]) if abs(back[2]) < 0.99 else np.array([1.0, 0.0, 0.0])
        right = np.cross(up, back)
        right /= np.linalg.norm(right)
        up = np.cross(back, right)
        for v in u:
            for w in u:
                if v * v + w * w <= radius * radius:
                    origins.append(centre + 1.1 * radius * back + w * right + v * up), directions.append(-back)
    return np.array(origins), np.array(directions)


def measure(firncore, path, density, origins, directions, light, occluders, samples, cached=None):
    """Baked and Monte Carlo sums of the green channel over the rays, and the Monte Carlo's noise; `cached`: a JSON
    file holding (or to hold) the Monte Carlo's two figures."""
    bake_suite.write_density(path, density, H)
    optics = firncore.VolumeOptics(*OPTICS_ARGS)
    stats = firncore.bake(path, optics, occluders=occluders, quality="DRAFT", seed=0, source_scale=1,
                          light_tracing=False, **light)
    assert stats["traced_voxels"] == 0 and stats["light_traced_voxels"] == 0
    baked = firncore.render_baked(path, optics, origins, directions, occluders=occluders)[:, 1].sum()
    if cached and os.path.exists(cached):
        with open(cached) as f:
            reference = json.load(f)
        return baked, reference["mean"], reference["error"]
    mean, error = firncore.monte_carlo_radiance(path, optics, origins, directions, occluders=occluders,
                                                samples=samples, seed=1, **light)
    reference = dict(mean=float(mean[:, 1].sum()), error=math.sqrt(float((error[:, 1] ** 2).sum())))
    if cached:
        with open(cached, "w") as f:
            json.dump(reference, f)
    return baked, reference["mean"], reference["error"]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=128, help="Monte Carlo paths per pixel")
    parser.add_argument("--folder", default=None, help="keep the files here (default: a temporary folder)")
    parser.add_argument("--cache", default=None, help="keep and reuse the Monte Carlo's sums in this folder")
    args = parser.parse_args()
    import firncore

    folder = args.folder or tempfile.mkdtemp()
    if args.cache:
        os.makedirs(args.cache, exist_ok=True)

    def cached(name, samples):
        return os.path.join(args.cache, f"{name}_{samples}.json") if args.cache else None
    path = os.path.join(folder, "lumps.vdb")
    e = math.radians(30.0)
    dark = firncore.Sky((0.0,) * 3)
    sun = dict(suns=[firncore.SunLight((math.cos(e), 0.0, math.sin(e)), (1.0,) * 3, 0.0093)], sky=dark)
    start = time.time()
    print(f"samples {args.samples} per pixel; baked / Monte Carlo - 1 (noise), and what the surroundings add to B")
    for name, gap, ground_z, albedos in (("cluster", 1, -0.03, (0.0, 0.9)), ("pile", 0, 0.06, (0.97,))):
        among = []  # B among the others, per ground
        for albedo in albedos:
            sums = {}
            for neighbours in (False, True):
                density, centre, radius = cluster_density(gap, neighbours)
                origins, directions = views_of(centre, radius, 14, 16)
                sums[neighbours] = measure(firncore, path, density, origins, directions, sun,
                                           [plane(ground_z, albedo)], args.samples,
                                           cached(f"{name}_{albedo}_{int(neighbours)}", args.samples))
            (b0, m0, _), (b1, m1, e1) = sums[False], sums[True]
            print(f"  {name} over ground {albedo:.2f}: B alone {100 * (b0 / m0 - 1):+.1f} %, among the others "
                  f"{100 * (b1 / m1 - 1):+.1f} % ({100 * e1 / m1:.1f}); they add baked {100 * (b1 / b0 - 1):+.1f} %, "
                  f"Monte Carlo {100 * (m1 / m0 - 1):+.1f} %", flush=True)
            among.append((b1, m1))
        if len(among) == 2:
            (b_black, m_black), (b_white, m_white) = among
            print(f"  the white ground's light on B among the others: baked / Monte Carlo "
                  f"{(b_white - b_black) / (m_white - m_black):.2f}", flush=True)
    piece, n, step = lump(), 6, 5
    side = (n - 1) * step + piece.shape[0]
    cube = np.zeros((side, side, side))
    for i, j, k in np.ndindex(n, n, n):
        box = tuple(slice(a * step, a * step + piece.shape[0]) for a in (i, j, k))
        cube[box] = np.maximum(cube[box], piece)
    u = (np.arange(16) + 0.5) / 16 * side * H
    U, V = np.meshgrid(u, u)
    origins = np.stack([U.ravel(), np.full(U.size, -0.5), V.ravel()], 1)
    directions = np.tile([0.0, 1.0, 0.0], (U.size, 1))
    sun_across = dict(suns=[firncore.SunLight((math.cos(e), 0.3, math.sin(e)), (1.0,) * 3, 0.0093)], sky=dark)
    for label, light, albedo in (("uniform sky, grey ground", dict(sky=firncore.Sky((1.0,) * 3)), 0.3),
                                 ("sun, white ground", sun_across, 0.97), ("sun, black ground", sun_across, 0.0)):
        b, m, err = measure(firncore, path, cube, origins, directions, light, [plane(-0.01, albedo)], 64,
                            cached(f"cube_{label.replace(' ', '').replace(',', '_')}", 64))
        print(f"  cube, {label}: {100 * (b / m - 1):+.1f} % ({100 * err / m:.1f})", flush=True)
    print(f"{time.time() - start:.0f} s wall, load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
