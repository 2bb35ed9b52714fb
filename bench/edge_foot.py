"""box_sharp's worst block, the lit +x face's bottom edge, against the core's Monte Carlo (docs/benchmarks.md,
box-edge).

The worst block ((300, 45) row 0 col 6) passes under the +x face's bottom edge: it crosses the +x face's
half-density plane (x 13.5 voxels) at z 1.2, below the bottom's (z 1.5), through the corner's ramp alone (the box's
full voxels x 2..13, y 2..11, z 2..7; sun from +x at 30 degrees: +x lit at cos 0.87, the bottom in shadow). Printed:
(1) that ray shifted across the image in quarter voxels, both image axes; (2) the +x face's half-density plane hit at
heights 0.125 .. 1.75 voxel above the bottom edge (y 6) along the block's direction and head-on, and the bottom's
plane at the same distances in from the edge head-on and along the block's direction (rays from below); Monte Carlo
/ bake, green; (3) with --voxels the baked S(w) towards the block's camera of the voxels (x, 4, z), x 12..14, z 1..3.

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/edge_foot.py [--paths 4096] [--voxels]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from edge_blocks import image_axis

VIEW, ROW, COLUMN = 3, 0, 6
HEIGHTS = (0.125, 0.375, 0.625, 0.875, 1.25, 1.75)  # voxels from the bottom edge, on the face


def rays(case):
    origins, directions, _ = bake_suite.views(case)
    block = VIEW * case.pixels ** 2 + ROW * case.pixels + COLUMN
    h = case.voxel
    w = -directions[block]  # towards the block's camera
    out_o, out_d, labels = [], [], []
    for axis in ("u", "v"):
        along = image_axis(case, VIEW, axis)
        for s in np.arange(-4, 5) / 4.0:
            out_o.append(origins[block] + s * h * along), out_d.append(directions[block])
            labels.append(f"block shifted {axis} {s:+.2f}")
    for face, n, m in (("+x", (1.0, 0, 0), (0, 0, -1.0)), ("bottom", (0, 0, -1.0), (1.0, 0, 0))):
        n, m = np.array(n), np.array(m)
        for way, d in (("head-on", n), ("block's", w)):
            if d @ n <= 0.0:
                continue
            for s in HEIGHTS:
                point = (np.array([13.0, 6.0, 2.0]) + 0.5 * n + (0.5 - s) * m) * h
                out_o.append(point + 0.5 * d), out_d.append(-d)
                labels.append(f"{face} {way} {s:.3f} from the edge")
    return np.array(out_o), np.array(out_d), labels, w


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--paths", type=int, default=4096)
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_edge_foot"))
    parser.add_argument("--voxels", action="store_true")
    args = parser.parse_args()
    case = bake_suite.case("box_sharp")
    origins, directions, labels, w = rays(case)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "box.vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        # bake_suite's kept Monte Carlo; _mc: not the older files' keys (mc, error)
        cached = os.path.join(args.cache, f"foot_{args.paths}_mc.npz")
        mc, error, _ = bake_suite.cached_monte_carlo(cached, case, path, origins, directions, args.paths, seed=13)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=[], quality="FINAL", seed=0)
        baked = firncore.render_baked(path, case.optics, origins, directions, occluders=[])
        print(f"box_sharp's worst block {case.views[VIEW]} row {ROW} col {COLUMN}, towards {np.round(w, 3)}; "
              f"Monte Carlo (noise) / bake, green")
        for label, m, e, b in zip(labels, mc[:, 1], error[:, 1], baked[:, 1]):
            print(f"  {label:<34} MC {m:.4f} ({100 * e / max(m, 1e-30):4.1f} %)  bake {b:.4f}  "
                  f"{100 * (b / max(m, 1e-30) - 1):+6.1f} %")
        if args.voxels:
            from spray_shade_probe import grid_values, lobes
            voxels = [(x, 4, z) for z in (3, 2, 1) for x in (12, 13, 14)]
            values = grid_values(path, np.array(voxels, dtype=np.float64) * case.voxel)
            broad, peak = lobes(values, w, "broad")[:, 1], lobes(values, w, "peak")[:, 1]
            print("  baked S towards the block's camera at (x, 4, z), broad + peak:")
            for row in range(3):
                print("    " + "  ".join(f"{voxels[i]}: {broad[i]:.4f} + {peak[i]:.4f}"
                                         for i in range(3 * row, 3 * row + 3)))


if __name__ == "__main__":
    main()
