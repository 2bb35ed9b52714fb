"""A skier's skis throwing snow down a slope, after Nishita et al. (1997), Fig. 7: two ski soles (rectangles) on an
animated path with two turns down a 20° snowy slope, under a simple body whose shadow moves with it; Add Snow Spray
simulates the thrown snow and the tracks, Bake Sequence bakes the light of the lumps and the tracked snow at every
frame (lit together: the spray's shadow on the snow, the snow's light under the lumps), and a short
animation is rendered at low resolution to PNGs (out/skier/####.png). Saves skier.blend next to this script.

blender -b --factory-startup --python blend_samples/skier.py -- [--output out/skier/] [--width 160] [--samples 8]
                                                                [--frames 36]
"""

import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sample_common as common  # noqa: E402

SLOPE_DEG = 20.0
SLOPE_SIZE = (7.5, 2.5)  # m, down the slope × across
SNOW_DEPTH = 0.15  # m
SOLE_HEIGHT = 0.07  # m above the ground: the skis sink 8 cm into the powder
SKI_SIZE = (1.6, 0.09)  # m
STANCE = 0.13  # m between the skis' centres and the skier's path
RUN = (-2.6, 2.6)  # m along the slope, first to last frame
TURN_WIDTH = 0.35  # m either side of the fall line
TURNS = 1.0  # full turns (left and right) over the run


def path(t):
    """(x, y, heading rad) of the skier at t in [0, 1], in the slope's plane."""
    x = RUN[0] + (RUN[1] - RUN[0]) * t
    y = TURN_WIDTH * math.sin(2 * math.pi * TURNS * t)
    dy_dx = TURN_WIDTH * 2 * math.pi * TURNS * math.cos(2 * math.pi * TURNS * t) / (RUN[1] - RUN[0])
    return x, y, math.atan(dy_dx)


def scaled_plane(size):
    """A rectangle of `size` (m) (the add operator's `scale` does not scale the object)."""
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    plane = bpy.context.object
    plane.scale = (*size, 1.0)
    return plane


def build_scene(frames):
    scene = common.new_scene()
    scene.frame_start, scene.frame_end = 1, frames
    common.nishita_sky(scene, sun_elevation_deg=30.0, sun_rotation_deg=-40.0, strength=0.3)
    common.sun(30.0, -40.0, irradiance=3.0)
    # The slope: everything on it is a child of a frame tilted down the x axis.
    bpy.ops.object.empty_add(rotation=(0.0, math.radians(SLOPE_DEG), 0.0))
    slope_frame = bpy.context.object
    slope_frame.name = "Slope Frame"
    ground = scaled_plane(SLOPE_SIZE)
    ground.name = "Slope"
    ground.data.materials.append(common.material("Ground", (0.3, 0.3, 0.3), roughness=0.9))
    ground.parent = slope_frame
    bpy.ops.object.empty_add()
    skier = bpy.context.object
    skier.name = "Skier"
    skier.parent = slope_frame
    for frame in range(1, frames + 1, 3):  # keys every third frame, Bézier in between
        x, y, heading = path((frame - 1) / (frames - 1))
        skier.location = (x, y, SOLE_HEIGHT)
        skier.rotation_euler = (0.0, 0.0, heading)
        skier.keyframe_insert("location", frame=frame)
        skier.keyframe_insert("rotation_euler", frame=frame)
    skis = []
    for side in (-1, 1):
        ski = scaled_plane(SKI_SIZE)
        ski.name = f"Ski {'Left' if side > 0 else 'Right'}"
        ski.parent = skier
        ski.location = (0.0, side * STANCE, 0.0)
        ski.hide_render = True  # the soles are the emitters, inside the groove they cut
        skis.append(ski)
    bpy.ops.mesh.primitive_cylinder_add(radius=0.17, depth=1.1, location=(0.0, 0.0, 0.75))
    body = bpy.context.object
    body.name = "Body"  # casts the moving shadow the per-frame bake follows (lumps fly through it: spray.md)
    body.parent = skier
    body.data.materials.append(common.material("Jacket", (0.6, 0.05, 0.04), roughness=0.7))
    common.camera((5.0, -4.5, 1.2), (0.8, 0.0, -0.3), lens=35.0)
    return scene, ground, skis


def add_spray(snow, skis, frames):
    bpy.ops.object.select_all(action="DESELECT")
    for ski in skis:
        ski.select_set(True)
    snow.select_set(True)
    bpy.context.view_layer.objects.active = snow
    if bpy.ops.firn.add_snow_spray(frame_start=1, frame_end=frames, seed=1, lump_radius=0.012,
                                   voxel_size=0.01) != {"FINISHED"}:
        raise RuntimeError("Add Snow Spray failed")
    return bpy.context.object


def bake_light(frames):
    """The light of the lumps and the tracked snow at every frame (Bake Sequence; the simulation is on disk)."""
    if bpy.ops.firn.bake_sequence(frame_start=1, frame_end=frames, quality="DRAFT") != {"FINISHED"}:
        raise RuntimeError("Bake Sequence failed")


def render_animation(scene, output, width, samples):
    """The frames as PNGs: Cycles, single scattering (quick), at `width` pixels."""
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise
    scene.render.resolution_x, scene.render.resolution_y = width, width * 9 // 16
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = os.path.join(os.path.abspath(output), "")
    os.makedirs(scene.render.filepath, exist_ok=True)
    bpy.ops.render.render(animation=True)


def add_arguments(parser):
    parser.add_argument("--frames", type=int, default=36, help="frames of the run (24 per second)")


def main():
    args = common.parse_args(__doc__.splitlines()[0], "out/skier/", add_arguments)
    args.width = 160 if args.width == 500 else args.width  # an animation: small frames unless asked
    args.samples = 8 if args.samples == 32 else args.samples
    stages = common.Stages()
    scene, ground, skis = stages.run("build scene", build_scene, args.frames)
    snow = stages.run("add snow layer", common.add_snow, [ground], depth=SNOW_DEPTH, spacing=0.05,
                      voxel_size=0.02, seed=2)
    scene.cycles.volume_bounces = 16  # unbaked snow is path traced: its light is many bounces deep
    spray = stages.run("add snow spray", add_spray, snow, skis, args.frames)
    print(f"firn sample: {spray.firn.spray.summary}")
    stages.run("bake light per frame", bake_light, args.frames)
    stages.run("render animation", render_animation, scene, args.output, args.width, args.samples)
    if not args.no_save:
        stages.run("save .blend", common.save_next_to, __file__, args.blend)
    print(f"firn sample: total {stages.total():.1f} s")


if __name__ == "__main__":
    main()
