"""Grain snow rendered two ways, in the same run: Firn's brute-force core tracer (firncore.grain_radiance) and
Cycles rendering the Add Grain Snow object (true spheres, the ice material). Same grains, same white sky, same
Lambertian ground, seen straight down through an orthographic camera; mean radiance over the view and time at
equal samples (paths per pixel × pixels).

blender -b --factory-startup --python bench/grains_vs_cycles.py -- [--grains 20000] [--samples 64] [--pixels 48]
"""

import argparse
import os
import sys
import tempfile
import time

import addon_utils
import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "blender"))
from bake_helpers import ortho_camera, render, uniform_world  # noqa: E402

GROUND_ALBEDO = 0.5
RADIUS = 0.001  # m


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--grains", type=int, default=20000)
    parser.add_argument("--samples", type=int, default=64)
    parser.add_argument("--pixels", type=int, default=48)
    return parser.parse_args(argv)


def lambertian(rgb):
    mat = bpy.data.materials.new("Ground")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (*rgb, 1.0)
    mat.node_tree.links.new(diffuse.outputs["BSDF"], nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    return mat


def scene_with_grains(count):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("firn", default_set=True)
    bpy.ops.mesh.primitive_plane_add(size=0.1)
    ground = bpy.context.object
    ground.data.materials.append(lambertian((GROUND_ALBEDO,) * 3))
    start = time.perf_counter()
    assert bpy.ops.firn.add_grain_snow(grain_radius=RADIUS, grain_count=count, seed=1) == {"FINISHED"}
    accumulate = time.perf_counter() - start
    grains = bpy.context.object
    n = len(grains.data.vertices)
    centres = np.empty(n * 3, np.float32)
    grains.data.vertices.foreach_get("co", centres)
    radii = np.empty(n, np.float32)
    grains.data.attributes["radius"].data.foreach_get("value", radii)
    cycles = bpy.context.scene.cycles
    cycles.diffuse_bounces = 1024
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    cycles.blur_glossy = 0.0  # Filter Glossy blurs the sharp ice: exact rendering needs it off
    uniform_world((1.0, 1.0, 1.0))
    return ground, centres.reshape(-1, 3).astype(np.float64), radii.astype(np.float64), accumulate


def main():
    from firn.common.core import firncore

    args = parse_args()
    ground, centres, radii, accumulate = scene_with_grains(args.grains)
    view = 0.04  # m, the square seen, well inside the 10 cm plane
    ortho_camera((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), scale=view, distance=0.5)
    with tempfile.TemporaryDirectory() as directory:
        start = time.perf_counter()
        image = render(directory, size=(args.pixels, args.pixels), samples=args.samples)
        cycles_seconds = time.perf_counter() - start
    cycles_mean = image.reshape(-1, 3).mean(axis=0)

    paths = args.pixels * args.pixels
    rng = np.random.default_rng(2)
    origins = np.column_stack([rng.uniform(-view / 2, view / 2, (paths, 2)), np.full(paths, 0.5)])
    directions = np.tile([0.0, 0.0, -1.0], (paths, 1))
    vertices = np.array([[-0.05, -0.05, 0], [0.05, -0.05, 0], [0.05, 0.05, 0], [-0.05, 0.05, 0]], np.float64)
    triangles = np.array([[0, 1, 2], [0, 2, 3]], np.uint32)
    absorption = firncore.ice_absorption_rgb(RADIUS)
    start = time.perf_counter()
    mean, error = firncore.grain_radiance(centres, radii, origins, directions, vertices=vertices, triangles=triangles,
                                          surface_albedo=(GROUND_ALBEDO,) * 3, eta=1.31, ice_absorption=absorption,
                                          sky=(1.0, 1.0, 1.0), samples=args.samples, seed=3)
    core_seconds = time.perf_counter() - start
    core_mean = mean.mean(axis=0)
    # The core's standard error of the view's mean: its rays' spread over the square (the view's variation) is
    # part of the estimate, as Cycles' pixel grid averages it.
    core_error = mean.std(axis=0) / np.sqrt(paths)

    print(f"{len(radii):,} grains of {RADIUS * 1e3:g} mm on a Lambertian ground of albedo {GROUND_ALBEDO} "
          f"(accumulated in {accumulate:.2f} s), white sky, seen straight down; {args.pixels}² pixels × "
          f"{args.samples} paths")
    print("| renderer | mean radiance R, G, B | time (s) |")
    print("|---|---|---|")
    print(f"| Cycles (spheres, ice material) | {cycles_mean[0]:.4f}, {cycles_mean[1]:.4f}, {cycles_mean[2]:.4f} "
          f"| {cycles_seconds:.1f} |")
    print(f"| Firn core brute force | {core_mean[0]:.4f}, {core_mean[1]:.4f}, {core_mean[2]:.4f} "
          f"(± {core_error.max():.4f}) | {core_seconds:.1f} |")
    rel = cycles_mean / core_mean - 1.0
    print(f"Cycles / core − 1: {rel[0]:+.3f}, {rel[1]:+.3f}, {rel[2]:+.3f} (goal: within 5 %)")


main()
