"""Render cost of snow's small-scale structure (issue 13) on the car sample: the baked car rendered plain, with
sub-balls, with glints, with both, and (--resolve) with the grains resolved; each twice, alternating, in one run.
Goal: sub-balls and glints at most 1.3x the plain render.

bench/run.sh bench/structure_bench.py [-- --width 240 --samples 32 --resolve]
"""

import argparse
import os
import sys
import tempfile
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blend_samples"))
import car_under_snow as car  # noqa: E402
import sample_common as common  # noqa: E402

VARIANTS = (  # label, sub-balls, glints, resolve grains
    ("plain", False, False, False),
    ("sub-balls", True, False, False),
    ("glints", False, True, False),
    ("sub-balls + glints", True, True, False),
)
RESOLVED = ("+ grains resolved", True, True, True)  # with --resolve: the close-up setting, far costlier


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--samples", type=int, default=32)
    parser.add_argument("--resolve", action="store_true", help="also render with Resolve Grains")
    args = parser.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
    scene, targets = car.build_scene()
    snow = common.add_snow(targets, depth=0.12, spacing=0.06, voxel_size=0.02)
    common.bake([snow], quality="DRAFT")
    folder = tempfile.mkdtemp(prefix="firn_bench_")
    variants = VARIANTS + ((RESOLVED,) if args.resolve else ())
    times = {label: [] for label, *_ in variants}
    for repeat in range(2):
        for label, sub_balls, glints, resolve in variants:
            snow.firn.sub_balls, snow.firn.glints, snow.firn.sub_ball_resolve = sub_balls, glints, resolve
            started = time.perf_counter()
            common.render(scene, os.path.join(folder, f"car_{repeat}.png"), args.width, args.samples)
            times[label].append(time.perf_counter() - started)
    print(f"car sample, {args.width} px wide, {args.samples} samples, {os.cpu_count()} threads, voxel 2 cm")
    print("variant               render s (best of 2)   vs plain")
    plain = min(times["plain"])
    for label, seconds in times.items():
        print(f"{label:<22}{min(seconds):10.1f}{min(seconds) / plain:17.2f}x")


main()
