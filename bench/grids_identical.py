"""Whether two VDB files hold the same grids value for value (docs/bake.md, Performance: an exact speed-up's
check): the same grid names, and per grid its active voxel count, its active bounding box and every value over
that box.

    /usr/bin/python3 bench/grids_identical.py A.vdb B.vdb      # exit status 0 when all are identical
"""

import sys

import numpy as np
import pyopenvdb


def dense(grid, box):
    """The grid's values over box (its active bounding box) as an array, vectors in a last axis of 3."""
    shape = tuple(int(box[1][k] - box[0][k] + 1) for k in range(3))
    vector = "Vec3" in type(grid).__name__
    values = np.zeros(shape + ((3,) if vector else ()), np.float32)
    grid.copyToArray(values, ijk=box[0])
    return values


def compare(path_a, path_b):
    names = [g.name for g in pyopenvdb.readAllGridMetadata(path_a)]
    others = [g.name for g in pyopenvdb.readAllGridMetadata(path_b)]
    same = sorted(names) == sorted(others)
    if not same:
        print(f"grids differ: {sorted(names)} against {sorted(others)}")
    for name in (name for name in names if name in others):
        a, b = pyopenvdb.read(path_a, name), pyopenvdb.read(path_b, name)
        box = a.evalActiveVoxelBoundingBox()
        if a.activeVoxelCount() != b.activeVoxelCount() or box != b.evalActiveVoxelBoundingBox():
            print(f"{name}: active voxels differ ({a.activeVoxelCount()} against {b.activeVoxelCount()})")
            same = False
            continue
        va, vb = dense(a, box), dense(b, box)
        equal = np.array_equal(va, vb)
        same &= equal
        detail = "" if equal else (f", {np.count_nonzero(va != vb)} values differ, at most {np.abs(va - vb).max():.3g} "
                                   f"of {np.abs(va).max():.3g}")
        print(f"{name}: {a.activeVoxelCount()} active, identical {equal}{detail}")
    print("ALL IDENTICAL" if same else "DIFFERENT")
    return same


if __name__ == "__main__":
    sys.exit(0 if compare(sys.argv[1], sys.argv[2]) else 1)
