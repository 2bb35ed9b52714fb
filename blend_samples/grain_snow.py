"""Grain snow after Chrisman: a red ball under thin (left) and thick (right) snow made of ice spheres, rendered
by Cycles as true spheres with Fresnel reflection and refraction. The red bleeds through the thin snow. Saves
grain_snow.blend next to this script.

blender -b --factory-startup --python blend_samples/grain_snow.py -- [--output out/grain_snow.png]
"""

import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sample_common as common  # noqa: E402

GRAIN_RADIUS = 0.001  # m
BALL_RADIUS = 0.025  # m
# label, x (m), side of the ground square (m), grains on the ball and its square. Grains stay where they land
# (Chrisman's model: no avalanches) and pack loosely (volume fraction ~0.24), so a square fills up like a box: a
# sprinkling of 1 mm grains on the left; on the right about 10 cm of snow, several centimetres over and in front
# of the ball, many transport mean free paths of 1 mm grains (docs/grains.md).
PANELS = (("thin", -0.055, 0.08, 1500), ("thick", 0.06, 0.12, 160000))


def build_scene():
    scene = common.new_scene()
    common.nishita_sky(scene, sun_elevation_deg=35.0, sun_rotation_deg=-60.0, strength=0.3)
    common.sun(35.0, -60.0, irradiance=3.0)
    red = common.material("Red Ball", (0.8, 0.04, 0.03), roughness=0.9)
    grey = common.material("Ground", (0.35, 0.35, 0.35), roughness=0.9)
    pairs = []
    for label, x, side, _count in PANELS:
        bpy.ops.mesh.primitive_uv_sphere_add(radius=BALL_RADIUS, location=(x, 0.0, BALL_RADIUS), segments=48,
                                             ring_count=24)
        ball = bpy.context.object
        ball.name = f"Ball ({label})"
        ball.data.materials.append(red)
        bpy.ops.object.shade_smooth()
        bpy.ops.mesh.primitive_plane_add(size=side, location=(x, 0.0, 0.0))
        ground = bpy.context.object
        ground.name = f"Ground ({label})"
        ground.data.materials.append(grey)
        pairs.append((ball, ground))
    bpy.ops.mesh.primitive_plane_add(size=2.0, location=(0.0, 0.0, -0.001))  # the floor beyond, no grains
    bpy.context.object.data.materials.append(grey)
    common.camera((0.0, -0.22, 0.26), (0.0, 0.0, 0.03), lens=45.0)
    return scene, pairs


def add_grains(targets, count, seed):
    bpy.ops.object.select_all(action="DESELECT")
    for obj in targets:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = targets[0]
    if bpy.ops.firn.add_grain_snow(grain_radius=GRAIN_RADIUS, grain_radius_variation=0.3 * GRAIN_RADIUS,
                                   grain_count=count, seed=seed) != {"FINISHED"}:
        raise RuntimeError("Add Grain Snow failed")
    return bpy.context.object


def main():
    args = common.parse_args(__doc__.splitlines()[0], "out/grain_snow.png")
    stages = common.Stages()
    scene, pairs = stages.run("build scene", build_scene)
    for (label, _x, _side, count), targets in zip(PANELS, pairs):
        grains = stages.run(f"add grain snow ({label})", add_grains, targets, count, len(label))
        print(f"firn sample: {label}: {len(grains.data.vertices):,} grains of {GRAIN_RADIUS * 1e3:g} mm")
    stages.run("render (Cycles)", common.render, scene, args.output, args.width, args.samples, aspect=(2, 1),
               label="thin | thick grain snow")
    if not args.no_save:
        stages.run("save .blend", common.save_next_to, __file__, args.blend)
    print(f"firn sample: total {stages.total():.1f} s")


main()
