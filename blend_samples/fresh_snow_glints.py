"""Fresh snow sparkling under a low sun: a close-up of a snow layer with glints (ice facets that mirror the sun)
and sub-balls, baked, seen towards the sun. The glints move with the camera: render two frames from slightly
different places to see them change. Saves fresh_snow_glints.blend next to this script.

blender -b --factory-startup --python blend_samples/fresh_snow_glints.py -- [--output out/glints.png]
"""

import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sample_common as common  # noqa: E402

SUN_ELEVATION = 25.0  # degrees: a low winter sun, in front of the camera


def build_scene():
    scene = common.new_scene()
    bpy.ops.mesh.primitive_plane_add(size=3.0)
    ground = bpy.context.object
    ground.data.materials.append(common.material("Soil", (0.2, 0.15, 0.1), roughness=0.9))
    common.nishita_sky(scene, sun_elevation_deg=SUN_ELEVATION, sun_rotation_deg=0.0)
    common.sun(elevation_deg=SUN_ELEVATION, rotation_deg=0.0, irradiance=3.0)  # towards +x
    common.camera(location=(-0.6, 0.0, 0.6), look_at=(0.3, 0.0, 0.02), lens=40)
    return scene, [ground]


def main():
    # Glints are rare and tiny (facets of 0.05 mm; the real sun is 0.53° wide): a pixel shows one when one of its
    # samples lands on a mirroring facet, so this sample takes more samples than the others.
    args = common.parse_args(__doc__, "out/fresh_snow_glints.png",
                             lambda parser: parser.set_defaults(width=640, samples=64))
    stages = common.Stages()
    scene, targets = stages.run("build scene", build_scene)
    snow = stages.run("add snow layer", common.add_snow, targets, depth=0.05, spacing=0.03)
    snow.firn.glints = True
    # Facets of 0.5 mm (a pixel here is about 1.5 mm), nearly as dense as they fit (10^6 per m²), slightly rough
    # (a lobe about the sun's size): glints that a few dozen samples per pixel find. With the default facets
    # (0.05 mm, perfect mirrors) about one sample in 10^6 lands on a glint.
    snow.firn.glint_size, snow.firn.glint_density, snow.firn.glint_roughness = 0.5e-3, 8e5, 0.05
    snow.firn.sub_balls = True
    stages.run("bake scattering", common.bake, [snow])
    stages.run("render (Cycles)", common.render, scene, args.output, args.width, args.samples,
               label=f"glints and sub-balls, sun {SUN_ELEVATION:.0f}° high")
    if not args.no_save:
        stages.run("save .blend", common.save_next_to, __file__, args.blend)
    print(f"firn sample: total {stages.total():.2f} s -> {args.output}")


if __name__ == "__main__":
    main()
