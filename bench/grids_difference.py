"""How far two bakes' grids lie apart, against a bake's own noise (docs/bake.md, Performance: an approximate
speed-up's check): per baked grid, the voxels' relative differences weighted by the first bake's emission,
sum |a - b| / sum |a| over the active voxels (all channels), and the ratio of the sums; with a third file, the
same for the first against it (two seeds of one code: its noise).

    /usr/bin/python3 bench/grids_difference.py MAIN.vdb BRANCH.vdb [MAIN_OTHER_SEED.vdb]
"""

import sys

import numpy as np
import pyopenvdb

from grids_identical import dense


def difference(a, b):
    """sum |a - b| / sum |a| and sum b / sum a over a's active bounding box."""
    return np.abs(a - b).sum() / max(np.abs(a).sum(), 1e-30), b.sum() / a.sum() if a.sum() else float("nan")


def main(paths):
    names = [g.name for g in pyopenvdb.readAllGridMetadata(paths[0]) if g.name.startswith("firn_source")]
    print(f"{'grid':<22}" + "".join(f"{'vs ' + p.split('/')[-2]:>34}" for p in paths[1:]))
    print(f"{'':<22}" + "".join(f"{'weighted |diff|   sum ratio':>34}" for _ in paths[1:]))
    for name in names:
        grids = [pyopenvdb.read(p, name) for p in paths]
        box = grids[0].evalActiveVoxelBoundingBox()
        values = [dense(g, box) for g in grids]
        row = "".join(f"{d:>21.3%} {r:>12.5f}" for d, r in (difference(values[0], v) for v in values[1:]))
        print(f"{name:<22}{row}")


if __name__ == "__main__":
    main(sys.argv[1:])
