"""The core's Monte Carlo reference against Cycles brute force on one case of bench/bake_suite.py (docs/bake.md).

The suite judges the bake against `firncore.monte_carlo_radiance`; this checks that oracle against Cycles itself:
the same density (Firn's voxel convention), the add-on's unbaked material with the case's custom optics, a Sun
lamp and a uniform world, Cycles unclamped (sample_clamp_direct = sample_clamp_indirect = 0) with many volume
bounces and a small step rate. Each pixel's Monte Carlo value averages rays spread over the pixel, as Cycles' box
filter does. Prints per view the mean of both over the pixels through optical depth >= 1, and the mean and
worst per-pixel relative difference against both noises.

    bench/run.sh bench/monte_carlo_vs_cycles.py -- [--case ball_grey] [--samples 1024] [--bounces 1024] [--step-rate 0.05] [--mc-samples N]
"""

import argparse
import math
import os
import sys
import tempfile
import time

import addon_utils
import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "tests", "blender"))
from bake_helpers import ortho_camera, render, uniform_world, volume_object  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_grey")
    parser.add_argument("--samples", type=int, default=1024)
    parser.add_argument("--bounces", type=int, default=1024)
    parser.add_argument("--step-rate", type=float, default=0.05)
    parser.add_argument("--views", default="0,180", help="azimuths (deg) of horizontal views")
    parser.add_argument("--mc-samples", type=int, default=0, help="Monte Carlo paths per pixel (0: the case's)")
    return parser.parse_args(argv)


def write_density(path, density, voxel):
    """Voxel by voxel (Cycles draws tiles as nothing), voxel i centred at i * voxel in Cycles."""
    import pyopenvdb

    grid = pyopenvdb.FloatGrid()
    grid.name = "density"
    transform = pyopenvdb.createLinearTransform(voxelSize=voxel)
    transform.translate((-voxel / 2,) * 3)
    grid.transform = transform
    accessor = grid.getAccessor()
    for ijk in np.argwhere(density > 0):
        accessor.setValueOn(tuple(int(i) for i in ijk), float(density[tuple(ijk)]))
    pyopenvdb.write(path, grids=[grid])


def main():
    args = parse_args()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("firn", default_set=True)
    from firn.common.core import firncore

    sys.modules.setdefault("firncore", firncore)  # bake_suite imports it by name, as outside Blender
    import bake_suite
    from firn.material import nodes as materials

    case = bake_suite.case(args.case)
    case.views = [(float(a), 0.0) for a in args.views.split(",")]
    case.samples = args.mc_samples or case.samples
    directory = tempfile.mkdtemp(prefix="firn_mc_cycles_")
    path = os.path.join(directory, "Snow.vdb")
    write_density(path, case.density, case.voxel)
    core_path = os.path.join(directory, "core.vdb")
    bake_suite.write_density(core_path, case.density, case.voxel)

    uniform_world((case.sky,) * 3)
    sun_data = bpy.data.lights.new("Sun", "SUN")
    sun_data.energy = case.sun  # W/m^2 on a plane facing it
    sun_data.angle = 0.0093
    sun = bpy.data.objects.new("Sun", sun_data)
    towards = np.array(case.suns()[0].direction)
    from mathutils import Vector

    sun.rotation_euler = (-Vector(towards)).to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.collection.objects.link(sun)

    snow = volume_object(path, "Snow")
    snow.firn.optics_mode = "CUSTOM"
    snow.firn.extinction_per_density = case.sigma_t / case.rho
    snow.firn.albedo = case.omega
    snow.firn.anisotropy = case.g
    materials.ensure_snow_material(snow)
    cycles = bpy.context.scene.cycles
    cycles.volume_bounces = cycles.max_bounces = cycles.transparent_max_bounces = args.bounces
    cycles.volume_step_rate = args.step_rate
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0

    origins, directions, tau = bake_suite.views(case)
    n = case.pixels
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    nonzero = np.argwhere(case.density > 0)
    radius = 0.55 * np.max((nonzero.max(0) - nonzero.min(0) + 1) * case.voxel)
    pixel = 2.0 * radius / n
    rng = np.random.default_rng(7)
    jitter = 16  # rays per pixel for the Monte Carlo
    print(f"{args.case}: {case.what}; Cycles {args.samples} samples, {args.bounces} bounces, step rate "
          f"{args.step_rate}, unclamped; core Monte Carlo {case.samples} paths per pixel over {jitter} rays")
    for v, (azimuth, elevation) in enumerate(case.views):
        a = math.radians(azimuth)
        back = np.array([math.cos(a), math.sin(a), 0.0])
        ortho_camera(tuple(map(float, centre)), tuple(map(float, back)), scale=float(2.0 * radius), distance=float(3.0 * radius))
        start = time.perf_counter()
        image = render(directory, size=(n, n), samples=args.samples, name=f"view{v}")
        cycles_seconds = time.perf_counter() - start
        up = np.array([0.0, 0.0, 1.0])
        right = np.cross(up, back)
        rays_o, rays_d = [], []
        for k in range(n * n):
            o = origins[v * n * n + k]
            for _ in range(jitter):
                rays_o.append(o + (rng.random() - 0.5) * pixel * right + (rng.random() - 0.5) * pixel * up)
                rays_d.append(directions[v * n * n + k])
        start = time.perf_counter()
        mean, error = firncore.monte_carlo_radiance(core_path, case.optics, np.array(rays_o), np.array(rays_d),
                                                    suns=case.suns(), sky=case.skies(),
                                                    samples=max(1, case.samples // jitter), seed=3)
        mc_seconds = time.perf_counter() - start
        mc = mean.reshape(n * n, jitter, 3).mean(1)
        mc_error = np.sqrt((error.reshape(n * n, jitter, 3) ** 2).sum(1)) / jitter
        seen = tau[v * n * n:(v + 1) * n * n] >= 1.0
        cy = image.reshape(n * n, 3)[seen]
        m, e = mc[seen], mc_error[seen]
        relative = cy / m - 1.0
        print(f"  view ({azimuth:.0f}, 0): Cycles {cy.mean():.4f} ({cycles_seconds:.0f} s), Monte Carlo {m.mean():.4f} "
              f"({mc_seconds:.0f} s): Cycles / MC - 1 = {100 * (cy.sum() / m.sum() - 1):+.1f} %; per pixel mean "
              f"|diff| {100 * np.abs(relative).mean():.1f} %, worst {100 * np.abs(relative).max():.0f} % "
              f"(MC noise {100 * np.median(e / m):.1f} %)", flush=True)


main()
