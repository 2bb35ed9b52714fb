"""A car's headlights sweep a snowy street at night: the night street sample (a street lamp and a lit window on
snow) with a car driving past after the snowfall (it carries no snow), its two headlights (Spots) lighting the snow
ahead and its body shading it. Bake Light Sequence bakes the snow's light at every frame; the frames render to
out/headlights/####.png and three of them (first, middle, last) side by side to the output. Saves headlights.blend
next to this script.

blender -b --factory-startup --python blend_samples/headlights.py -- [--output out/headlights.png] [--width 320]
                                                                      [--samples 16] [--frames 8] [--quality DRAFT]
"""

import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import night_street  # noqa: E402
import sample_common as common  # noqa: E402

DRIVE = (-5.0, 1.2)  # m along x: the car's centre at the first and the last frame
LANE = 0.45  # m along y: the car's centre line, between the street lamp and the house
BODY = (2.6, 1.3, 0.8)  # m: length, width, height of its body
CLEARANCE = 0.35  # m between the street and the body: above the snow (8 cm)
XENON = (1.0, 0.95, 0.85)  # the headlights' colour


def add_arguments(parser):
    parser.add_argument("--frames", type=int, default=8, help="frames of the drive")
    parser.add_argument("--quality", default="DRAFT", choices=("DRAFT", "FINAL"))
    parser.set_defaults(width=320, samples=16)  # a frame each: small ones


def drive(obj, offset_x, frames):
    """Keyframes obj along x from DRIVE[0] to DRIVE[1] (plus its offset from the car's centre) over the frames."""
    for frame, x in ((1, DRIVE[0]), (frames, DRIVE[1])):
        obj.location.x = x + offset_x
        obj.keyframe_insert("location", index=0, frame=frame)
    for fcurve in obj.animation_data.action.fcurves:
        for point in fcurve.keyframe_points:
            point.interpolation = "LINEAR"


def headlight(side, frames):
    """A Spot at the front of the car, shining along +x and 8° down, with a glowing lens that only the camera sees."""
    front, height = BODY[0] / 2, CLEARANCE + 0.25
    y = LANE + side * 0.45
    lens = night_street.box(f"Headlight {side:+d}", (0.0, y, height), (0.04, 0.22, 0.1), XENON)
    lens.data.materials[0] = night_street.glowing(f"Headlight {side:+d}", XENON, 30.0)
    lens.visible_shadow = False  # glass: the spot shines through it
    drive(lens, front + 0.02, frames)
    # A Spot shines along its local -Z: turned -82° about y it shines along +x, 8° down.
    bpy.ops.object.light_add(type="SPOT", location=(0.0, y, height), rotation=(0.0, math.radians(-82.0), 0.0))
    spot = bpy.context.object
    spot.name = f"Headlight Spot {side:+d}"
    spot.data.energy, spot.data.color = 350.0, XENON
    spot.data.spot_size, spot.data.spot_blend = math.radians(55.0), 0.3
    spot.data.shadow_soft_size = 0.04
    drive(spot, front + 0.05, frames)


def car(frames):
    body = night_street.box("Car", (0.0, LANE, CLEARANCE + BODY[2] / 2), BODY, (0.05, 0.07, 0.12), roughness=0.3)
    drive(body, 0.0, frames)
    for side in (-1, 1):
        headlight(side, frames)


def bake_light_sequence(snow, frames, quality):
    bpy.ops.object.select_all(action="DESELECT")
    snow.select_set(True)
    bpy.context.view_layer.objects.active = snow
    if bpy.ops.firn.bake_light_sequence(frame_start=1, frame_end=frames, quality=quality) != {"FINISHED"}:
        raise RuntimeError("Bake Light Sequence failed")
    return bpy.context.object


def render_frames(scene, args):
    paths = []
    for frame in range(1, args.frames + 1):
        scene.frame_set(frame)
        paths.append(os.path.join(os.path.splitext(args.output)[0], f"{frame:04d}.png"))
        common.render(scene, paths[-1], args.width, args.samples)
    return paths


def main():
    args = common.parse_args(__doc__, "out/headlights.png", add_arguments)
    stages = common.Stages()
    scene, targets = stages.run("build scene", night_street.build_scene)
    scene.frame_start, scene.frame_end = 1, args.frames
    snow = stages.run("add snow layer", common.add_snow, targets, depth=0.08, spacing=0.04, voxel_size=0.02)
    stages.run("car", car, args.frames)
    lit = stages.run("bake light sequence", bake_light_sequence, snow, args.frames, args.quality)
    print(f"firn sample: bake {lit.firn.bake_summary}")
    paths = stages.run("render (Cycles)", render_frames, scene, args)
    common.side_by_side([paths[0], paths[len(paths) // 2], paths[-1]], args.output)
    if not args.no_save:
        stages.run("save .blend", common.save_next_to, __file__, args.blend)
    print(f"firn sample: total {stages.total():.2f} s -> {args.output}")


if __name__ == "__main__":
    main()
