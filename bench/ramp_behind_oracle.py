"""What a ramp that showed cameras behind it the right light would be worth (docs/benchmarks.md, "plate-ramp"): an
oracle on the baked grids.

Bakes a suite case (FINAL, seed 0) and renders each view again from a copy of the grids in which every source grid's
value at the air voxels beside the snow (those that carry a surface's exit lobe) whose outward normal (the density's
gradient over 3^3) the view's rays leave along (n . d > --leaving) is scaled by --factor; 1/1.48 is the excess that
bench/ramp_from_behind.py measures in the ramp's outer part (x 29.85: +48 %). Against the suite's cached reference.

--edges (bumpy_plate): instead, for every view, the top snow voxel of each column on the layer's four cut sides (the
layer's convex top edge), and with --edges-air their air neighbours across the cut sides too (--air-only: those air
voxels alone, the render's blend of the edge with the air beside it). --corners (bumpy_plate):
the four voxel columns where two cut sides meet (the layer's vertical corners, snow and the air above), with --edges
added to them.

    PYTHONPATH=build/python /usr/bin/python3 bench/ramp_behind_oracle.py [--case bumpy_plate] [--factor 0.676]
        [--leaving 0] [--edges [--edges-air | --air-only]] [--corners]
"""

import argparse
import os
import tempfile

import numpy as np
import pyopenvdb

import bake_suite as bs
import firncore
from plate_ramp_behind import PAD, baked_and_reference, box_sum, padded_normals


def scaled_grids(path, mask, factor):
    """The file's grids with the source grids' values at mask (padded density index) scaled, and its metadata."""
    grids, metadata = pyopenvdb.readAll(path)
    for g in grids:
        if not g.name.startswith("firn_source"):
            continue
        lo, hi = g.evalActiveVoxelBoundingBox()
        shape = tuple(np.array(hi) - np.array(lo) + 1)
        values = np.zeros(shape + (3,), np.float32)
        g.copyToArray(values, ijk=lo)
        at = np.argwhere(np.ones(shape, bool)) + np.array(lo) + PAD
        inside = np.all((at >= 0) & (at < np.array(mask.shape)), axis=1)
        chosen = np.zeros(len(at), bool)
        chosen[inside] = mask[at[inside, 0], at[inside, 1], at[inside, 2]]
        values.reshape(-1, 3)[chosen] *= factor
        g.copyFromArray(values, ijk=tuple(lo), tolerance=(0.0, 0.0, 0.0))
    return grids, metadata


def cut_top_edges(snow, with_air):
    """bumpy_plate's convex top edge in the padded grid: each cut side's columns' top snow voxel (and the air
    voxel beside it across the side)."""
    last = PAD + snow.shape[0] - 2 * PAD - 1  # the layer's last index on x and y
    above = np.roll(snow, -1, axis=2)
    edge = np.zeros(snow.shape, bool)
    for axis in (0, 1):
        for at, out in ((PAD, -1), (last, 1)):
            index = [slice(None)] * 3
            index[axis] = at
            edge[tuple(index)] = (snow & ~above)[tuple(index)]
            if with_air:
                index[axis] = at + out
                edge[tuple(index)] |= np.take(snow & ~above, at, axis=axis)
    return edge


def corner_columns(snow):
    """bumpy_plate's four vertical corners in the padded grid: the voxel columns where two cut sides meet."""
    last = PAD + snow.shape[0] - 2 * PAD - 1
    corner = np.zeros(snow.shape, bool)
    for x in (PAD, last):
        for y in (PAD, last):
            corner[x, y, :] = True
    return corner


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="bumpy_plate")
    parser.add_argument("--factor", type=float, default=1 / 1.48)
    parser.add_argument("--leaving", type=float, default=0.0)
    parser.add_argument("--edges", action="store_true", help="scale bumpy_plate's cut top edge instead")
    parser.add_argument("--edges-air", action="store_true", help="with --edges: their air neighbours too")
    parser.add_argument("--corners", action="store_true", help="scale bumpy_plate's four vertical corner columns")
    parser.add_argument("--air-only", action="store_true", help="with --edges: only the air neighbours across the sides")
    args = parser.parse_args()
    case = next(c for c in bs.cases() if c.name == args.case)
    origins, directions, tau = bs.views(case)
    seen = tau >= 1.0
    per = case.pixels ** 2
    rho, normal = padded_normals(case)
    snow = rho > 0.0
    air_beside = ~snow & (box_sum(snow) > 0)

    def score(baked):
        rel = np.abs(baked[seen] / reference[seen] - 1.0)
        return (f"mean {100 * rel.mean():.2f} %, worst {100 * rel.max():.0f} %, "
                f"bias {100 * (baked[seen].sum() / reference[seen].sum() - 1):+.2f} %")

    with tempfile.TemporaryDirectory() as folder:
        path, baked, reference = baked_and_reference(case, folder, origins, directions)
        oracle = baked.copy()
        for v in range(len(case.views)):
            rays = slice(v * per, (v + 1) * per)
            if args.edges or args.corners:
                mask = corner_columns(snow) if args.corners else np.zeros(snow.shape, bool)
                if args.edges and args.air_only:
                    mask |= cut_top_edges(snow, True) & ~cut_top_edges(snow, False)
                elif args.edges:
                    mask |= cut_top_edges(snow, args.edges_air)
            else:
                mask = air_beside & (normal @ directions[v * per] > args.leaving)
            grids, metadata = scaled_grids(path, mask, args.factor)
            view_path = os.path.join(folder, f"view{v}.vdb")
            pyopenvdb.write(view_path, grids=grids, metadata=metadata)
            oracle[rays] = firncore.render_baked(view_path, case.optics, origins[rays], directions[rays],
                                                 occluders=case.occluders)
    edges = "the cut top edge's air neighbours across the sides" if args.air_only else \
        f"the cut top edge{' and its air neighbours' if args.edges_air else ''}"
    if args.corners:
        scaled = "the four corner columns" + (f" and {edges}" if args.edges else "")
    else:
        scaled = edges if args.edges else f"the ramp seen from behind (n . d > {args.leaving})"
    print(f"{case.name}: baked {score(baked)}; {scaled} x {args.factor:.3f}: {score(oracle)}")


if __name__ == "__main__":
    main()
