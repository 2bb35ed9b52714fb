"""A wheel rolling through fresh snow leaves a rut: a tyre (a rotating cylinder) drives 3 m across a snowy plane;
its contact patch (a rectangle under the hub that moves with it but does not turn) is the emitter of Add Snow Spray,
which cuts the rut, compacts the snow under it and throws a little snow; Bake Sequence bakes the light of the
tracked snow at every frame (the tyre's shadow moves with it). Renders the last frame (the rut behind the wheel)
to a PNG and, with --animation, every frame. Saves wheel_rut.blend next to this script.

blender -b --factory-startup --python blend_samples/wheel_rut.py -- [--output out/wheel_rut.png] [--width 500]
                                                                     [--samples 32] [--frames 24] [--animation]
"""

import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sample_common as common  # noqa: E402

SNOW_DEPTH = 0.12  # m of fresh snow
TYRE_RADIUS, TYRE_WIDTH = 0.32, 0.2  # m
SINK = 0.08  # m the tyre sinks below the snow's top: the rut's depth
PATCH_LENGTH = 0.25  # m along the way: the tyre's contact with the snow
DRIVE = (-1.8, 1.2)  # m along x, first to last frame
FPS = 24


def build_scene(frames):
    scene = common.new_scene()
    scene.frame_start, scene.frame_end = 1, frames
    scene.render.fps = FPS
    # A low sun from across the drive (+y): the rut's walls cast shadows into it.
    common.nishita_sky(scene, sun_elevation_deg=18.0, sun_rotation_deg=20.0, strength=0.3)
    common.sun(18.0, 20.0, irradiance=3.0)
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    ground = bpy.context.object
    ground.name = "Ground"
    ground.scale = (5.0, 2.0, 1.0)
    ground.data.materials.append(common.material("Ground", (0.25, 0.22, 0.2), roughness=0.9))
    hub_height = SNOW_DEPTH - SINK + TYRE_RADIUS
    bpy.ops.object.empty_add(location=(DRIVE[0], 0.0, hub_height))
    hub = bpy.context.object
    hub.name = "Hub"
    for frame, x in ((1, DRIVE[0]), (frames, DRIVE[1])):
        hub.location.x = x
        hub.keyframe_insert("location", frame=frame)
    for point in hub.animation_data.action.fcurves[0].keyframe_points:
        point.interpolation = "LINEAR"  # a steady 1 m/s or so
    bpy.ops.mesh.primitive_cylinder_add(radius=TYRE_RADIUS, depth=TYRE_WIDTH, rotation=(math.pi / 2, 0.0, 0.0))
    tyre = bpy.context.object
    tyre.name = "Tyre"
    tyre.parent = hub
    tyre.location = (0.0, 0.0, 0.0)
    tyre.data.materials.append(common.material("Rubber", (0.02, 0.02, 0.02), roughness=0.6))
    distance = DRIVE[1] - DRIVE[0]
    tyre.rotation_mode = "XYZ"
    for frame, angle in ((1, 0.0), (frames, distance / TYRE_RADIUS)):  # rolling without slipping
        tyre.rotation_euler = (math.pi / 2, angle, 0.0)
        tyre.keyframe_insert("rotation_euler", frame=frame)
    for fcurve in tyre.animation_data.action.fcurves:
        for point in fcurve.keyframe_points:
            point.interpolation = "LINEAR"
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    patch = bpy.context.object
    patch.name = "Contact Patch"
    patch.parent = hub
    patch.location = (0.0, 0.0, -TYRE_RADIUS)
    patch.scale = (PATCH_LENGTH, TYRE_WIDTH, 1.0)
    patch.hide_render = True  # the emitter: inside the rut it cuts
    common.camera((2.7, -1.1, 0.8), (-0.6, 0.0, 0.0), lens=35.0)  # looking back along the rut
    return scene, ground, patch


def add_rut(snow, patch, frames):
    bpy.ops.object.select_all(action="DESELECT")
    patch.select_set(True)
    snow.select_set(True)
    bpy.context.view_layer.objects.active = snow
    # A tyre throws little: a low rate and throw speed; the rut and its compacted floor are the point.
    if bpy.ops.firn.add_snow_spray(frame_start=1, frame_end=frames, seed=3, rate=2000.0, throw_speed=0.3,
                                   track_thickness=0.03, compaction_depth=0.04) != {"FINISHED"}:
        raise RuntimeError("Add Snow Spray failed")
    if bpy.ops.firn.bake_sequence(frame_start=1, frame_end=frames, quality="DRAFT") != {"FINISHED"}:
        raise RuntimeError("Bake Sequence failed")
    return bpy.context.object


def render(scene, args):
    """The last frame (the rut behind the wheel) to --output; with --animation every frame beside it first."""
    if args.animation:
        common.render(scene, args.output, args.width, args.samples)  # the settings; then the frames
        scene.render.filepath = os.path.join(os.path.splitext(os.path.abspath(args.output))[0], "")
        bpy.ops.render.render(animation=True)
    scene.frame_set(scene.frame_end)
    common.render(scene, args.output, args.width, args.samples)


def add_arguments(parser):
    parser.add_argument("--frames", type=int, default=24, help="frames of the drive (24 per second)")
    parser.add_argument("--animation", action="store_true", help="also render every frame")


def main():
    args = common.parse_args(__doc__.splitlines()[0], "out/wheel_rut.png", add_arguments)
    stages = common.Stages()
    scene, ground, patch = stages.run("build scene", build_scene, args.frames)
    snow = stages.run("add snow layer", common.add_snow, [ground], depth=SNOW_DEPTH, spacing=0.04,
                      voxel_size=0.01, seed=4)
    scene.cycles.volume_bounces = 16  # the thrown snow is path traced
    spray = stages.run("rut and light", add_rut, snow, patch, args.frames)
    print(f"firn sample: {spray.firn.spray.summary}")
    stages.run("render", render, scene, args)
    if not args.no_save:
        stages.run("save .blend", common.save_next_to, __file__, args.blend)
    print(f"firn sample: total {stages.total():.1f} s")


main()
