"""Thin snow scattered by Cycles itself (docs/benchmarks.md, thin-ring and thin-cycles): the suite's cases baked by
firncore, then rendered by Cycles with the add-on's own material in its two forms: BAKED, and BAKED_SCATTER
(Scatter Thin Snow), which scatters where the bake's `firn_scatter` grid is 1 (rule B of thin-ring: the voxels the
bake traces of sigma_t h < 2 and the air touching them): Principled Volume of k rho share
(colour omega, anisotropy g), absorption k rho (1 - share) and the baked emission k rho S (1 - share); a voxel per
step times the scene's `--step-rate`. Cycles unclamped, `--bounces` volume bounces,
the camera's background transparent (the suite's reference leaves the sky seen straight through
the snow out). Each image is `--factor` (odd) times the suite's pixels with a pixel filter of 0.01 pixel, so
the middle pixel of each factor x factor group is the suite's camera ray through that block's centre: the blocks
compare one to one with the cached Monte Carlo reference (bench/bake_suite.py's figures: mean |error| over the
blocks of optical depth >= 1, worst, bias, each view's bias). Noise: the mean |relative difference| of the
blocks against the render at the most samples. Time: Cycles' wall seconds per render (its threads `--threads`).
With `--core-paths N` the same bake is also rendered by the core's emulation of the mixed material
(`render_scattering_where_thin`, bench/bake_suite.py's mixed rows, N paths per block) and each Cycles mixed render
is set against it block by block: their bias (sum over sum) with its standard error, and chi2 per block, the sum
of the squared relative differences over the sum of the two renders' relative variances (1 where they differ by
noise alone; Cycles' variance from `--seeds` renders, at least 2, each its own Cycles seed, whose mean is the figure).

    bench/run.sh bench/thin_scatter_cycles.py -- [--cases slab_thin_forward,ball_forward] [--samples 64,256,1024]
        [--baked-samples 64,1024] [--bounces 16] [--step-rate 1] [--factor 1] [--threads 2] [--seeds 1]
        [--core-paths 0]
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
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "tests", "blender"))
from bake_helpers import uniform_world, volume_object  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="slab_thin_forward,ball_forward")
    parser.add_argument("--samples", default="64,256,1024", help="Cycles samples of the mixed material")
    parser.add_argument("--baked-samples", default="64,1024", help="Cycles samples of the baked material")
    parser.add_argument("--bounces", type=int, default=16, help="volume bounces of the mixed material")
    parser.add_argument("--step-rate", type=float, default=1.0, help="the scene's, times the material's")
    parser.add_argument("--factor", type=int, default=1, help="image pixels per suite block and axis (odd)")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--seeds", type=int, default=1, help="Cycles mixed renders per sample count (their mean)")
    parser.add_argument("--core-paths", type=int, default=0,
                        help="paths per block of the core's mixed render to set Cycles' against (0: none)")
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_bake_suite"))
    args = parser.parse_args(argv)
    if args.factor % 2 != 1:
        parser.error("--factor must be odd (a pixel centred on each block's ray)")
    if args.core_paths and args.seeds < 2:
        parser.error("--core-paths needs --seeds 2 or more (Cycles' own variance per block)")
    return args


def cycles_copy(core_path, path):
    """The baked file (the bake's firn_scatter among its grids) voxel by voxel (Cycles draws tiles as nothing), each
    grid with its own transform: the bake writes them in Cycles' convention, firn_scatter on voxels SCATTER_SCALE
    times the density's (docs/vdb-contract.md; given the density's transform, it shrank towards the origin)."""
    import pyopenvdb

    grids = []
    for source in pyopenvdb.readAll(core_path)[0]:
        grid = type(source)()
        grid.name, grid.transform = source.name, source.transform.deepCopy()
        accessor = grid.getAccessor()
        for item in source.citerOnValues():
            lo, hi = item["min"], item["max"]
            for i in range(lo[0], hi[0] + 1):
                for j in range(lo[1], hi[1] + 1):
                    for k in range(lo[2], hi[2] + 1):
                        accessor.setValueOn((i, j, k), item["value"])
        grids.append(grid)
    pyopenvdb.write(path, grids=grids)


def snow_material(obj, case, scatter):
    """The add-on's own material for the baked file, as after Bake Scattering: its form BAKED_SCATTER (the file
    has firn_scatter) with Scatter Thin Snow on, BAKED with it off."""
    from firn.bake import operators as bake, state as bake_state
    from firn.material import nodes as materials

    obj.firn.is_snow = True
    bake_state.store(obj, {"bench": case.name})  # a bake's fingerprint: the material asks only whether there is one
    bake.keep_baked_optics(obj.firn, case.optics)
    obj.firn.scatter_thin = scatter
    materials.ensure_snow_material(obj)
    assert materials.material_form(obj) == ("BAKED_SCATTER" if scatter else "BAKED")


def scene_for(case, path, args):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("firn", default_set=True)  # factory settings leave it off
    uniform_world((case.sky,) * 3)
    scene = bpy.context.scene
    if case.sun > 0.0:
        sun_data = bpy.data.lights.new("Sun", "SUN")
        sun_data.energy = case.sun  # W/m^2 on a plane facing it
        sun_data.angle = 0.0093
        sun = bpy.data.objects.new("Sun", sun_data)
        sun.rotation_euler = (-Vector(case.suns()[0].direction)).to_track_quat("-Z", "Y").to_euler()
        scene.collection.objects.link(sun)
    snow = volume_object(path, "Snow")
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.use_denoising = False
    cycles.use_adaptive_sampling = False
    cycles.pixel_filter_type = "GAUSSIAN"  # Blender syncs a box filter at width 1 whatever filter_width says
    cycles.filter_width = 0.01  # pixels: each sample through the pixel's centre, the suite's camera ray
    scene.render.film_transparent = True  # the reference leaves the sky seen straight through the snow out
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    cycles.volume_step_rate = args.step_rate
    cycles.volume_bounces = args.bounces
    cycles.max_bounces = cycles.transparent_max_bounces = max(args.bounces, 8)
    scene.render.threads_mode = "FIXED"
    scene.render.threads = args.threads
    scene.render.resolution_x = scene.render.resolution_y = case.pixels * args.factor
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    return snow


def render_views(case, directory, samples, seed, args):
    """The case's views as (blocks of all views, 3) radiance at the block centres, (full images), seconds."""
    n = np.array(case.density.shape)
    centre = (n - 1) / 2 * case.voxel
    nonzero = np.argwhere(case.density > 0)
    radius = 0.55 * np.max((nonzero.max(0) - nonzero.min(0) + 1) * case.voxel)
    scene = bpy.context.scene
    scene.cycles.samples = samples
    scene.cycles.seed = seed
    blocks, images, seconds = [], [], 0.0
    middle = args.factor // 2
    for v, (azimuth, elevation) in enumerate(case.views):
        a, e = math.radians(azimuth), math.radians(elevation)
        back = Vector((math.cos(a) * math.cos(e), math.sin(a) * math.cos(e), math.sin(e)))
        data = bpy.data.cameras.new("Camera")
        data.type, data.ortho_scale, data.clip_start = "ORTHO", float(2.0 * radius), 0.001
        camera = bpy.data.objects.new("Camera", data)
        camera.location = Vector(tuple(map(float, centre))) + float(3.0 * radius) * back
        up = "Y" if abs(back.z) < 0.99 else "X"  # bake_suite.views' up: world z, or x looking straight down
        camera.rotation_euler = (-back).to_track_quat("-Z", up).to_euler()
        scene.collection.objects.link(camera)
        scene.camera = camera
        path = os.path.join(directory, f"{case.name}_{v}_{samples}_{seed}.exr")
        scene.render.filepath = path
        start = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        seconds += time.perf_counter() - start
        image = bpy.data.images.load(path, check_existing=False)
        width, height = image.size
        pixels = np.empty(width * height * 4, np.float32)
        image.pixels.foreach_get(pixels)
        bpy.data.images.remove(image)
        pixels = pixels.reshape(height, width, 4)[:, :, :3]  # rows bottom up, as views' v
        images.append(pixels)
        blocks.append(pixels[middle::args.factor, middle::args.factor].reshape(-1, 3))
        bpy.data.objects.remove(camera)
    return np.concatenate(blocks), images, seconds


def scores(case, estimate, reference, seen):
    per = case.pixels ** 2
    relative = estimate[seen] / np.maximum(reference[seen], 1e-30) - 1.0
    views = [estimate[v * per:(v + 1) * per][seen[v * per:(v + 1) * per]].sum() /
             reference[v * per:(v + 1) * per][seen[v * per:(v + 1) * per]].sum() - 1.0 for v in range(len(case.views))]
    worst = relative.flat[np.abs(relative).argmax()]
    return (f"{100 * np.abs(relative).mean():5.1f} % {100 * worst:+5.0f} % "
            f"{100 * (estimate[seen].sum() / reference[seen].sum() - 1.0):+5.1f} %  "
            + " ".join(f"{100 * b:+4.0f}" for b in views))


def agreement(cycles_mean, cycles_variance, core, core_error, seen):
    """Cycles' mixed render (mean of its seeds and that mean's variance per block) against the core's (mean and
    standard error per block) over the seen blocks: the bias with its standard error, chi2 per block."""
    c, v, b, e = cycles_mean[seen], cycles_variance[seen], core[seen], core_error[seen]
    bias = c.sum() / b.sum() - 1.0
    bias_error = np.sqrt(v.sum() + (e ** 2).sum()) / b.sum()
    scale = np.maximum(b, 1e-30) ** 2  # relative terms: every block weighs alike, bright or dim
    chi2 = ((c - b) ** 2 / scale).sum() / ((v + e ** 2) / scale).sum()  # one noisy variance per block: pooled
    return (f"against the core's: bias {100 * bias:+.2f} +- {100 * bias_error:.2f} %, chi2 per block {chi2:.2f}, "
            f"mean |difference| {100 * np.abs(c / np.maximum(b, 1e-30) - 1).mean():.1f} %")


def main():
    args = parse_args()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("firn", default_set=True)
    from firn.common.core import firncore

    sys.modules.setdefault("firncore", firncore)  # bake_suite imports it by name, as outside Blender
    import bake_suite

    directory = tempfile.mkdtemp(prefix="firn_thin_cycles_")
    counts = [int(x) for x in args.samples.split(",")]
    print(f"Cycles {bpy.app.version_string}, {args.threads} threads, volume bounces {args.bounces}, step rate "
          f"{args.step_rate}, unclamped; images {args.factor}x the suite's blocks; figures: mean |error|, worst, "
          "bias over the blocks of optical depth >= 1, each view's bias; s: Cycles' wall seconds for all views",
          flush=True)
    for name in args.cases.split(","):
        case = bake_suite.case(name)
        core_path = os.path.join(directory, name + "_core.vdb")
        run = bake_suite.baked_case(case, core_path, args.cache)
        origins, directions, tau, reference, error = run.origins, run.directions, run.tau, run.mean, run.error
        seen = tau >= 1.0
        core_baked = firncore.render_baked(core_path, case.optics, origins, directions, occluders=case.occluders)
        scatter = (firncore.grid_statistics(core_path, firncore.SCATTER_GRID_NAME)["active_voxels"]
                   if firncore.SCATTER_GRID_NAME in firncore.grid_names(core_path) else 0)
        path = os.path.join(directory, name + ".vdb")
        cycles_copy(core_path, path)
        print(f"{name}: {case.what}; views {case.views}; {scatter} firn_scatter voxels (the bake's) "
              f"({int((case.density > 0).sum())} snow voxels); reference noise "
              f"{100 * np.median(error[seen] / np.maximum(reference[seen], 1e-30)):.1f} %", flush=True)
        print(f"  {'core render_baked':<34} {scores(case, core_baked, reference, seen)}", flush=True)

        snow = scene_for(case, path, args)
        snow_material(snow, case, scatter=False)
        for samples in [int(x) for x in args.baked_samples.split(",")]:
            baked, _, seconds = render_views(case, directory, samples, 0, args)
            print(f"  {'Cycles baked, %d spp' % samples:<34} {scores(case, baked, reference, seen)}"
                  f"   {seconds:6.1f} s", flush=True)
        print(f"    Cycles baked / core render_baked - 1: mean |per block| "
              f"{100 * np.abs(baked[seen] / np.maximum(core_baked[seen], 1e-30) - 1).mean():.1f} %, sum "
              f"{100 * (baked[seen].sum() / core_baked[seen].sum() - 1):+.1f} %", flush=True)
        if args.core_paths:
            core, core_error = firncore.render_scattering_where_thin(
                core_path, case.optics, origins, directions, suns=case.suns(), sky=case.skies(),
                occluders=case.occluders, samples=args.core_paths, seed=1000, traced_only=True)
            print(f"  {'core mixed, %d paths' % args.core_paths:<34} {scores(case, core, reference, seen)}   noise "
                  f"{100 * np.median(core_error[seen] / np.maximum(core[seen], 1e-30)):.1f} %", flush=True)
        snow_material(snow, case, scatter=True)
        renders = {}
        for samples in counts:
            seeded, seconds = [], 0.0
            for seed in range(args.seeds):
                blocks, _, spent = render_views(case, directory, samples, seed, args)
                seeded.append(blocks)
                seconds += spent
            renders[samples] = np.mean(seeded, axis=0)
            print(f"  {'Cycles mixed, %d spp x %d' % (samples, args.seeds):<34} "
                  f"{scores(case, renders[samples], reference, seen)}   {seconds:6.1f} s", flush=True)
            if args.core_paths:
                variance = np.var(seeded, axis=0, ddof=1) / args.seeds
                print(f"    {agreement(renders[samples], variance, core, core_error, seen)}", flush=True)
        best = renders[max(counts)]
        print("    noise (mean |block / the %d spp block - 1|): " % max(counts) +
              ", ".join(f"{s} spp {100 * np.abs(renders[s][seen] / np.maximum(best[seen], 1e-30) - 1).mean():.1f} %"
                        for s in counts if s != max(counts)), flush=True)


if __name__ == "__main__":  # bench/bounce_cost.py imports its scene
    main()
