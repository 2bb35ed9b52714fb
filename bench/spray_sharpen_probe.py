"""Whether spray_dense's traced voxels store their hat's mean where the renderer needs the field at their centre
(docs/benchmarks.md, spray-dense, stop 71).

A traced voxel's value reads right against the Monte Carlo over its whole trilinear hat (spray-core), but the renderer
blends those values trilinearly again: a twice-smoothed field. Per axis the tent of half-width h has variance
h²/6, so its mean is m = f + (h²/12) f'' + O(h⁴) and the centre value is f ≈ m − (1/12) Σ_axes (m₊ + m₋ − 2m)
(the discrete Laplacian of the stored values). Here the bake's six source grids of the snow voxels are scaled by f/m of
firn_source (per channel, the voxels' lobes kept) and the case rendered baked against the suite's reference:
"interior" sharpens only voxels whose six neighbours are snow, "all" every snow voxel (the air neighbours' carried
face values in its Laplacian).

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/spray_sharpen_probe.py [--case spray_dense] [--seeds 0,1]
"""

import argparse
import os
import tempfile

import numpy as np
import pyopenvdb

import bake_suite
import firncore
from spray_shade_probe import GRIDS


def sharpened_scale(source, snow, interior_only):
    """f/m per voxel and channel from the stored source m (the tent's second-order term removed), 1 elsewhere."""
    laplacian = -6.0 * source
    inner = snow.copy()
    for axis in range(3):
        for shift in (1, -1):
            laplacian += np.roll(source, shift, axis)
            inner &= np.roll(snow, shift, axis)
    keep = (inner if interior_only else snow)[..., None] & (source > 0.0)
    centre = np.maximum(source - laplacian / 12.0, 0.0)
    return np.where(keep, centre / np.where(source > 0.0, source, 1.0), 1.0)


def rescaled(path, out, scale):
    grids, metadata = pyopenvdb.readAll(path)
    for g in grids:
        if g.name in GRIDS:
            values = np.zeros(scale.shape, np.float32)
            g.copyToArray(values, ijk=(0, 0, 0))
            g.copyFromArray((values * scale).astype(np.float32), ijk=(0, 0, 0), tolerance=(0.0, 0.0, 0.0))
    pyopenvdb.write(out, grids=grids, metadata=metadata)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="spray_dense")
    parser.add_argument("--seeds", default="0,1")
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    snow = case.density > 0.0
    cache = bake_suite.CACHE
    for seed in (int(s) for s in args.seeds.split(",")):
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "s.vdb")
            run = bake_suite.baked_case(case, path, cache, "FINAL", seed)
            seen = run.tau >= 1.0
            grids, _ = pyopenvdb.readAll(path)
            source = np.zeros(case.density.shape + (3,), np.float32)
            next(g for g in grids if g.name == "firn_source").copyToArray(source, ijk=(0, 0, 0))
            line = f"{case.name} seed {seed}:"
            for label, variant in (("main", None), ("interior", True), ("all", False)):
                p = path
                if variant is not None:
                    p = os.path.join(folder, label + ".vdb")
                    rescaled(path, p, sharpened_scale(source.astype(np.float64), snow, variant))
                render = firncore.render_baked(p, case.optics, run.origins, run.directions, occluders=case.occluders)
                s = bake_suite.scored(case, render[:, 1], run.mean[:, 1], seen)
                line += (f"  {label} mean {100 * s['mean']:.2f} % worst {100 * s['worst_signed']:+.0f} % "
                         f"bias {100 * s['bias']:+.2f} %")
            print(line, flush=True)


if __name__ == "__main__":
    main()
