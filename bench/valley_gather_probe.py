"""The light arriving at bumpy_plate's surface points from each direction of their hemisphere: the bake's render
(`firncore.render_baked`, what a gather from that point reads) against the core's Monte Carlo (all orders), sun
alone (docs/benchmarks.md, "plate-near 2"). Points --height voxels (1.5) out along the surface's normal over a valley's
centre, a slope facing the sun and one facing away, away from the plate and the cut sides. Per point and per band
of mu (the cosine to the normal): the irradiance share and the bake's error; and the whole irradiance.

    PYTHONPATH=build/python:bench python3 bench/valley_gather_probe.py [--samples 512] [--azimuths 12] [--height 1.5]
"""

import argparse
import copy
import math
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore
from limb_circle import frame

# (name, x, y) in voxels: s = sin(2 pi x / 14) cos(2 pi y / 11) is -1 at the valleys' centres
POINTS = [("valley a", 3.5, 16.5), ("valley b", 24.5, 11.0), ("valley c", 24.5, 22.0),
          ("side to sun", 7.0, 22.0), ("side away", 7.0, 5.5)]
MU = np.array([0.1, 0.3, 0.5, 0.7, 0.9])  # band centres, width 0.2


def surface(x, y, depth=6.0, amplitude=3.0):
    """The top's height (voxels) and unit normal at (x, y) (bake_suite.bumpy's sine)."""
    a, b = 2 * np.pi / bs.BUMPS[0], 2 * np.pi / bs.BUMPS[1]
    top = bs.bumpy_top(x, y, depth, amplitude)
    gx = amplitude * a * math.cos(a * x) * math.cos(b * y)
    gy = -amplitude * b * math.sin(a * x) * math.sin(b * y)
    n = np.array([-gx, -gy, 1.0])
    return top, n / np.linalg.norm(n)


def hemisphere(n, azimuths):
    t, b, _ = frame(n)
    out = []
    for mu in MU:
        s = math.sqrt(1 - mu * mu)
        for k in range(azimuths):
            phi = 2 * np.pi * (k + 0.5) / azimuths
            out.append(mu * n + s * (math.cos(phi) * t + math.sin(phi) * b))
    return np.array(out)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=512)
    parser.add_argument("--azimuths", type=int, default=12)
    parser.add_argument("--height", type=float, default=1.5, help="the points' distance out along the normal, voxels")
    parser.add_argument("--out", default=os.path.join(tempfile.gettempdir(), "valley_gather_probe"))
    args = parser.parse_args()
    case = copy.copy(bs.case("bumpy_plate"))
    case.sky = 0.0
    os.makedirs(args.out, exist_ok=True)
    path = os.path.join(args.out, "plate.vdb")
    bs.write_density(path, case.density, case.voxel)
    h = case.voxel
    origins, directions = [], []
    for _, x, y in POINTS:
        top, n = surface(x, y)
        p = (np.array([x, y, top]) + args.height * n) * h
        for w in hemisphere(n, args.azimuths):
            origins.append(p), directions.append(w)
    origins, directions = np.array(origins), np.array(directions)
    file = os.path.join(args.out, f"mc_{args.samples}_{args.azimuths}_{args.height:g}.npz")
    if not os.path.exists(file):
        mean, error = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                                    occluders=case.occluders, samples=args.samples, seed=11)
        np.savez(file, mean=mean, error=error)
    truth = np.load(file)["mean"][:, 1]
    firncore.bake(path, case.optics, suns=case.suns(), occluders=case.occluders, quality="FINAL", seed=0)
    baked = firncore.render_baked(path, case.optics, origins, directions, occluders=case.occluders)[:, 1]
    per = len(MU) * args.azimuths
    print("point          E truth  E bake  error  | per mu band: share of E truth, bake error (%)")
    for i, (name, _, _) in enumerate(POINTS):
        t = truth[i * per:(i + 1) * per].reshape(len(MU), -1) * MU[:, None]
        b = baked[i * per:(i + 1) * per].reshape(len(MU), -1) * MU[:, None]
        scale = 2 * np.pi * 0.2 / args.azimuths  # W/m^2 per (radiance x mu) sample
        et, eb = scale * t.sum(), scale * b.sum()
        bands = "  ".join(f"{mu:.1f}: {100 * t[j].sum() / t.sum():4.0f} " +
                          (f"{100 * (b[j].sum() / t[j].sum() - 1):+5.1f}" if t[j].sum() > 0 else "    -")
                          for j, mu in enumerate(MU))
        print(f"{name:<13} {et:7.4f} {eb:7.4f} {100 * (eb / et - 1):+6.1f}  | {bands}")


if __name__ == "__main__":
    main()
