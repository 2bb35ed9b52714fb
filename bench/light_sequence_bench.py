"""What Bake Light Sequence adds to the bakes it runs (docs/user-guide.md "Light that moves"): a snow layer under a
sun that sets over N frames, lit frame by frame, against Bake Scattering of the same layer at each of those frames,
in one run (the same machine and load). Printed: each way's wall seconds, their ratio (the sequence's reading of the
scene at every frame, its world requests, markers and Lit Volume, over N bakes done one by one), a second Bake Light
Sequence that finds every frame baked (its cost: reading the scene and checking the markers), and the scene's
reading alone on the main thread per frame (with the Lit Volume there: its files are not loaded while the scene
steps through the frames).

    blender -b --factory-startup --python bench/light_sequence_bench.py -- [--frames 6] [--voxel 0.01]
        [--quality DRAFT]
(with the build's add-on: BLENDER_USER_SCRIPTS=build/blender_scripts)
"""

import argparse
import os
import sys
import time

import addon_utils
import bpy


def parse_args():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=6)
    parser.add_argument("--voxel", type=float, default=0.01, help="m")
    parser.add_argument("--quality", default="DRAFT", choices=("DRAFT", "FINAL"))
    return parser.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])


def scene(frames, voxel):
    """A 1 m × 0.6 m plane with 5 cm of snow, and a sun from 80° to 20° elevation over the frames; the layer."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("firn", default_set=True)
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    bpy.context.object.scale = (1.0, 0.6, 1.0)
    if bpy.ops.firn.add_snow_layer(depth=0.05, spacing=0.04, voxel_size=voxel, seed=1) != {"FINISHED"}:
        raise RuntimeError("Add Snow Layer failed")
    snow = bpy.context.object
    bpy.ops.object.light_add(type="SUN")
    sun = bpy.context.object
    sun.data.energy = 3.0
    for frame, elevation in ((1, 1.4), (frames, 0.35)):
        sun.rotation_euler = (1.5708 - elevation, 0.0, 0.0)
        sun.keyframe_insert("rotation_euler", frame=frame)
    bpy.context.scene.frame_start, bpy.context.scene.frame_end = 1, frames
    return snow


def timed(fn):
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def main():
    args = parse_args()
    snow = scene(args.frames, args.voxel)
    snow_file = bpy.path.abspath(snow.data.filepath)
    voxels = __import__("firn.common.core", fromlist=["firncore"]).firncore.grid_statistics(snow_file, "density")

    def sequence():
        bpy.context.view_layer.objects.active = snow
        if bpy.ops.firn.bake_light_sequence(quality=args.quality) != {"FINISHED"}:
            raise RuntimeError("Bake Light Sequence failed")

    def one_by_one():  # after the sequence: Bake Scattering rewrites the layer's file, which the sequence reads
        bpy.ops.object.select_all(action="DESELECT")  # the Lit Volume: Bake Scattering bakes the selection
        for frame in range(1, args.frames + 1):
            bpy.context.scene.frame_set(frame)
            bpy.context.view_layer.objects.active = snow
            if bpy.ops.firn.bake_scattering(quality=args.quality) != {"FINISHED"}:
                raise RuntimeError("Bake Scattering failed")

    lit = timed(sequence)
    kept = timed(sequence)
    separate = timed(one_by_one)
    from firn.spray import light

    folder = os.path.dirname(bpy.path.abspath(bpy.data.objects[f"{snow.name} Lit"].data.filepath))
    reading = timed(lambda: light.gather_layer(bpy.context, snow, snow, range(1, args.frames + 1), folder,
                                               args.quality, 0))
    load = os.getloadavg()[0]
    print(f"light_sequence: {voxels['active_voxels']:,} active voxels, {args.frames} frames, {args.quality}, "
          f"load {load:.1f}")
    print(f"  Bake Scattering frame by frame   {separate:8.2f} s")
    print(f"  Bake Light Sequence              {lit:8.2f} s   ratio {lit / separate:.3f}")
    print(f"  again, every frame kept          {kept:8.2f} s   ratio {kept / separate:.4f}")
    print(f"  reading the scene (main thread)  {reading / args.frames * 1e3:8.2f} ms a frame")


main()
