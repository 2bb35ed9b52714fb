"""Where a ball's surface solve lets the sun out, by the angle psi from the point under the sun, against a flat top
(docs/benchmarks.md, ball-bias). Needs bench/ball_bias_switches.diff applied (its FIRN_T_PRINT line in
surfaceLight, channel G: each smooth patch in the sun's plane with its sun entering, returned, leaving (escaped + the
solve's outflow), escaped at once, fluence and drift); run on a build without it the script finds no patches.

The sun 30 degrees from +x towards +z over the ball (bench/lit_face_probe.py's pole), 30 degrees from +z over the
slab's top; the sun alone, FINAL, seed 0. Printed: the slab top's medians, the ball's per 10-degree band of psi, and
the share of the ball's exitance past the terminator (axisymmetry about the sun assumed). With --truth (the output of
bench/ball_exit_distance.cpp for the same ball: its power per 5-degree ring of psi) and --cross-section (the density's,
m^2: bench/ball_energy_balance.py's "entering" over the sun), both per W entering the density per 10 degrees of psi:
the patches' power is their exitance over the sphere of radius --radius (the render shows it over the density's
larger ball, docs/benchmarks.md snow-bias).

    git apply bench/ball_bias_switches.diff && make -C build firncore
    PYTHONPATH=build/python python3 bench/ball_patch_exit.py [--case ball_snow] [--radius 0.08]
"""

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

import bake_suite
import firncore


def patches(case, radius, shape):
    """The printed patches (columns: normal 3, sun in, returned, leaving, at once, phi, drift 3, area) of one bake,
    run in a child so its stderr can be read."""
    run = subprocess.run([sys.executable, __file__, "--child", case, str(radius), shape],
                         env={**os.environ, "FIRN_T_PRINT": "1"}, capture_output=True, text=True, check=True)
    rows = [[float(x) for x in re.findall(r"[-+]?\d*\.?\d+(?:[eE][-+]?\d+)?", line)]
            for line in run.stderr.splitlines() if line.startswith("PATCH")]
    return np.array(rows).reshape(-1, 12)


def child(name, radius, shape):
    case = bake_suite.case(name)
    peak = case.density.max()
    density = bake_suite.ball(radius, case.voxel) * peak if shape == "ball" else bake_suite.slab(32, 12) * peak
    s = math.radians(30.0)
    sun = (math.cos(s), 0.0, math.sin(s)) if shape == "ball" else (math.sin(s), 0.0, math.cos(s))
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "snow.vdb")
        bake_suite.write_density(path, density, case.voxel)
        firncore.bake(path, case.optics, suns=[firncore.SunLight(sun, (1.0,) * 3, 0.0093)], quality="FINAL", seed=0)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        child(sys.argv[2], float(sys.argv[3]), sys.argv[4])
        return
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_snow", help="the bench/bake_suite.py case whose snow to use")
    parser.add_argument("--radius", type=float, default=0.08, help="m")
    parser.add_argument("--truth", default="", help="bench/ball_exit_distance.cpp's output for this ball")
    parser.add_argument("--cross-section", type=float, default=0.0, help="the density's, m^2")
    args = parser.parse_args()
    slab = patches(args.case, args.radius, "slab")
    top = slab[slab[:, 2] > 0.99]
    print(f"slab top ({len(top)} patches, sun 30 deg): per sun entering returned {np.median(top[:, 4] / top[:, 3]):.3f}, "
          f"leaving {np.median(top[:, 5] / top[:, 3]):.3f}, at once {np.median(top[:, 6] / top[:, 3]):.3f}")
    ball = patches(args.case, args.radius, "ball")
    sun = np.array([math.cos(math.radians(30.0)), 0.0, math.sin(math.radians(30.0))])
    n = ball[:, 0:3]
    mu0 = n @ sun
    psi = np.degrees(np.arccos(np.clip(mu0, -1.0, 1.0)))
    print(f"ball r {args.radius * 100:g} cm of {args.case}'s snow, by psi: mu0, per sun entering leaving and at once, "
          "exitance (W/m^2 per W/m^2 of sun), drift away from the point under the sun")
    total = past = 0.0
    bands = []
    for lo in range(0, 180, 10):
        k = (psi >= lo) & (psi < lo + 10)
        if not k.any():
            continue
        entering = np.where(ball[k, 3] > 0.0, ball[k, 3], np.nan)
        away = -(sun[None, :] - mu0[k, None] * n[k])
        away /= np.maximum(np.linalg.norm(away, axis=1)[:, None], 1e-9)
        exitance = np.mean(ball[k, 5] / ball[k, 11])
        band = math.cos(math.radians(lo)) - math.cos(math.radians(lo + 10))
        total, past = total + exitance * band, past + exitance * band * (lo >= 90)
        bands.append(exitance * band)
        per = (f"leaving {np.nanmean(ball[k, 5] / entering):.3f}  at once {np.nanmean(ball[k, 6] / entering):.3f}"
               if np.isfinite(entering).any() else "(unlit)" + " " * 27)
        print(f"  psi {lo:3d}-{lo + 10:3d}  mu0 {mu0[k].mean():+.2f}  {per}  exitance {exitance:.4f}  "
              f"drift {(ball[k, 8:11] * away).sum(1).mean():+.3f}")
    print(f"  exitance past the terminator: {past / total:.3f} of the ball's")
    if args.truth:
        rings = [float(x) for x in open(args.truth).read().split("per 5 deg ring of psi, per W entering:")[1].split()[:36]]
        truth = np.array(rings[0::2]) + np.array(rings[1::2])
        baked = np.array(bands) * 2.0 * math.pi * args.radius ** 2 / args.cross_section
        print("per W entering, per 10 deg of psi: the truth (ball_exit_distance) | the patches")
        print("  " + " ".join(f"{x:.3f}" for x in truth) + f"  sum {truth.sum():.3f}")
        print("  " + " ".join(f"{x:.3f}" for x in baked) + f"  sum {baked.sum():.3f}")
        for name, part in (("psi < 40", slice(0, 4)), ("40-90", slice(4, 9)), ("past 90", slice(9, 18))):
            print(f"  {name}: truth {truth[part].sum():.3f}, patches {baked[part].sum():.3f}")


if __name__ == "__main__":
    main()
