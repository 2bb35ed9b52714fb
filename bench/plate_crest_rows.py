"""bumpy_plate's -y cut edge along the suite's view (180, 50), ray by ray, against the core's Monte Carlo
(docs/benchmarks.md, "plate-sides"): rays in the plane y = Y (voxels) of the view, started at z 14 voxels, whose
depth-one points run over the slope facing away from the sun up to its crest (x 12-18), and the same bump phase
inside (y 11). Printed per ray: x of its depth-one point, the Monte Carlo's green radiance and its standard error,
the bake's error. The Monte Carlo is cached per light and path count in --cache. --scale X,Z,F (an oracle): the render with every
firn_source grid's values scaled by F over the voxel row (X, every y, Z).

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/plate_crest_rows.py [--light sun|sky|full]
        [--samples 2048] [--rows=-0.35,0,0.5,11] [--scale X,Z,F ...]
"""

import argparse
import math
import os
import tempfile

import numpy as np
import pyopenvdb

import bake_suite as bs
import firncore
from plate_err_regions import light_case


def rays(case, rows, starts):
    h = case.voxel
    a, e = math.radians(180.0), math.radians(50.0)
    back = np.array([math.cos(a) * math.cos(e), math.sin(a) * math.cos(e), math.sin(e)])
    origins = np.array([[x * h, y * h, 14 * h] for y in rows for x in starts])
    return origins, np.tile(-back, (len(origins), 1))


def scaled_row(path, x, z, factor, out):
    """The baked file at path written to out with every firn_source grid scaled by factor over voxels (x, *, z)."""
    grids, metadata = pyopenvdb.readAll(path)
    for g in grids:
        if not g.name.startswith("firn_source"):
            continue
        accessor = g.getAccessor()
        for y in range(-2, 40):
            value, on = accessor.probeValue((x, y, z))
            if on:
                accessor.setValueOn((x, y, z), tuple(factor * v for v in value) if isinstance(value, tuple)
                                    else factor * value)
    pyopenvdb.write(out, grids=grids, metadata=metadata)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--light", default="sun", choices=("full", "sun", "sky"))
    parser.add_argument("--samples", type=int, default=2048)
    parser.add_argument("--rows", default="-0.35,0,0.5,11")
    parser.add_argument("--scale", action="append", default=[], help="X,Z,F: the row (X, *, Z) scaled by F")
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_plate_crest"))
    args = parser.parse_args()
    os.makedirs(args.cache, exist_ok=True)
    case = light_case(bs.case("bumpy_plate"), args.light)
    rows = [float(v) for v in args.rows.split(",")]
    starts = np.arange(7.0, 13.01, 0.5)
    origins, directions = rays(case, rows, starts)
    hit = bs.depth_one_points(case, origins, directions, np.ones(len(origins), bool)) / case.voxel
    file = os.path.join(args.cache, f"{args.light}_{args.samples}_{args.rows}.npz")
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "bumpy.vdb")
        bs.write_density(path, case.density, case.voxel)
        truth, error, _ = bs.cached_monte_carlo(file, case, path, origins, directions, args.samples, seed=5)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                      quality="FINAL", seed=0)
        for k, spec in enumerate(args.scale):
            x, z, factor = spec.split(",")
            shown = os.path.join(folder, f"scaled{k}.vdb")
            scaled_row(path, int(x), int(z), float(factor), shown)
            path = shown
        baked = firncore.render_baked(path, case.optics, origins, directions, occluders=case.occluders)
    print(f"bumpy_plate, {args.light} alone, view (180, 50), {args.samples} paths: per row, each ray's depth-one x "
          f"(voxels), Monte Carlo green, bake error %" + (f"; scaled {args.scale}" if args.scale else ""))
    n = len(starts)
    for k, y in enumerate(rows):
        m = slice(k * n, (k + 1) * n)
        t, b = truth[m, 1], baked[m, 1]
        row = 100 * (b.sum() / t.sum() - 1)
        print(f"  y {y:5.2f} (row {row:+5.1f} %): " + "  ".join(
            f"{x:4.1f} {v:.3f} {100 * (bv / v - 1):+4.0f}" for x, v, bv in zip(hit[m, 0], t, b)), flush=True)


if __name__ == "__main__":
    main()
