"""Where the baked render shows a ball's sun, by the angle psi from the point under the sun, in absolute power
(docs/benchmarks.md, cap-shape): cap-round's table of the truth's exit power per band against what the render shows.

A bench/bake_suite.py ball case baked with its sun alone (FINAL, --seed) and rendered from a Fibonacci sphere of
orthographic views (no symmetry assumed); each pixel's power L dA (channel G) is put in the band of psi of its ray's
point of optical depth 1 (the normal there taken radially from the ball's centre); rays of optical depth under 1 are
the halo. Summed over the sphere, 4 pi / views, and over the sun's irradiance: cm^2 of sun, the units of cap-round's
truth (ball_snow 75.1 / 157.0 / 22.0 cm^2 at psi < 40 / 40-90 / past 90, its exit point the last scattering). The
peaked lobes' part (grids firn_source_peak*) apart. --directions splits each band's power by the view's angle from
the sun (the directions the light leaves in: towards the sun theta < 60, 60-120, beyond). To split the ramp's own
terms run it with the temporary FIRN_T_RAMPOFF switch of bench/cap_render_switch.diff (bits: 1 forwardPeakThrough,
2 beamsInRamp, 4 limbCarriedInRamp, 16 the patches' radiance carried into the fringe, facingAverage) and subtract.
--samples N renders the core's Monte Carlo (the sun alone, N paths per ray) over the same rays and bins it alike: the
truth per band as the render sees it. --suite instead bins the suite's own views (its sun and sky) against their
cached references.

    PYTHONPATH=build/python:bench python3 bench/cap_render_bands.py [--case ball_snow] [--views 100] [--pixels 24]
        [--samples 64] [--directions] [--suite]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore
from backlit_probe import sun_towards, write_without_peaks
from ball_energy_balance import fibonacci, view_rays

BANDS = ((0, 40), (40, 90), (90, 181))
THETAS = ((0, 60), (60, 120), (120, 181))


def depth_one(case, origins, directions):
    """Each ray's whole optical depth and its point of optical depth 1 (NaN where it never reaches 1)."""
    step = 0.25 * case.voxel
    length = 6.0 * case.voxel * max(case.density.shape)
    s = np.arange(0.5 * step, length, step)
    points = origins[:, None, :] + s[None, :, None] * directions[:, None, :]
    rho = bs.trilinear(case.density, (points / case.voxel).reshape(-1, 3)).reshape(len(origins), -1)
    tau = np.cumsum(rho, axis=1) * step * case.sigma_t / case.rho
    first = np.minimum((tau < 1.0).sum(1), len(s) - 1)
    hit = points[np.arange(len(origins)), first]
    hit[tau[:, -1] < 1.0] = np.nan
    return tau[:, -1], hit


def suite_views(case, args):
    """The suite's views of the case (its sun and sky, FINAL): per view and band of psi, the cached reference's and
    the baked render's sums over the rays (green), and the baked render's peaked part."""
    sun = sun_towards()
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    with tempfile.TemporaryDirectory() as folder:
        bs.run_case(case, folder, args.cache, "FINAL", args.seed)
        path = os.path.join(folder, case.name + ".vdb")
        origins, directions, _ = bs.views(case)
        mean, _, _ = bs.reference(case, path, origins, directions, args.cache)
        baked = firncore.render_baked(path, case.optics, origins, directions)
        write_without_peaks(path, path + ".broad.vdb")
        broad = firncore.render_baked(path + ".broad.vdb", case.optics, origins, directions)
    tau, hit = depth_one(case, origins, directions)
    normal = (hit - centre) / np.linalg.norm(hit - centre, axis=1)[:, None]
    psi = np.degrees(np.arccos(np.clip(normal @ sun, -1.0, 1.0)))
    per = case.pixels ** 2
    print(f"{case.name}, the suite's views, FIRN_T_RAMPOFF {os.environ.get('FIRN_T_RAMPOFF', '0')}: per band of psi "
          "reference, baked (its peaked part), baked / reference - 1, rays")
    for v, view in enumerate(case.views):
        s = slice(v * per, (v + 1) * per)
        m, b, p, t, a = mean[s, 1], baked[s, 1], baked[s, 1] - broad[s, 1], tau[s], psi[s]
        cells = []
        for lo, hi in BANDS:
            k = (t >= 1.0) & (a >= lo) & (a < hi)
            if k.any():
                cells.append(f"psi {lo}-{min(hi, 180)}: {m[k].sum():.4f} {b[k].sum():.4f} ({p[k].sum():.4f}) "
                             f"{b[k].sum() / m[k].sum() - 1:+6.1%} {k.sum():2d}")
        k = t < 1.0
        cells.append(f"halo {m[k].sum():.4f} {b[k].sum():.4f} {k.sum():2d}")
        print(f"  {str(tuple(view)):<9} " + " | ".join(cells))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_snow")
    parser.add_argument("--views", type=int, default=100, help="Fibonacci views over the sphere")
    parser.add_argument("--pixels", type=int, default=24, help="per side of each view")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--directions", action="store_true", help="split each band by the view's angle from the sun")
    parser.add_argument("--samples", type=int, default=0,
                        help="Monte Carlo paths per ray: the core's truth over the same rays and bands (0: none)")
    parser.add_argument("--suite", action="store_true", help="the suite's own views against its cached references")
    parser.add_argument("--cache", default=bs.CACHE)
    args = parser.parse_args()
    if args.suite:
        suite_views(bs.case(args.case), args)
        return
    case = bs.case(args.case)
    sun = sun_towards()
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    power = np.zeros((len(BANDS) + 1, len(THETAS), 3))  # bands + halo, view theta, (all, peaked, Monte Carlo)
    per10 = np.zeros(18)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "snow.vdb")
        bs.write_density(path, case.density, case.voxel)
        firncore.bake(path, case.optics, suns=case.suns(), quality="FINAL", seed=args.seed)
        write_without_peaks(path, path + ".broad.vdb")
        for back in fibonacci(args.views):
            origins, directions, area = view_rays(case, back, args.pixels)
            baked = firncore.render_baked(path, case.optics, origins, directions)[:, 1] * area
            broad = firncore.render_baked(path + ".broad.vdb", case.optics, origins, directions)[:, 1] * area
            traced = np.zeros(len(origins))
            if args.samples:
                mean, _ = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                                        samples=args.samples, seed=7)
                traced = mean[:, 1] * area
            tau, hit = depth_one(case, origins, directions)
            normal = (hit - centre) / np.linalg.norm(hit - centre, axis=1)[:, None]
            psi = np.degrees(np.arccos(np.clip(normal @ sun, -1.0, 1.0)))
            theta = math.degrees(math.acos(float(np.clip(back @ sun, -1.0, 1.0))))
            t = next(i for i, (lo, hi) in enumerate(THETAS) if lo <= theta < hi)
            for b, (lo, hi) in enumerate(BANDS):
                k = (tau >= 1.0) & (psi >= lo) & (psi < hi)
                power[b, t] += baked[k].sum(), (baked - broad)[k].sum(), traced[k].sum()
            halo = tau < 1.0
            power[-1, t] += baked[halo].sum(), (baked - broad)[halo].sum(), traced[halo].sum()
            for j in range(18):
                per10[j] += baked[(tau >= 1.0) & (psi >= 10 * j) & (psi < 10 * j + 10)].sum()
    scale = 4.0 * math.pi / args.views / case.sun * 1e4  # W/sr summed over views -> cm^2 of sun
    power *= scale
    per10 *= scale
    switch = os.environ.get("FIRN_T_RAMPOFF", "0")
    print(f"{case.name}, sun alone, seed {args.seed}, {args.views} views x {args.pixels}^2 px, FIRN_T_RAMPOFF {switch}:"
          " cm^2 of sun by psi of the ray's depth-one point")
    names = [f"psi {lo}-{min(hi, 180)}" for lo, hi in BANDS] + ["halo"]
    for b, name in enumerate(names):
        line = f"  {name:<11} {power[b, :, 0].sum():7.2f} (peaked {power[b, :, 1].sum():6.2f})"
        if args.samples:
            line += f"  Monte Carlo {power[b, :, 2].sum():7.2f} ({power[b, :, 0].sum() / power[b, :, 2].sum() - 1:+6.1%})"
        if args.directions:
            line += "   by view theta " + " / ".join(f"{power[b, t, 0]:6.2f}" for t in range(len(THETAS)))
            if args.samples:
                line += " (MC " + " / ".join(f"{power[b, t, 2]:6.2f}" for t in range(len(THETAS))) + ")"
        print(line)
    print(f"  all         {power[:, :, 0].sum():7.2f} (peaked {power[:, :, 1].sum():6.2f})"
          + (f"  Monte Carlo {power[:, :, 2].sum():7.2f}" if args.samples else ""))
    print("  per 10 deg  " + " ".join(f"{x:.1f}" for x in per10))


if __name__ == "__main__":
    main()
