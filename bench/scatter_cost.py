"""What Scatter Thin Snow costs in Cycles on the demo's scenes: the car sample (blend_samples/car_under_snow.py, its
snow baked FINAL) and one spray frame (blend_samples/skier.py, its lumps and tracked snow lit DRAFT), each rendered
with the option on (material form BAKED_SCATTER where the bake wrote firn_scatter) and off (BAKED): Cycles' wall
seconds and peak memory (MB, its status line's "Peak"), and the firn_scatter voxels. The same render settings
both ways (the bake's: volume bounces 32; 16 before tidy-63); `--samples` per pixel at `--width` × 9/16 pixels.

bench/run.sh bench/scatter_cost.py -- [--width 500] [--samples 32] [--spray-frames 6] [--scenes car,spray]
"""

import argparse
import math
import os
import sys
import tempfile
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blend_samples"))
import sample_common as common  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--width", type=int, default=500)
    parser.add_argument("--samples", type=int, default=32)
    parser.add_argument("--spray-frames", type=int, default=6, help="the skier's run, every frame lit")
    parser.add_argument("--scenes", default="car,spray")
    return parser.parse_args(argv)


def scatter_voxels(obj):
    """The firn_scatter grid's active voxels and their bounding box's (what Cycles holds dense) in the Volume's
    file (its frame's, for a sequence)."""
    from firn.common import cache
    from firn.common.core import firncore
    from firn.material import nodes as materials
    from firn.spray import files as spray_files

    volume = obj.data
    path = cache.volume_path(volume)
    if volume.is_sequence:  # the frame's file
        paths = spray_files.sequence_paths(path, volume.frame_start, volume.frame_duration)
        path = paths[bpy.context.scene.frame_current - volume.frame_start]
    if materials.SCATTER_GRID not in firncore.grid_names(path):
        return 0, 0
    statistics = firncore.grid_statistics(path, materials.SCATTER_GRID)
    return statistics["active_voxels"], math.prod(statistics["box_voxels"])


def render_both_ways(name, scene, snows, args, folder):
    from firn.bake import operators as bake
    from firn.material import nodes as materials

    bake.scatter_render_settings(scene)  # both ways alike
    voxels, box = map(sum, zip(*(scatter_voxels(snow) for snow in snows)))
    forms = {snow.name: materials.material_form(snow) for snow in snows}
    print(f"{name}: firn_scatter active voxels {voxels} (box {box}); forms {forms}; volume bounces "
          f"{scene.cycles.volume_bounces}, {args.width} px wide, {args.samples} samples", flush=True)
    for scatter in (False, True):
        for snow in snows:
            snow.firn.scatter_thin = scatter
        started = time.perf_counter()
        peak = common.render_peak_mb(scene, os.path.join(folder, f"{name}_{scatter}.png"), args.width, args.samples)
        seconds = time.perf_counter() - started
        print(f"  Scatter Thin Snow {'on ' if scatter else 'off'}: {seconds:6.1f} s, Cycles peak {peak:6.0f} MB",
              flush=True)


def car_scene(args, folder):
    import car_under_snow as car

    scene, targets = car.build_scene()
    snow = car.add_car_snow(targets)
    common.bake([snow])
    render_both_ways("car", scene, [snow], args, folder)


def spray_scene(args, folder):
    import skier
    from firn.material import nodes as materials

    frames = args.spray_frames
    scene, ground, skis = skier.build_scene(frames)
    snow = common.add_snow([ground], depth=skier.SNOW_DEPTH, spacing=0.05, voxel_size=0.02, seed=2)
    spray = skier.add_spray(snow, skis, frames)
    skier.bake_light(frames)  # every frame: Blender plays a sequence only whole
    scene.frame_set(frames)
    lit = [obj for obj in scene.objects if obj.type == "VOLUME" and obj.firn.bake_fingerprint]
    assert all(materials.material_form(obj).startswith("BAKED") for obj in lit)
    print(f"spray frame {frames} of the skier: {spray.firn.spray.summary}", flush=True)
    render_both_ways(f"spray frame {frames}", scene, lit, args, folder)


def main():
    args = parse_args()
    folder = tempfile.mkdtemp(prefix="firn_scatter_cost_")
    scenes = {"car": car_scene, "spray": spray_scene}
    for name in args.scenes.split(","):
        scenes[name](args, folder)


main()
