"""A smooth ridge (a layer whose top rises to a rounded crest along y, uniform in y) under a sun from +x 30 degrees up,
sun alone: its -x slope is shadowed below the crest. Rays in the plane y = the middle, from the -x side along the
view (180, 50) as bench/plate_crest_rows.py's, started at x over the shadowed slope, so they pass the air beside
the crest's voxels (smooth voxels with two or more air faces: their top lit, their -x side not) before reaching the
slope. Printed per ray: x of its depth-one point (voxels), the core's Monte Carlo (green, its standard error) and the
bake's error; and the rays' sum, baked over the Monte Carlo (docs/benchmarks.md, crest-face).

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/ridge_crest.py [--samples 2048] [--cache DIR]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore

WIDTH, LENGTH, HEIGHT = 24, 12, 12  # voxels along x (across the ridge), y (along it), z
CREST = 14.0  # x of the crest (voxels)


def ridge_top(x):
    """The ridge's top (voxels): a layer 3 voxels deep rising to 7.5 at the crest, half a cosine 6 voxels wide (its
    slopes up to 67 degrees: the -x slope turned from the sun below the crest)."""
    return 3.0 + 4.5 * np.clip(np.cos(2 * np.pi * (x - CREST) / 12.0), 0.0, None)


def ridge_case(sigma_t=1500.0, g=0.7):
    """bumpy_plate's snow (1 cm voxels, tau 15 a voxel, omega 0.999) in the ridge's shape, sun alone."""
    X, Y, Z = bs.grid((WIDTH, LENGTH, HEIGHT))
    fine = np.zeros(X.shape)
    for s in range(8):  # the top's coverage over a voxel's width
        fine += np.clip(ridge_top(X - 0.5 + (s + 0.5) / 8) - Z + 0.5, 0.0, 1.0) / 8
    fine[:, :, 0] = 0.0
    return bs.Case("ridge", "ridge along y, crest lit on +x", fine * 300, 0.01, sigma_t, 300.0, (0.999,) * 3, g,
                   sky=0.0)


def rays(case, starts):
    h = case.voxel
    a, e = math.radians(180.0), math.radians(50.0)
    back = np.array([math.cos(a) * math.cos(e), math.sin(a) * math.cos(e), math.sin(e)])
    origins = np.array([[x * h, 0.5 * (LENGTH - 1) * h, 14 * h] for x in starts])
    return origins, np.tile(-back, (len(origins), 1))


def measure(samples=2048, cache=None, starts=np.arange(2.0, 10.01, 0.5)):
    """Per ray: depth-one x (voxels), Monte Carlo green, its standard error, baked green."""
    case = ridge_case()
    origins, directions = rays(case, starts)
    hit = bs.depth_one_points(case, origins, directions, np.ones(len(origins), bool)) / case.voxel
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "ridge.vdb")
        bs.write_density(path, case.density, case.voxel)
        file = os.path.join(cache, f"ridge_{samples}_{case.key()}.npz") if cache else None
        truth, error, _ = bs.cached_monte_carlo(file, case, path, origins, directions, samples, seed=5)
        firncore.bake(path, case.optics, suns=case.suns(), quality="FINAL", seed=0)
        baked = firncore.render_baked(path, case.optics, origins, directions)
    return hit[:, 0], truth[:, 1], error[:, 1], baked[:, 1]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=2048)
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_ridge_crest"))
    args = parser.parse_args()
    x, truth, error, baked = measure(args.samples, args.cache)
    print(f"ridge, sun alone, view (180, 50), {args.samples} paths: depth-one x, Monte Carlo green (error), bake %")
    for k in range(len(x)):
        print(f"  x {x[k]:5.1f}  {truth[k]:.4f} ({error[k]:.4f})  {100 * (baked[k] / truth[k] - 1):+6.1f} %")
    print(f"sum baked / Monte Carlo: {baked.sum() / truth.sum():.3f}")


if __name__ == "__main__":
    main()
