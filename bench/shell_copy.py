"""Is the air shell's blend the balls' deficit against the sun? (docs/benchmarks.md, ball-back)

A grid poke, no core change: a suite case baked as bench/bake_suite.py bakes it (FINAL, seed 0, its cached
reference), then each air voxel next to the snow (two layers out, each from its densest face neighbour already
filled) given that neighbour's source grids: the broad lobes only (firn_source, firn_source_x/y/z; --peaks: the
peaked lobes too). What the render then shows through the density's ramp is the surface voxel's own value, as if the
shell held the surface's lobes unblended. Printed: each case's mean |error|, bias and view biases before and after,
and against_sun.py's bands of the view (180, 0) after.

    PYTHONPATH=build/python:bench python3 bench/shell_copy.py [--cases ball_grey,ball_snow] [--peaks]
"""

import argparse
import os
import tempfile

import numpy as np
import pyopenvdb

import bake_suite as S
import firncore
from against_sun import against_regions
from backlit_probe import write_without_peaks

PAD = 3  # voxels of air around the density's box


def shell_copied(path, density, peaks):
    """The baked file's air shell given its densest face neighbour's source grids, in place."""
    grids, metadata = pyopenvdb.readAll(path)
    shape = tuple(n + 2 * PAD for n in density.shape)
    arrays = {}
    for grid in grids:
        if grid.name.startswith("firn_source") and (peaks or "peak" not in grid.name):
            arrays[grid.name] = np.zeros(shape + (3,), np.float32)
            grid.copyToArray(arrays[grid.name], ijk=(-PAD,) * 3)
    rank = np.zeros(shape)
    rank[PAD:-PAD, PAD:-PAD, PAD:-PAD] = density
    filled = rank > 0
    index = np.indices(shape).transpose(1, 2, 3, 0)
    for _ in range(2):
        best, source = np.full(shape, -1.0), np.zeros(shape + (3,), int)
        for axis in range(3):
            for step in (-1, 1):
                neighbour = np.roll(rank, -step, axis=axis)
                take = ~filled & np.roll(filled, -step, axis=axis) & (neighbour > best)
                best[take] = neighbour[take]
                source[take] = index[take] + step * np.eye(3, dtype=int)[axis]
        new = ~filled & (best >= 0)
        i, j, k = np.nonzero(new)
        si, sj, sk = source[i, j, k].T
        for a in arrays.values():
            a[i, j, k] = a[si, sj, sk]
        rank[new] = 0.999 * best[new]  # the next layer takes the nearer voxel
        filled |= new
    for grid in grids:
        if grid.name in arrays:
            grid.clear()
            grid.copyFromArray(arrays[grid.name], ijk=(-PAD,) * 3, tolerance=(0.0, 0.0, 0.0))
    pyopenvdb.write(path, grids=list(grids), metadata=metadata)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="ball_grey,ball_snow,ball_clean,ball_rgb,ball_issue")
    parser.add_argument("--peaks", action="store_true", help="copy the peaked lobes' grids too")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        for name in args.cases.split(","):
            case = S.case(name)
            path = os.path.join(folder, name + ".vdb")
            run = S.baked_case(case, path, S.CACHE)
            seen = run.tau >= 1.0
            for label in ("main", "copied"):
                if label == "copied":
                    shell_copied(path, case.density, args.peaks)
                baked = firncore.render_baked(path, case.optics, run.origins, run.directions, occluders=case.occluders)
                r = S.scored(case, baked, run.mean, seen)
                print(f"{name:<14} {label:<6} mean {100 * r['mean']:5.2f} %  bias {100 * r['bias']:+5.2f} %  views "
                      + " ".join(f"{100 * x:+5.1f}" for x in r["view_bias"]), flush=True)
            write_without_peaks(path, path + ".broad.vdb")
            broad = firncore.render_baked(path + ".broad.vdb", case.optics, run.origins, run.directions)
            against_regions(case, run.origins, run.directions, run.tau, run.mean, baked, broad)


if __name__ == "__main__":
    main()
