"""How far two bakes' grids lie apart (docs/benchmarks.md, car-sky: a change that alters values within the bake's
noise): per grid present in both, over the voxels where the first file's value (a vector's length) exceeds 1e-3
of its largest, the mean and the 99th percentile of |b - a| / |a|. Run it on two seeds of one build for the noise.

    /usr/bin/python3 bench/grids_relative.py A.vdb B.vdb
"""

import sys

import numpy as np
import pyopenvdb

from grids_identical import dense


def main():
    path_a, path_b = sys.argv[1], sys.argv[2]
    names = [g.name for g in pyopenvdb.readAllGridMetadata(path_a)]
    others = {g.name for g in pyopenvdb.readAllGridMetadata(path_b)}
    for name in (name for name in names if name in others):
        a, b = pyopenvdb.read(path_a, name), pyopenvdb.read(path_b, name)
        box = a.evalActiveVoxelBoundingBox()
        box = (tuple(min(p, q) for p, q in zip(box[0], b.evalActiveVoxelBoundingBox()[0])),
               tuple(max(p, q) for p, q in zip(box[1], b.evalActiveVoxelBoundingBox()[1])))
        va, vb = dense(a, box).astype(np.float64), dense(b, box).astype(np.float64)
        size_a = np.linalg.norm(va, axis=-1) if va.ndim == 4 else np.abs(va)
        size_d = np.linalg.norm(vb - va, axis=-1) if va.ndim == 4 else np.abs(vb - va)
        mask = size_a > 1e-3 * size_a.max()
        rel = size_d[mask] / size_a[mask]
        print(f"{name:>16}: {mask.sum():>9} voxels, mean |rel diff| {100 * rel.mean():.3f} %, "
              f"99th percentile {100 * np.percentile(rel, 99):.2f} %, max {100 * rel.max():.1f} %")


if __name__ == "__main__":
    main()
