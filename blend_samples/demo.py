"""The README's main job: a small scene built from scratch, covered with snow by the add-on, rendered headless.

blender -b --factory-startup --python blend_samples/demo.py -- --output out/demo.png [--samples N] [--width W]
(scripts/demo.sh runs it with the add-on from the build tree.)
"""

import argparse
import math
import sys
import time

import addon_utils
import bpy


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--output", required=True)
    parser.add_argument("--samples", type=int, default=32)
    parser.add_argument("--width", type=int, default=480)
    return parser.parse_args(argv)


def build_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("firn", default_set=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_plane_add(size=6.0)
    ground = bpy.context.object
    ground.name = "Ground"
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.0, 0.0, 0.75), scale=(1.2, 0.8, 0.05))
    table = bpy.context.object
    table.name = "Table"
    for x in (-0.55, 0.55):
        for y in (-0.35, 0.35):
            bpy.ops.mesh.primitive_cylinder_add(radius=0.04, depth=0.72, location=(x, y, 0.36))
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.4, location=(1.6, 0.9, 0.4), segments=48, ring_count=24)
    bpy.ops.object.shade_smooth()
    ball = bpy.context.object
    ball.name = "Ball"
    red = bpy.data.materials.new("Red")
    red.diffuse_color = (0.6, 0.05, 0.04, 1.0)
    ball.data.materials.append(red)

    bpy.ops.object.light_add(type="SUN", rotation=(math.radians(50), 0.0, math.radians(30)))
    bpy.context.object.data.energy = 3.0
    world = bpy.data.worlds.new("Sky")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.45, 0.6, 0.9, 1.0)
    scene.world = world

    bpy.ops.object.camera_add(location=(5.2, -4.4, 2.9), rotation=(math.radians(66), 0.0, math.radians(50)))
    scene.camera = bpy.context.object
    return scene, [ground, table, ball]


def add_snow(targets):
    bpy.ops.object.select_all(action="DESELECT")
    for obj in targets:
        obj.select_set(True)
    result = bpy.ops.firn.add_snow_layer(depth=0.08, spacing=0.04)
    if result != {"FINISHED"}:
        raise RuntimeError(f"Add Snow Layer failed: {result}")


def render(scene, args):
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise
    scene.render.resolution_x = args.width
    scene.render.resolution_y = args.width * 9 // 16
    scene.render.resolution_percentage = 100
    scene.render.filepath = args.output
    scene.render.image_settings.file_format = "PNG"
    bpy.ops.render.render(write_still=True)


def main():
    args = parse_args()
    stages = []
    start = time.perf_counter()
    scene, targets = build_scene()
    stages.append(("build scene", time.perf_counter() - start))
    start = time.perf_counter()
    add_snow(targets)
    stages.append(("add snow layer", time.perf_counter() - start))
    start = time.perf_counter()
    render(scene, args)
    stages.append(("render (Cycles)", time.perf_counter() - start))
    for name, seconds in stages:
        print(f"firn demo: {name:>16}: {seconds:7.2f} s")


main()
