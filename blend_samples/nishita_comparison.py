"""The same snow four ways, after Nishita et al. (1997), Fig. 6: (a) an opaque surface, (b) single scattering
with sub-balls, (c) multiple scattering (baked) without and (d) with sub-balls, each a render mode of the snow
(obj.firn.render_mode, sub_balls). Renders the four side by side; saves nishita_comparison.blend (the baked
version, with sub-balls) next to this script.

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


PANELS = (  # name, render mode, sub-balls, label
    ("opaque", "OPAQUE", False, "(a) opaque surface"),
    ("single", "SINGLE", True, "(b) single scattering, sub-balls"),
    ("multiple", "BAKED", False, "(c) multiple scattering"),
    ("sub_balls", "BAKED", True, "(d) multiple, sub-balls"),
)


def render_panels(args, stages):
    """The four panels of Fig. 6 as PNGs."""
    scene, targets = stages.run("build scene", build_scene)
    snow = stages.run("add snow layer", common.add_snow, targets, depth=0.1, spacing=0.04)
    snow.firn.sub_ball_radius = 2e-3  # coarse grains, as Nishita's, seen from a few metres
    snow.firn.sub_ball_resolve = True
    stages.run("bake", common.bake, [snow])
    folder = tempfile.mkdtemp(prefix="firn_panels_")  # the parts; only the joined picture is kept
    paths = []
    for name, mode, sub_balls, label in PANELS:
        snow.firn.render_mode, snow.firn.sub_balls = mode, sub_balls
        paths.append(os.path.join(folder, f"nishita_{name}.png"))
        stages.run(f"render {name}", common.render, scene, paths[-1], args.width // len(PANELS), args.samples,
                   aspect=(1, 1), label=label)
    return paths


def main():
    common.panels_sample(__file__, __doc__, render_panels, lambda parser: parser.set_defaults(width=800))


if __name__ == "__main__":
    main()
