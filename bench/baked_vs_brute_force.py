"""Baked snow against Cycles brute force on the same volume, in the same run: time and error.

A semi-infinite slab of real snow (sigma_t = 3000 /m, omega = 0.9999, g = 0.87, 1 cm voxels, 30 cm deep) under a
uniform white sky, seen straight down: the exact radiance is the plane albedo A(1) = 0.92182 (snow-optics.md,
adding-doubling), so the error of each render is known without a reference render.

blender -b --factory-startup --python bench/baked_vs_brute_force.py -- [--bounces 256] [--step-rate 0.1]
"""

import argparse
import os
import sys
import tempfile
import time

import addon_utils
import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "blender"))
from bake_helpers import mean_pixel, ortho_camera, render, uniform_world, volume_object, write_volume  # noqa: E402

A_1 = 0.92182  # exact, g = 0.87, omega = 0.9999
K, RHO, G, OMEGA = 10.0, 300.0, 0.87, 0.9999


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--bounces", type=int, default=256)
    parser.add_argument("--step-rate", type=float, default=0.1)
    parser.add_argument("--samples", type=int, default=64)
    parser.add_argument("--pixels", type=int, default=8)
    return parser.parse_args(argv)


def scene(directory):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("firn", default_set=True)
    uniform_world((1.0, 1.0, 1.0))
    path = write_volume(os.path.join(directory, "Slab.vdb"), 0.01, (-50, -50, -29), (49, 49, 0), RHO)
    slab = volume_object(path, "Slab")
    slab.firn.optics_mode = "CUSTOM"
    slab.firn.extinction_per_density = K
    slab.firn.albedo = (OMEGA, OMEGA, OMEGA)
    slab.firn.anisotropy = G
    slab.select_set(True)
    bpy.context.view_layer.objects.active = slab
    ortho_camera((0, 0, 0), (0.0, 0.0, 1.0), scale=0.04)
    return slab


def timed_render(directory, args, name):
    start = time.perf_counter()
    value = float(mean_pixel(render(directory, size=(args.pixels, args.pixels), samples=args.samples,
                                    name=name)).mean())
    return value, time.perf_counter() - start


def main():
    args = parse_args()
    directory = tempfile.mkdtemp(prefix="firn_bench_")
    slab = scene(directory)
    from firn.material import nodes as materials

    materials.ensure_snow_material(slab)  # the unbaked material: Cycles traces the scattering itself
    cycles = bpy.context.scene.cycles
    cycles.volume_bounces = cycles.max_bounces = args.bounces
    cycles.transparent_max_bounces = args.bounces
    cycles.volume_step_rate = args.step_rate
    brute, brute_seconds = timed_render(directory, args, "brute")

    cycles.volume_bounces, cycles.volume_step_rate = 0, 1.0  # Cycles' defaults: the baked material needs none
    start = time.perf_counter()
    assert bpy.ops.firn.bake_scattering(quality="FINAL") == {"FINISHED"}
    bake_seconds = time.perf_counter() - start
    baked, baked_seconds = timed_render(directory, args, "baked")

    def error(value):
        return f"{100 * (value / A_1 - 1):+.1f} %"

    print(f"Slab, sigma_t 3000 /m, omega {OMEGA}, g {G}, {args.pixels}x{args.pixels} px, {args.samples} samples; "
          f"exact A(1) = {A_1}")
    print()
    print("| render | radiance | error | bake (s) | render (s) | render time / baked |")
    print("|---|---|---|---|---|---|")
    print(f"| Cycles brute force, {args.bounces} bounces, step rate {args.step_rate} | {brute:.4f} | {error(brute)} "
          f"| — | {brute_seconds:.1f} | {brute_seconds / baked_seconds:.0f}x |")
    print(f"| Firn baked (FINAL), Cycles defaults | {baked:.4f} | {error(baked)} | {bake_seconds:.1f} "
          f"| {baked_seconds:.1f} | 1x |")


main()
