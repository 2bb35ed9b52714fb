"""The sky-lit wall under a sharp top edge against the core's Monte Carlo (docs/benchmarks.md, edge-wall).

test_bake_accuracy's box (wall_on_ground_bench: 12 x 12 x 6 voxels of 1 cm, tau 15 per voxel, omega 0.999, g 0.7) on
a black ground under the sky alone (or --sun: the sun 30 degrees high facing the wall, and the sky): the +x wall
head-on at heights 3 … 7.4 voxels (the top edge voxel spans 6.5 … 7.5) and the top head-on at 0.1 … 3.5 voxels from
the edge, each a row of 8 rays along y on the density's half level; then the test's own views (rows 4–6 from 55
degrees above and 30 degrees below) and the same of the edge voxel's row 7. Printed: the Monte Carlo's radiance
(green, the row's mean) and baked / Monte Carlo. The Monte Carlo is kept in --cache (docs/benchmarks.md: 1024 paths).

    PYTHONPATH=build/python /usr/bin/python3 bench/edge_wall.py [--sun] [--samples 2048]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore
import wall_on_ground_bench as wall

H = wall.H
WALL_HEIGHTS = (3.0, 4.0, 5.0, 5.5, 5.75, 6.0, 6.25, 6.5, 6.75, 7.0, 7.25, 7.4)  # voxels
TOP_FROM_EDGE = (0.1, 0.25, 0.5, 0.75, 1.0, 1.5, 2.5, 3.5)  # voxels from the +x edge (x 13.5) along the top


def head_on_rows():
    """(label, origins, directions) per row: the wall's heights, then the top's distances from the edge."""
    rows = []
    for z in WALL_HEIGHTS:
        points = np.array([[13.5 * H, (y + 0.5) * H, z * H] for y in range(4, 12)])
        rows.append((f"wall z {z:4.2f}", points + [0.2, 0.0, 0.0], np.tile([-1.0, 0.0, 0.0], (8, 1))))
    for d in TOP_FROM_EDGE:
        points = np.array([[(13.5 - d) * H, (y + 0.5) * H, 7.5 * H] for y in range(4, 12)])
        rows.append((f"top  {d:4.2f} from edge", points + [0.0, 0.0, 0.2], np.tile([0.0, 0.0, -1.0], (8, 1))))
    for heights, name in (((4.0, 5.0, 6.0), "test's rows 4-6"), ((7.0,), "the edge voxel's row 7")):
        for elevation in (55.0, -30.0):
            origins, directions = wall.wall_rays(heights, elevation, 0.03)
            rows.append((f"{name} at {elevation:+g} deg", origins, directions))
    return rows


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--sun", action="store_true")
    parser.add_argument("--samples", type=int, default=2048)
    parser.add_argument("--cache", default="/tmp/wt_edge-wall/mc")
    args = parser.parse_args()
    light = dict(sky=firncore.Sky((0.05,) * 3),
                 suns=[firncore.SunLight((math.cos(math.pi / 6), 0.0, 0.5), (1.0,) * 3, 0.0093)] if args.sun else [])
    rows = head_on_rows()
    origins = np.concatenate([r[1] for r in rows])
    directions = np.concatenate([r[2] for r in rows])
    os.makedirs(args.cache, exist_ok=True)
    with tempfile.TemporaryDirectory() as folder:
        _, path, optics, ground = wall.baked_box(os.path.join(folder, "box.vdb"), 0.0, light)
        cached = os.path.join(args.cache, f"wall_{'sun' if args.sun else 'sky'}_{args.samples}_{len(origins)}.npz")
        if os.path.exists(cached):
            mc = np.load(cached)["mc"]
        else:
            mc = firncore.monte_carlo_radiance(path, optics, origins, directions, occluders=ground,
                                               samples=args.samples, seed=5, **light)[0]
            np.savez(cached, mc=mc)
        baked = firncore.render_baked(path, optics, origins, directions, occluders=ground)
    start = 0
    for label, o, _ in rows:
        part = slice(start, start + len(o))
        start += len(o)
        print(f"{label:28s} MC {mc[part, 1].mean():.5f}  baked/MC {baked[part, 1].sum() / mc[part, 1].sum():.3f}")


if __name__ == "__main__":
    main()
