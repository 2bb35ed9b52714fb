"""A ball case's squared error split by view, region and light part (docs/benchmarks.md, ball-issue-split).

Every seen block of the suite's case (bench/bake_suite.py, green channel, its cached reference) is put in a region by
the ball's normal at the block ray's optical depth 1 point: mu0 (to the sun) and mu_v (to the camera): lit face
(mu0 >= 0.3, mu_v >= 0.5), lit limb (mu0 >= 0.3, mu_v < 0.5), terminator (|mu0| < 0.3), shadowed face, shadowed
limb. Each block's relative error e = baked / reference - 1 is split by light: the sun alone and the sky alone, each
baked (FINAL, --seed) and traced by the core's Monte Carlo (--samples paths, seeds 21 and 22), e_sun = (baked sun -
Monte Carlo sun) / reference, e_sky likewise (their sum differs from e by the reference's and these runs' noise). The
baked sun is split into its peaked lobes' part (grids firn_source_peak*: the ramp's single scattering, beamsInRamp, and
the surface's forward return) and its broad part (the diffusion's own light); the Monte Carlo sun into its exact single
scattering (backlit_probe.single_scattering) and the rest. Per region: blocks, sum e^2 (and its share), sum e_sun^2,
sum e_sky^2, the two runs' variance over the reference squared, summed (what their noise adds to those two), mean e,
and the four sums of radiance. With --voxel the same ball and snow on other voxels, against the two runs summed.

    PYTHONPATH=build/python python3 bench/ball_light_budget.py [--case ball_issue] [--samples 4096] [--seed 0]
        [--maps] [--voxel 0.005]
"""

import argparse
import dataclasses
import os
import re
import tempfile

import numpy as np

import bake_suite
import firncore
from backlit_probe import single_scattering, sun_towards, write_without_peaks


def region_names(case, origins, directions, seen):
    """Each block's region by its normal at optical depth 1 (the ball's centre to that point)."""
    hit = bake_suite.depth_one_points(case, origins, directions, seen)
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    normal = (hit - centre) / np.linalg.norm(hit - centre, axis=1)[:, None]
    mu0, muv = normal @ sun_towards(), -(normal * directions).sum(1)
    side = np.where(mu0 >= 0.3, "lit", np.where(mu0 < -0.3, "shadowed", "terminator"))
    return np.array([s if s == "terminator" else f"{s} {'face' if v >= 0.5 else 'limb'}" for s, v in zip(side, muv)])


def baked_parts(case, folder, origins, directions, seed, **light):
    """One light baked alone: the render whole and its peaked lobes' part."""
    path = os.path.join(folder, "alone.vdb")
    bake_suite.write_density(path, case.density, case.voxel)
    firncore.bake(path, case.optics, quality="FINAL", seed=seed, **light)
    whole = firncore.render_baked(path, case.optics, origins, directions)[:, 1]
    write_without_peaks(path, path + ".broad.vdb")
    broad = firncore.render_baked(path + ".broad.vdb", case.optics, origins, directions)[:, 1]
    return whole, whole - broad


def truth_parts(case, path, origins, directions, samples, cache):
    """The Monte Carlo's sun alone and sky alone, the sun's exact single scattering and the two runs' variance (green),
    cached in `cache`."""
    file = os.path.join(cache, f"{case.name}_{case.key()}_{samples}e.npz")
    if os.path.exists(file):
        data = np.load(file)
        return data["sun"], data["sky"], data["once"], data["variance"]
    sun, sun_error = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                                   samples=samples, seed=21)
    sky, sky_error = firncore.monte_carlo_radiance(path, case.optics, origins, directions, sky=case.skies(),
                                                   samples=samples, seed=22)
    once = case.sun * np.array([single_scattering(case, o, d) for o, d in zip(origins, directions)])
    variance = sun_error[:, 1] ** 2 + sky_error[:, 1] ** 2
    os.makedirs(cache, exist_ok=True)
    np.savez(file, sun=sun[:, 1], sky=sky[:, 1], once=once, variance=variance)
    return sun[:, 1], sky[:, 1], once, variance


def maps(case, seen, arrays):
    """Each array per view as the suite's pixel map (top row first); relative ones (names starting e) in %."""
    per, n = case.pixels ** 2, case.pixels
    for v, view in enumerate(case.views):
        for name, values in arrays.items():
            full = np.full(len(seen), np.nan)
            full[seen] = values
            print(f"  view {view}, {name}")
            for r in reversed(range(n)):
                cells = full[v * per + r * n:v * per + (r + 1) * n]
                print("   " + " ".join("   .  " if np.isnan(x) else (f"{100 * x:+5.0f} " if name.startswith("e")
                                                                      else f"{x:.4f}") for x in cells))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_issue")
    parser.add_argument("--samples", type=int, default=4096)
    parser.add_argument("--seed", type=int, default=0, help="the bakes'")
    parser.add_argument("--voxel", type=float, default=0.0,
                        help="the case's ball on voxels of this size (m), the same snow; its reference the lights' sum")
    parser.add_argument("--maps", action="store_true",
                        help="per view, the pixel maps of e, e_sun, e_sky and the sun's parts")
    parser.add_argument("--parts-cache", default=os.path.join(tempfile.gettempdir(), "firn_light_budget"))
    parser.add_argument("--cache", default=bake_suite.CACHE)
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    if args.voxel > 0.0:  # the same ball and snow on other voxels; the reference: the two lights' runs summed
        radius = float(re.search(r"r (\d+) cm", case.what).group(1)) / 100.0
        case = dataclasses.replace(case, density=bake_suite.ball(radius, args.voxel) * case.density.max(),
                                   voxel=args.voxel)
    origins, directions, tau = bake_suite.views(case)
    seen = tau >= 1.0
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "snow.vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), quality="FINAL", seed=args.seed)
        baked = firncore.render_baked(path, case.optics, origins, directions)[:, 1]
        o, d = origins[seen], directions[seen]
        sun, sun_peak = baked_parts(case, folder, o, d, args.seed, suns=case.suns())
        sky, _ = baked_parts(case, folder, o, d, args.seed, sky=case.skies())
        mc_sun, mc_sky, once, variance = truth_parts(case, path, o, d, args.samples, args.parts_cache)
    if args.voxel > 0.0:
        reference = mc_sun + mc_sky
    else:
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "snow.vdb")
            bake_suite.write_density(path, case.density, case.voxel)
            reference = bake_suite.reference(case, path, origins, directions, args.cache)[0][seen, 1]
    baked = baked[seen]
    e = baked / reference - 1.0
    e_sun, e_sky = (sun - mc_sun) / reference, (sky - mc_sky) / reference
    noise = variance / reference ** 2  # what the two runs' noise adds to e_sun^2 + e_sky^2 (the reference's to e^2)
    view = np.repeat([str(v) for v in case.views], case.pixels ** 2)[seen]
    region = region_names(case, origins, directions, seen)[seen]
    total = (e ** 2).sum()
    print(f"{case.name}, bake seed {args.seed}, {args.samples} paths per light; sum e^2 {total:.3f} over {len(e)} "
          f"blocks (green); mean |e| {np.abs(e).mean():.1%}, worst {e[np.abs(e).argmax()]:+.0%}, bias "
          f"{baked.sum() / reference.sum() - 1:+.1%}; the lights baked apart against together: sum e^2 "
          f"{(((sun + sky) / baked - 1) ** 2).sum():.3f}, worst {np.abs((sun + sky) / baked - 1).max():.1%}; per view "
          + ", ".join(
              f"{v} {baked[view == v].sum() / reference[view == v].sum() - 1:+.1%}" for v in dict.fromkeys(view)))
    print("  view          region          blocks  sum e^2 (share)  e_sun^2  e_sky^2  noise  mean e  mean e_sun  "
          "mean e_sky   sun: MC (once, more)         baked (peak, broad)          sky: MC  baked")
    rows = []
    for v in dict.fromkeys(view):
        for r in ("lit face", "lit limb", "terminator", "shadowed face", "shadowed limb"):
            k = (view == v) & (region == r)
            if k.any():
                rows.append(((e[k] ** 2).sum(), v, r, k))
    for share, v, r, k in sorted(rows, key=lambda x: -x[0]):
        print(f"  {v:<13} {r:<15} {k.sum():4d}   {share:6.3f} ({share / total:4.0%})  {(e_sun[k] ** 2).sum():6.3f}  "
              f"{(e_sky[k] ** 2).sum():6.3f}  {noise[k].sum():5.3f}  {e[k].mean():+5.1%}  {e_sun[k].mean():+6.1%}     "
              f"{e_sky[k].mean():+6.1%}    "
              f"{mc_sun[k].sum():.4f} ({once[k].sum():.4f}, {mc_sun[k].sum() - once[k].sum():.4f})  "
              f"{sun[k].sum():.4f} ({sun_peak[k].sum():.4f}, {sun[k].sum() - sun_peak[k].sum():.4f})  "
              f"{mc_sky[k].sum():.4f}  {sky[k].sum():.4f}")
    if args.maps:
        maps(case, seen, {"e": e, "e_sun": e_sun, "e_sky": e_sky, "MC sun": mc_sun, "baked sun": sun,
                          "baked peak": sun_peak, "MC once": once})
    worst = np.argsort(-np.abs(e))[:8]
    print("  worst blocks: view, pixel, region, e, e_sun, e_sky, MC sun (once), baked sun (peak), MC sky, baked sky")
    per = case.pixels ** 2
    index = np.nonzero(seen)[0]
    for j in worst:
        print(f"    {view[j]:<10} {index[j] % per:3d}  {region[j]:<14} {e[j]:+6.1%} {e_sun[j]:+6.1%} {e_sky[j]:+6.1%}  "
              f"{mc_sun[j]:.4f} ({once[j]:.4f})  {sun[j]:.4f} ({sun_peak[j]:.4f})  {mc_sky[j]:.4f}  {sky[j]:.4f}")


if __name__ == "__main__":
    main()
