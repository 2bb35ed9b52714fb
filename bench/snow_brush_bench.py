"""Snow Brush (issue 15) on the car sample's snow: ms per dab, against rasterizing the whole snow again.

bench/run.sh bench/snow_brush_bench.py [-- --dabs N --radius M]   (blender -b with the add-on from the build tree)
Goal: <= 30 ms per dab (median and worst), no dab rebuilding the whole grid (leaves rasterized per dab, printed).
The dabs walk across the car and the ground around it, one core call each (as the modal brush makes them).
"""

import argparse
import os
import statistics
import sys
import time

import addon_utils
import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blend_samples"))
import car_under_snow  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--dabs", type=int, default=60)
    parser.add_argument("--radius", type=float, default=0.3)
    parser.add_argument("--strength", type=float, default=0.02)
    return parser.parse_args(argv)


def surface_points(count):
    """Points on the scene's surfaces (snow proxy included) under a line across the car, from above."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    points = []
    for x in np.linspace(-3.0, 3.0, count):
        hit, location, *_rest = bpy.context.scene.ray_cast(depsgraph, (x, 0.3 * x, 20.0), (0.0, 0.0, -1.0))
        if hit:
            points.append(tuple(location))
    return points


def main():
    args = parse_args()
    addon_utils.enable("firn", default_set=True)
    from firn.common.core import firncore
    from firn.snow_layer import brush

    _scene, targets = car_under_snow.build_scene()
    snow = car_under_snow.add_car_snow(targets)
    path = bpy.path.abspath(snow.data.filepath)
    voxels = firncore.grid_statistics(path, "density")["active_voxels"]

    start = time.perf_counter()
    _snow, canvas = brush._snow_and_canvas(bpy.context)
    canvas_s = time.perf_counter() - start
    metaballs = canvas.metaballs()
    settings = brush.core_settings(snow.firn.layer, 50e6, 1.0)
    start = time.perf_counter()
    firncore.rasterize_metaballs(metaballs, settings, path + ".full.vdb")
    full_s = time.perf_counter() - start

    points = surface_points(args.dabs)
    print(f"car sample: {voxels:,} active density voxels in {canvas.leaf_count:,} leaves (surface grid), "
          f"{len(metaballs['radii']):,} metaballs; canvas made "
          f"(file read, ball index, ray caster) in {canvas_s:.2f} s; whole snow rasterized and written in "
          f"{full_s:.2f} s; {len(points)} dabs of radius {args.radius} m, strength {args.strength} m\n")
    # Wall time is what the user waits; processor time (all threads) does not count the time other programs
    # held the cores, so it shows the dab's own cost on a busy machine.
    print("| mode | median ms/dab | worst ms/dab | CPU ms/dab, all threads (median / worst) "
          "| leaves per dab (median / most) | balls per dab (median) |")
    print("|---|---|---|---|---|---|")
    for mode in ("ADD", "SMOOTH", "ERASE"):
        times, cpu, leaves, balls = [], [], [], []
        for point in points:
            start, start_cpu = time.perf_counter(), time.process_time()
            stats = canvas.stroke(np.array([point]), np.array([1.0]), mode, args.radius, args.strength)
            times.append((time.perf_counter() - start) * 1000.0)
            cpu.append((time.process_time() - start_cpu) * 1000.0)
            leaves.append(stats["leaves"])
            balls.append(stats["added"] + stats["removed"] + stats["changed"])
        print(f"| {mode} | {statistics.median(times):.1f} | {max(times):.1f} | {statistics.median(cpu):.1f} / "
              f"{max(cpu):.1f} | {statistics.median(leaves):.0f} / {max(leaves)} | {statistics.median(balls):.0f} |")
    start = time.perf_counter()
    canvas.write(path + ".stroke.vdb")
    print(f"\nA stroke's end: grids written in {time.perf_counter() - start:.2f} s")


main()
