"""Can the sun lobe table's family hold a half-space's low-sun exits (docs/benchmarks.md, lit-hg-blend 2)?

The exact half-space (bench/lobe_form.py's half_space_exits: numpy local estimates, pi L / (mu0 E), sun travelling
towards +x) of a bench/bake_suite.py case's snow under a low sun, and the table's family fitted to it: a peaked HG
lobe (SunPeak: anisotropy k about an axis in the sun's plane at least kMinPeakElevationDegrees = 5 deg above the
horizon, forwards) plus a broad HG lobe (what exitLobe makes of the linear rest), the exitance kept, least squares in
relative error weighted by mu dw (the table's weight) or by dw (grazing exits weigh as much as the others). Printed:
the truth and each fit towards the probe exits of bench/flat_limb_split.py (mu@azimuth off the sun's travel).

    /usr/bin/python3 bench/limb_family_fit.py [--optics ball_grey] [--mu0 0.15,0.3,0.44] [--photons 8000]
"""
import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from lobe_form import axis, half_space_exits, lobe, nelder_mead, sphere_grid  # noqa: E402

OPTICS = {"ball_grey": (0.9, 0.6), "ball_issue": (0.98, 0.85), "ball_snow": (0.9999, 0.85)}  # bake_suite's (omega, g)
EXITS = "0.05@29,0.18@29,0.4@29,0.05@90,0.18@90,0.4@90,0.05@150,0.18@150,0.4@150"
MIN_ELEVATION = math.radians(5.0)


def exit_direction(mu, azimuth_deg):
    a, s = math.radians(azimuth_deg), math.sqrt(1.0 - mu * mu)
    return np.array([s * math.cos(a), s * math.sin(a), mu])  # forward = +x, the sun's travel


def family(p, v):
    """share P(k_p about elevation e) + (1 - share) HG(k_b about theta_b in the sun's plane), unscaled."""
    share = 1.0 / (1.0 + math.exp(-p[0]))
    k_peak = 0.95 * math.tanh(p[1])
    elevation = MIN_ELEVATION + (0.5 * math.pi - MIN_ELEVATION) / (1.0 + math.exp(-p[2]))
    peak = lobe(k_peak, v @ axis(0.5 * math.pi - elevation, 0.0))
    broad = lobe(0.95 * math.tanh(p[3]), v @ axis(p[4], 0.0))
    return share * peak + (1.0 - share) * broad


def fit(target, views, dw, weight):
    flux = (target * views[:, 2] * dw).sum()

    def model(p, v=views):
        f = family(p, v)
        return f * flux / max((family(p, views) * views[:, 2] * dw).sum(), 1e-30)

    def cost(p):
        return (weight * ((model(p) - target) / np.maximum(target, 1e-3)) ** 2).sum() / weight.sum()

    starts = [[-0.85, 1.4, -3.0, 0.4, 1.0], [0.0, 1.0, -1.0, 0.5, 1.0], [-2.0, 2.0, -3.0, 0.1, 0.2]]
    best = min((nelder_mead(cost, x0) for x0 in starts), key=cost)
    return best, model


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--optics", default="ball_grey", choices=sorted(OPTICS))
    parser.add_argument("--mu0", default="0.15,0.3,0.44")
    parser.add_argument("--exits", default=EXITS)
    parser.add_argument("--photons", type=int, default=8000)
    args = parser.parse_args()
    omega, g = OPTICS[args.optics]
    exits = [tuple(float(x) for x in e.split("@")) for e in args.exits.split(",")]
    probes = np.array([exit_direction(mu, a) for mu, a in exits])
    views, dw = sphere_grid(12, 36, upper_only=True)
    print(f"{args.optics} (omega {omega}, g {g}), {args.photons} photons: pi L / (mu0 E) towards each exit, the "
          f"truth (+- by halves) and the table's family fitted with weight mu dw / dw (fit / truth)")
    for mu0 in (float(x) for x in args.mu0.split(",")):
        halves = [sum(half_space_exits(omega, g, mu0, np.vstack([views, probes]), args.photons // 2, seed))
                  for seed in (1, 2)]
        truth = 0.5 * (halves[0] + halves[1])
        spread = 0.5 * abs(halves[0] - halves[1])
        grid, probe_truth = truth[:len(views)], truth[len(views):]
        rows = []
        for name, weight in (("mu dw", views[:, 2] * dw), ("dw", dw)):
            p, model = fit(grid, views, dw, weight)
            share = 1.0 / (1.0 + math.exp(-p[0]))
            elev = math.degrees(MIN_ELEVATION + (0.5 * math.pi - MIN_ELEVATION) / (1.0 + math.exp(-p[2])))
            print(f"  mu0 {mu0:.2f} fit by {name:5s}: share {share:.2f} k_peak {0.95 * math.tanh(p[1]):.2f} "
                  f"elevation {elev:.1f} deg, broad k {0.95 * math.tanh(p[3]):.2f} at {math.degrees(p[4]):.0f} deg")
            rows.append(model(p, probes))
        for e, (mu, a) in enumerate(exits):
            print(f"    mu {mu:.2f} az {a:3.0f}: truth {probe_truth[e]:.3f} ({spread[len(views) + e]:.3f})  "
                  + "  ".join(f"{r[e]:.3f} ({r[e] / probe_truth[e]:.2f})" for r in rows))


if __name__ == "__main__":
    main()
