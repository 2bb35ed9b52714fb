"""The same snow three ways, after Chrisman's "bridging two levels of detail": a teapot under 4 cm of 1 mm ice
grains (every grain traced), under a baked volumetric snow layer with the grains' optics, and multi-scale (a
shell of grains over the volumetric layer), under an overcast sky (a sun's light reaches the table through
clear grains only by refraction, which path tracing finds too rarely). Prints each panel's render time at equal
samples, and stamps it on the panel. Saves grain_scales.blend (the multi-scale panel) next to this script.

blender -b --factory-startup --python blend_samples/grain_scales.py -- [--output out/grain_scales.png]
"""

import os
import sys
import tempfile

import addon_utils
import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sample_common as common  # noqa: E402

GRAIN_RADIUS = 0.001  # m
PILE_DENSITY = 215.0  # kg/m³: Chrisman's piles pack at a volume fraction of about 0.235 (docs/grains.md)
DEPTH = 0.04  # m of snow on the open table: about 1.5 transport mean free paths of these grains
SHELL = 0.006  # m of grains over the volume (multi-scale): a few mean free paths of 1 mm grains
TABLE = 0.24  # m, side of the table


def grains_for(depth):
    """Grains that make `depth` of snow over the table at the piles' packing."""
    grain_volume = 4.0 / 3.0 * 3.14159265 * GRAIN_RADIUS ** 3
    return int(depth * TABLE * TABLE * PILE_DENSITY / 917.0 / grain_volume)


def build_scene():
    scene = common.new_scene()
    addon_utils.enable("add_mesh_extra_objects", default_set=True)
    bpy.ops.mesh.primitive_plane_add(size=TABLE)
    table = bpy.context.object
    table.name = "Table"
    table.data.materials.append(common.material("Slate", (0.12, 0.12, 0.13), roughness=0.8))
    bpy.ops.mesh.primitive_teapot_add()
    teapot = bpy.context.object
    teapot.name = "Teapot"
    teapot.scale = (0.03, 0.03, 0.03)
    bpy.ops.object.shade_smooth()
    teapot.data.materials.append(common.material("Porcelain", (0.7, 0.1, 0.08), roughness=0.3))
    common.overcast_sky(scene, 1.0)
    common.camera(location=(0.2, -0.26, 0.2), look_at=(0.0, 0.0, 0.03), lens=50)
    return scene, [table, teapot]


def add_grains(targets, count):
    bpy.ops.object.select_all(action="DESELECT")
    for obj in targets:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = targets[0]
    if bpy.ops.firn.add_grain_snow(grain_radius=GRAIN_RADIUS, grain_count=count, seed=1) != {"FINISHED"}:
        raise RuntimeError("Add Grain Snow failed")
    return bpy.context.object


def snow_layer(targets, depth):
    snow = common.add_snow(targets, depth=depth, spacing=0.01, smoothness=0.8, voxel_size=0.002,
                           density_top=PILE_DENSITY, density_bottom=PILE_DENSITY)
    snow.firn.grain_radius = GRAIN_RADIUS  # the grains' optics (KZ04 matches a pile of them: docs/grains.md)
    return snow


def all_grains(targets):
    add_grains(targets, grains_for(DEPTH))


def volumetric(targets):
    common.bake([snow_layer(targets, DEPTH)])


def multi_scale(targets):
    snow = snow_layer(targets, DEPTH - SHELL)
    add_grains([snow], grains_for(SHELL))  # Match Snow Optics: the layer keeps the grains' optics
    common.bake([snow])


PANELS = (("grains", all_grains), ("volume", volumetric), ("multi-scale", multi_scale))


def panel(name, make_snow, args, stages):
    scene, targets = stages.run(f"build scene ({name})", build_scene)
    stages.run(f"snow ({name})", make_snow, targets)
    path = os.path.join(tempfile.mkdtemp(prefix="firn_panels_"), f"grain_scales_{name}.png")
    stages.run(f"render ({name})", common.render, scene, path, args.width // 3, args.samples, aspect=(1, 1),
               label=name, stamp_time=True)
    return path


def main():
    common.panels_sample(__file__, __doc__.splitlines()[0], lambda args, stages: [
        panel(name, make_snow, args, stages) for name, make_snow in PANELS])


if __name__ == "__main__":
    main()
