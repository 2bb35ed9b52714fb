"""A teapot and a red ball under thin and under thick snow, after Chrisman's Fig. 4-5: thin snow lets the
ball's red bleed through (light scattered in the snow reaches the ball and comes back coloured), thick snow
hides it. Renders both side by side; saves teapot_and_ball.blend (the thick version) next to this script.

blender -b --factory-startup --python blend_samples/teapot_and_ball.py -- [--output out/teapot_and_ball.png]
"""

import os
import sys
import tempfile

import addon_utils
import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sample_common as common  # noqa: E402

DEPTHS = (("thin", 0.015, 0.003), ("thick", 0.06, 0.006))  # depth and voxel size, m


def build_scene():
    scene = common.new_scene()
    addon_utils.enable("add_mesh_extra_objects", default_set=True)
    bpy.ops.mesh.primitive_plane_add(size=1.4)
    table = bpy.context.object
    table.name = "Table"
    table.data.materials.append(common.material("Wood", (0.35, 0.22, 0.12), roughness=0.7))
    bpy.ops.mesh.primitive_teapot_add()
    teapot = bpy.context.object
    teapot.name = "Teapot"
    teapot.scale = (0.12, 0.12, 0.12)
    teapot.location = (-0.3, 0.1, 0.0)
    bpy.ops.object.shade_smooth()
    teapot.data.materials.append(common.material("Porcelain", (0.85, 0.85, 0.8), roughness=0.2))
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.18, location=(0.35, -0.15, 0.18), segments=64, ring_count=32)
    ball = bpy.context.object
    ball.name = "Red Ball"
    bpy.ops.object.shade_smooth()
    ball.data.materials.append(common.material("Red", (0.7, 0.03, 0.02), roughness=0.4))
    common.nishita_sky(scene, sun_elevation_deg=40.0, sun_rotation_deg=160.0)
    common.sun(elevation_deg=40.0, rotation_deg=160.0, irradiance=3.0)
    common.camera(location=(1.3, -1.5, 0.8), look_at=(0.0, 0.0, 0.15), lens=50)
    return scene, [table, teapot, ball]


def snow_version(name, depth, voxel_size, args, stages):
    scene, targets = stages.run(f"build scene ({name})", build_scene)
    snow = stages.run(f"add snow ({name})", common.add_snow, targets, depth=depth, spacing=max(0.01, depth / 2),
                      smoothness=0.8, voxel_size=voxel_size)
    stages.run(f"bake ({name})", common.bake, [snow])
    path = os.path.join(tempfile.mkdtemp(prefix="firn_panels_"), f"teapot_and_ball_{name}.png")
    stages.run(f"render ({name})", common.render, scene, path, args.width // 2, args.samples, aspect=(1, 1),
               label=f"{name} snow, {depth * 1000:.0f} mm")
    return path


def main():
    common.panels_sample(__file__, __doc__, lambda args, stages: [
        snow_version(name, depth, voxel, args, stages) for name, depth, voxel in DEPTHS])


if __name__ == "__main__":
    main()
