"""The same snow three ways, after Nishita et al. (1997), Fig. 6: as an opaque white surface, as a volume with
single scattering only, and with all orders of scattering baked by Firn. Renders the three side by side;
saves nishita_comparison.blend (the baked version) next to this script.

blender -b --factory-startup --python blend_samples/nishita_comparison.py -- [--output out/comparison.png]
"""

import os
import sys
import tempfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sample_common as common  # noqa: E402


def build_scene():
    scene = common.new_scene()
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    ground = bpy.context.object
    ground.data.materials.append(common.material("Soil", (0.2, 0.15, 0.1), roughness=0.9))
    stone = common.material("Stone", (0.35, 0.33, 0.3), roughness=0.8)
    targets = [ground]
    for location, scale in (((-0.6, 0.3, 0.3), (0.5, 0.4, 0.3)), ((0.7, -0.2, 0.45), (0.35, 0.35, 0.45))):
        bpy.ops.mesh.primitive_cube_add(size=1.0, location=location, scale=scale)
        block = bpy.context.object
        block.modifiers.new("Bevel", "BEVEL").width = 0.05
        block.data.materials.append(stone)
        targets.append(block)
    common.nishita_sky(scene, sun_elevation_deg=30.0, sun_rotation_deg=210.0)
    common.sun(elevation_deg=30.0, rotation_deg=210.0, irradiance=3.5)
    common.camera(location=(2.6, -3.0, 1.7), look_at=(0.0, 0.0, 0.3), lens=45)
    return scene, targets


def render_panels(args, stages):
    """(a) opaque, (b) single scattering, (c) baked multiple scattering: the three PNGs."""
    scene, targets = stages.run("build scene", build_scene)
    snow = stages.run("add snow layer", common.add_snow, targets, depth=0.1, spacing=0.04, surface_mesh=True)
    surface = next(child for child in snow.children if child.type == "MESH" and child != snow.firn.metaballs)
    surface.data.materials.append(common.material("Opaque Snow", (0.9, 0.9, 0.9), roughness=0.6))
    folder = tempfile.mkdtemp(prefix="firn_panels_")  # the parts; only the joined picture is kept
    panels = [os.path.join(folder, f"nishita_{name}.png") for name in ("opaque", "single", "multiple")]
    width = args.width // 3

    snow.hide_render, surface.hide_render = True, False
    stages.run("render opaque", common.render, scene, panels[0], width, args.samples, aspect=(1, 1),
               label="(a) opaque surface")
    snow.hide_render, surface.hide_render = False, True
    scene.cycles.volume_bounces = 0  # Cycles: exact single scattering, nothing more (cycles-volumes notes)
    stages.run("render single", common.render, scene, panels[1], width, args.samples, aspect=(1, 1),
               label="(b) single scattering")
    stages.run("bake", common.bake, [snow])
    stages.run("render multiple", common.render, scene, panels[2], width, args.samples, aspect=(1, 1),
               label="(c) multiple scattering")
    return panels


def main():
    common.panels_sample(__file__, __doc__, render_panels)


if __name__ == "__main__":
    main()
