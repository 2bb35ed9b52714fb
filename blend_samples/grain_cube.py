"""Chrisman's cube: about 120³ ice grains of 1 mm poured into a box whose walls are then taken away, rendered by
Cycles at 1, 10 and 100 samples per pixel under an overcast sky. Saves grain_cube.blend next to this script.

blender -b --factory-startup --python blend_samples/grain_cube.py -- [--output out/grain_cube.png] [--grains N]
"""

import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sample_common as common  # noqa: E402

GRAIN_RADIUS = 0.001  # m
PACKING = 0.235  # volume fraction of Chrisman's piles (docs/grains.md)
SAMPLES = (1, 10, 100)


def open_box(side):
    """A box of `side` (m) without its top, standing on z = 0."""
    bpy.ops.mesh.primitive_cube_add(size=side, location=(0.0, 0.0, side / 2))
    box = bpy.context.object
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="DESELECT")
    bpy.ops.object.mode_set(mode="OBJECT")
    for face in box.data.polygons:
        face.select = face.normal.z > 0.5
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.delete(type="FACE")
    bpy.ops.object.mode_set(mode="OBJECT")
    return box


def build_scene(count):
    scene = common.new_scene()
    common.overcast_sky(scene, 1.0)
    side = (count * 4.0 / 3.0 * math.pi * GRAIN_RADIUS ** 3 / PACKING) ** (1.0 / 3.0)
    bpy.ops.mesh.primitive_plane_add(size=20 * side, location=(0.0, 0.0, -0.001))
    bpy.context.object.data.materials.append(common.material("Floor", (0.3, 0.3, 0.3), roughness=0.9))
    box = open_box(side)
    common.camera(location=(1.9 * side, -2.4 * side, 1.9 * side), look_at=(0.0, 0.0, 0.4 * side), lens=50)
    return scene, box


def pour(box, count):
    bpy.ops.object.select_all(action="DESELECT")
    box.select_set(True)
    bpy.context.view_layer.objects.active = box
    if bpy.ops.firn.add_grain_snow(grain_radius=GRAIN_RADIUS, grain_count=count, seed=1) != {"FINISHED"}:
        raise RuntimeError("Add Grain Snow failed")
    box.hide_render = True  # the walls go; the grains stay where they settled (no avalanches in this model)
    return bpy.context.object


def render_panels(args, stages):
    import tempfile

    count = args.grains
    scene, box = stages.run("build scene", build_scene, count)
    grains = stages.run("pour grains", pour, box, count)
    print(f"firn sample: {len(grains.data.vertices):,} grains of {GRAIN_RADIUS * 1e3:g} mm")
    folder = tempfile.mkdtemp(prefix="firn_panels_")
    paths = []
    for samples in SAMPLES:
        path = os.path.join(folder, f"grain_cube_{samples}.png")
        stages.run(f"render {samples} spp", common.render, scene, path, args.width // 3, samples, aspect=(1, 1),
                   label=f"{samples} sample{'s' if samples > 1 else ''}", stamp_time=True)
        paths.append(path)
    return paths


def main():
    common.panels_sample(__file__, __doc__.splitlines()[0], render_panels, lambda parser: parser.add_argument(
        "--grains", type=int, default=120 ** 3, help="grains to pour (Chrisman's cube: 120³)"))


if __name__ == "__main__":
    main()
