"""Add Snow Layer against Blender's bundled Real Snow add-on, on the same scene in the same run.

blender -b --factory-startup --python bench/snow_layer_bench.py -- [--triangles N] [--skip-real-snow]
(bench/run.sh runs it with the add-on from the build tree.) Prints markdown rows; timings vary with the
machine's load, the ratio is what to compare.
"""

import argparse
import math
import sys
import time

import addon_utils
import bpy


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--triangles", type=int, default=1_000_000, help="about this many scene triangles")
    parser.add_argument("--skip-real-snow", action="store_true")
    return parser.parse_args(argv)


def build_scene(triangles):
    """A 4 x 4 m subdivided ground, a table and a dense sphere: about `triangles` triangles in all."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sphere_rings = 200
    sphere_triangles = 2 * sphere_rings * (2 * sphere_rings)
    cuts = max(1, int(math.sqrt(max(triangles - sphere_triangles, 2) / 2)) - 1)
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=cuts + 1, y_subdivisions=cuts + 1, size=4.0)
    ground = bpy.context.object
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.0, 0.0, 0.75), scale=(0.6, 0.4, 0.03))
    table = bpy.context.object
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.4, location=(1.2, 1.0, 0.4), segments=2 * sphere_rings,
                                         ring_count=sphere_rings)
    ball = bpy.context.object
    objects = [ground, table, ball]
    count = 0
    for obj in objects:
        obj.data.calc_loop_triangles()
        count += len(obj.data.loop_triangles)
    return objects, count


def select(objects):
    bpy.ops.object.select_all(action="DESELECT")
    for obj in objects:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = objects[0]


def time_firn(objects):
    addon_utils.enable("firn", default_set=True)
    select(objects)
    start = time.perf_counter()
    assert bpy.ops.firn.add_snow_layer(depth=0.1) == {"FINISHED"}
    return time.perf_counter() - start


def time_real_snow(objects):
    addon_utils.enable("real_snow", default_set=True)
    bpy.context.scene.snow.height = 0.1
    select(objects)
    start = time.perf_counter()
    assert bpy.ops.snow.create() == {"FINISHED"}
    return time.perf_counter() - start


def main():
    args = parse_args()
    objects, count = build_scene(args.triangles)
    firn_seconds = time_firn(objects)
    print("| scene triangles | Firn Add Snow Layer (s) | Real Snow (s) | Firn / Real Snow |")
    print("|---|---|---|---|")
    if args.skip_real_snow:
        print(f"| {count:,} | {firn_seconds:.2f} | not run | |")
        return
    objects, _ = build_scene(args.triangles)  # fresh scene, same geometry
    real_seconds = time_real_snow(objects)
    print(f"| {count:,} | {firn_seconds:.2f} | {real_seconds:.2f} | {firn_seconds / real_seconds:.3f} |")


main()
