"""Firn next to Blender's bundled Real Snow add-on on the same scene: a table and a ball on the ground.
Real Snow (left) covers every upward face, also the ground under the table; Firn (right) leaves sheltered
ground bare and bakes the light in the snow. Renders both side by side.

blender -b --factory-startup --python blend_samples/firn_vs_real_snow.py -- [--output out/firn_vs_real_snow.png]
"""

import os
import sys
import tempfile

import addon_utils
import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sample_common as common  # noqa: E402


def build_scene():
    scene = common.new_scene()
    bpy.ops.mesh.primitive_plane_add(size=5.0)
    ground = bpy.context.object
    ground.data.materials.append(common.material("Soil", (0.2, 0.15, 0.1), roughness=0.9))
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.0, 0.0, 0.75), scale=(1.2, 0.8, 0.05))
    table = bpy.context.object
    wood = common.material("Wood", (0.35, 0.22, 0.12), roughness=0.7)
    table.data.materials.append(wood)
    legs = []
    for x in (-0.55, 0.55):
        for y in (-0.35, 0.35):
            bpy.ops.mesh.primitive_cylinder_add(radius=0.04, depth=0.72, location=(x, y, 0.36))
            bpy.context.object.data.materials.append(wood)
            legs.append(bpy.context.object)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.35, location=(1.3, 0.8, 0.35), segments=48, ring_count=24)
    ball = bpy.context.object
    bpy.ops.object.shade_smooth()
    ball.data.materials.append(common.material("Red", (0.6, 0.04, 0.03), roughness=0.4))
    common.nishita_sky(scene, sun_elevation_deg=35.0, sun_rotation_deg=200.0)
    common.sun(elevation_deg=35.0, rotation_deg=200.0, irradiance=3.5)
    common.camera(location=(3.6, -3.4, 1.8), look_at=(0.2, 0.1, 0.35), lens=40)
    return scene, [ground, table, ball] + legs


def real_snow(targets):
    addon_utils.enable("real_snow", default_set=True)
    bpy.context.scene.snow.height = 0.1
    bpy.ops.object.select_all(action="DESELECT")
    for obj in targets:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = targets[0]
    if bpy.ops.snow.create() != {"FINISHED"}:
        raise RuntimeError("Real Snow failed")


def main():
    args = common.parse_args(__doc__, "out/firn_vs_real_snow.png")
    stages = common.Stages()
    folder = tempfile.mkdtemp(prefix="firn_panels_")  # the parts; only the joined picture is kept
    panels = [os.path.join(folder, "real_snow.png"), os.path.join(folder, "firn.png")]
    scene, targets = stages.run("build scene", build_scene)
    stages.run("Real Snow", real_snow, targets)
    stages.run("render Real Snow", common.render, scene, panels[0], args.width // 2, args.samples, aspect=(1, 1),
               label="Real Snow (Blender)")
    scene, targets = stages.run("build scene again", build_scene)
    snow = stages.run("Firn: add snow layer", common.add_snow, targets, depth=0.1, spacing=0.04)
    stages.run("Firn: bake", common.bake, [snow])
    stages.run("render Firn", common.render, scene, panels[1], args.width // 2, args.samples, aspect=(1, 1),
               label="Firn")
    common.side_by_side(panels, args.output)
    print(f"firn sample: total {stages.total():.2f} s -> {args.output}")


if __name__ == "__main__":
    main()
