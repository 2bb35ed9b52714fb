"""bumpy_plate's top seen row by row across the layer (docs/benchmarks.md, "plate-ramp"): where along y the baked top
is too bright or too dark.

Parallel rays of one view from the points (x, y, 14 voxels), above the snow and under the plate (z 22 voxels: rays
started further back would meet it), for x 3-26 (every voxel: the bumps' phases along x averaged out), one row per y
(voxel index; the cut sides' half density at -0.5 and 29.5); per row the baked render against the core's Monte Carlo
(green, summed over the row), FINAL, seed 0.
The rows y 0, 11 and 22 cross the bumps at the same phase (cos(2 pi y / 11 h) = 1).
--split X: each row's error also for the rays started at x < X and at x >= X (from (180, 50) the rays from x 19 on
meet the top within 2.5 voxels of the sunlit +x wall: the layer's corner with the cut side at y 0 or 29).
--omega W: the snow's single-scattering albedo instead of the case's 0.999 (a shorter diffusion length).
--zero X,Y (repeatable): the baked render with every source grid cleared over the voxel column (X, Y) (an oracle: how
much of a row's reading that column's voxels hold); --no-peak: with the peaked lobe's grids cleared; --quality: the
bake's (REFERENCE path traces every surface voxel's exit: what the grids' lobes can hold when their light is right).

    PYTHONPATH=build/python /usr/bin/python3 bench/plate_edge_profile.py [--view 180,50] [--light full|sun|sky]
        [--rows -0.35,0,0.5,1,2,4,8,11,22,29] [--samples 2048] [--split 19] [--omega 0.99]
        [--zero 29,0 --zero 29,1] [--no-peak] [--quality REFERENCE]
"""

import argparse
import copy
import math
import os
import tempfile

import numpy as np
import pyopenvdb

import bake_suite as bs
import firncore
from plate_err_regions import light_case


def cleared(path, columns, peak, out):
    """The baked file at path written to out with the source grids cleared over the voxel columns (x, y) and, with
    peak, the peaked lobe's grids cleared everywhere."""
    grids, metadata = pyopenvdb.readAll(path)
    for g in grids:
        if not g.name.startswith("firn_source"):
            continue
        if peak and "peak" in g.name:
            g.clear()
            continue
        accessor = g.getAccessor()
        lo, hi = g.evalActiveVoxelBoundingBox()
        for x, y in columns:
            for z in range(lo[2], hi[2] + 1):
                accessor.setValueOn((x, y, z), (0.0, 0.0, 0.0))
    pyopenvdb.write(out, grids=grids, metadata=metadata)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--view", default="180,50", help="azimuth, elevation (degrees)")
    parser.add_argument("--light", default="full", choices=("full", "sun", "sky"))
    parser.add_argument("--rows", default="-0.35,0,0.5,1,2,4,8,11,22,29")
    parser.add_argument("--samples", type=int, default=2048)
    parser.add_argument("--split", type=int, help="also the rays started at x < SPLIT and at x >= SPLIT apart")
    parser.add_argument("--omega", type=float, help="single-scattering albedo instead of the case's")
    parser.add_argument("--zero", action="append", default=[], help="X,Y: clear the sources over that column")
    parser.add_argument("--no-peak", action="store_true", help="clear the peaked lobe's grids")
    parser.add_argument("--quality", default="FINAL", help="the bake's quality (REFERENCE: the surface path traced)")
    args = parser.parse_args()
    case = light_case(next(c for c in bs.cases() if c.name == "bumpy_plate"), args.light)
    if args.omega is not None:
        case = copy.copy(case)
        case.omega = (args.omega,) * 3
    h = case.voxel
    azimuth, elevation = (math.radians(float(v)) for v in args.view.split(","))
    back = np.array([math.cos(azimuth) * math.cos(elevation), math.sin(azimuth) * math.cos(elevation),
                     math.sin(elevation)])  # towards the camera
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "bumpy.vdb")
        bs.write_density(path, case.density, h)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                      quality=args.quality, seed=0)
        if args.zero or args.no_peak:
            shown = os.path.join(folder, "cleared.vdb")
            cleared(path, [tuple(int(v) for v in c.split(",")) for c in args.zero], args.no_peak, shown)
        else:
            shown = path
        print(f"bumpy_plate, view ({args.view}), {args.light} light, {args.quality}: green, rows summed over x 3-26")
        xs = np.arange(3, 27)
        for y in (float(v) for v in args.rows.split(",")):
            origins = np.array([[x * h, y * h, 14 * h] for x in xs])
            directions = np.tile(-back, (len(origins), 1))
            reference = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                                      sky=case.skies(), occluders=case.occluders,
                                                      samples=args.samples, seed=5)[0]
            baked = firncore.render_baked(shown, case.optics, origins, directions, occluders=case.occluders)
            parts = [] if args.split is None else [(f"x < {args.split}", xs < args.split),
                                                   (f"x >= {args.split}", xs >= args.split)]
            split = "".join(f"; {name}: {100 * (baked[m, 1].sum() / reference[m, 1].sum() - 1):+.1f} %"
                            for name, m in parts)
            print(f"  y {y:6.2f}: baked {baked[:, 1].mean():.4f}, Monte Carlo {reference[:, 1].mean():.4f}, "
                  f"{100 * (baked[:, 1].sum() / reference[:, 1].sum() - 1):+.1f} %{split}", flush=True)


if __name__ == "__main__":
    main()
