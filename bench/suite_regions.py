"""A suite case's error split into the bake's own noise and its bias, per region of what its pixels see
(docs/benchmarks.md, spray-dense).

Bakes the case with seeds 0..N-1 against the suite's cached reference (bench/bake_suite.py; each pixel one block,
its three channels averaged as the suite's mean is) and reports, per region, the mean |relative error| of one
seed's render, of the seeds' mean render (its noise shrunk by sqrt(N): what is left is bias, the reference's noise
and the mean's own), the baked render's spread across the seeds (relative standard deviation per block) and the
bias of the sum, and one seed's squared error per block split into the seeds' variance and the bias squared (each
as rms over the blocks: the noise more paths remove, the error they do not). Regions by where each pixel's camera
ray reaches optical depth 1 of snow: sun-lit or shadowed there (the sun's optical depth from that point, under or
over 2), and the ray's whole optical depth through the snow (a rim or a thin lump: under 20; a lump's core: 20 or
more); and per view. With --mixed N the same for the mixed render (bake_suite.run_case: Cycles scattering the
bake's thin traced snow, N paths per block), the regions split further by whether the ray reaches depth 1 in a
voxel the renderer scatters (firncore.scatter_voxels: the bake's firn_scatter).

    PYTHONPATH=build/python python3 bench/suite_regions.py [--case spray_dense] [--seeds 4] [--mixed 1024]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore


def sun_depth(case, points):
    """Optical depth of the snow from each point towards the sun (NaN points give NaN); occluders are not counted
    (with --case bumpy_plate the blocks under the plate count as lit)."""
    towards = np.array([math.cos(bake_suite.SUN_ELEVATION), 0.0, math.sin(bake_suite.SUN_ELEVATION)])
    steps = np.linspace(0.0, 0.5, 2000)
    out = np.full(len(points), np.nan)
    for i, p in enumerate(points):
        if np.all(np.isfinite(p)):
            line = p + steps[:, None] * towards
            column = bake_suite.trilinear(case.density, line / case.voxel).sum() * (steps[1] - steps[0])
            out[i] = column * case.sigma_t / case.rho
    return out


def regions(case, origins, directions, tau):
    """Per pixel: seen (the ray's optical depth through the snow at least 1), lit (the sun's optical depth under 2
    where a seen ray reaches depth 1) and core (the ray's optical depth 20 or more)."""
    seen = tau >= 1.0
    lit = sun_depth(case, bake_suite.depth_one_points(case, origins, directions, seen)) < 2.0
    return seen, lit, tau >= 20.0


def row(label, relative, spread, mean_render, reference):
    """One region's figures: per-seed and seeds' mean |error|, spread, bias (blocks x channels arrays)."""
    per_seed = np.mean([np.abs(r).mean() for r in relative])
    of_mean = np.abs(mean_render / reference - 1.0).mean()
    bias = mean_render.sum() / reference.sum() - 1.0
    # Per block, one seed's squared error = its bias squared + the seeds' variance: both as rms over the blocks, the
    # bias squared less what the seeds' mean keeps of the variance (unbiased; the reference's noise stays in it).
    variance = relative.var(0, ddof=1)
    bias_squared = relative.mean(0) ** 2 - variance / len(relative)
    noise_rms, bias_rms = math.sqrt(variance.mean()), math.sqrt(max(bias_squared.mean(), 0.0))
    return (f"  {label:<28} {relative.shape[1]:4d} pixels  one seed {100 * per_seed:5.1f} %  seeds' mean "
            f"{100 * of_mean:5.1f} %  spread {100 * spread.mean():5.1f} %  bias {100 * bias:+5.1f} %  per block rms: "
            f"noise {100 * noise_rms:5.1f} %, bias {100 * bias_rms:5.1f} %")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="spray_dense")
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--cache", default=bake_suite.CACHE)
    parser.add_argument("--mixed", type=int, default=0, help="paths per block of the mixed render (0: baked only)")
    args = parser.parse_args()
    if args.seeds < 2:
        parser.error("--seeds must be 2 or more (the spread across seeds)")
    case = bake_suite.case(args.case)
    origins, directions, tau = bake_suite.views(case)
    seen, lit, core = regions(case, origins, directions, tau)
    with tempfile.TemporaryDirectory() as folder:
        runs = [bake_suite.run_case(case, folder, args.cache, seed=seed, mixed=args.mixed) for seed in range(args.seeds)]
        path = os.path.join(folder, case.name + ".vdb")
        scattered = set(map(tuple, firncore.scatter_voxels(path, case.optics, occluders=case.occluders)))
        bake_suite.write_density(path, case.density, case.voxel)
        reference, _, _ = bake_suite.reference(case, path, origins, directions, args.cache)
    hits = bake_suite.depth_one_points(case, origins, directions, seen)[seen]
    thin = np.array([tuple(np.rint(p / case.voxel).astype(int)) in scattered for p in hits])
    reference = reference[seen]
    lit, core = lit[seen], core[seen]
    view = np.repeat(np.arange(len(case.views)), case.pixels ** 2)[seen]
    forms = [("baked", runs)] + ([(f"mixed, {args.mixed} paths", [r["mixed"] for r in runs])] if args.mixed else [])
    for form, chosen in forms:
        relative = np.array([r["relative"] for r in chosen])  # seeds x blocks x channels
        renders = (relative + 1.0) * reference
        mean_render = renders.mean(0)
        spread = renders.std(0, ddof=1) / np.maximum(mean_render, 1e-30)
        print(f"{case.name} {form}, {args.seeds} seeds: one seed's means " +
              ", ".join(f"{100 * r['mean']:.1f}" for r in chosen) + " %")
        groups = [("all", np.ones(len(reference), bool)),
                  ("lit, core (tau >= 20)", lit & core), ("lit, rim or thin (tau < 20)", lit & ~core),
                  ("shadowed, core", ~lit & core), ("shadowed, rim or thin", ~lit & ~core)]
        if args.mixed:
            groups += [("depth 1 in scattered voxels", thin), ("  of them lit", thin & lit),
                       ("depth 1 in baked, core", ~thin & core), ("depth 1 in baked, rim", ~thin & ~core),
                       ("  baked, lit", ~thin & lit), ("  baked, shadowed", ~thin & ~lit)]
        groups += [(f"view {v}", view == i) for i, v in enumerate(case.views)]
        for label, where in groups:
            if where.any():
                print(row(label, relative[:, where], spread[where], mean_render[where], reference[where]), flush=True)


if __name__ == "__main__":
    main()
