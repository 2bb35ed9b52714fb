"""A flat slab of a suite snow under a sun alone: the baked radiance per exit direction against the core's Monte Carlo
(docs/benchmarks.md, grey-lit): is the ball's lit face error the flat surface's own (the bake's exit law at this
snow) or the ball's (its curvature and staircase)?

A wide slab (24 x 24 voxels of 1 cm, 6 deep) of the snow (omega, g, tau per voxel) under a sun at each mu0; camera
rays aimed at four points a quarter voxel apart round the top's middle, for exit cosines mu and azimuths from the
sun's side (0: back towards the sun) to 180 (forward): baked (`firncore.render_baked`, FINAL) and the Monte Carlo
(`firncore.monte_carlo_radiance`, --samples paths), channel G, the four points summed (in brackets the Monte Carlo's mean radiance, W/(m² sr) per W/m² of sun).

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/grey_flat_exit.py [--omega 0.9 --g 0.6 --tau 5]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--omega", type=float, default=0.9)
    parser.add_argument("--g", type=float, default=0.6)
    parser.add_argument("--tau", type=float, default=5.0, help="optical depth per voxel")
    parser.add_argument("--mu0", default="0.3,0.5,0.8,1.0")
    parser.add_argument("--samples", type=int, default=8192)
    args = parser.parse_args()
    h, width, layers = 0.01, 24, 6
    density = bake_suite.slab(width, layers) * 100.0
    optics = firncore.VolumeOptics(args.tau / h / 100.0, (args.omega,) * 3, args.g)
    top = bake_suite.slab_top(density, layers, h) + np.array([0.0, 0.0, 0.5 * h])
    offsets = [np.array([dx, dy, 0.0]) * h for dx in (-0.125, 0.125) for dy in (-0.125, 0.125)]
    exits = [(mu, az) for mu in (0.2, 0.4, 0.6, 0.8, 1.0) for az in ((0.0,) if mu == 1.0 else (0.0, 90.0, 180.0))]
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "slab.vdb")
        bake_suite.write_density(path, density, h)
        print(f"omega {args.omega} g {args.g} tau {args.tau}/voxel; baked / Monte Carlo (G), four points; "
              f"exit (mu, azimuth from the sun's side)")
        for mu0 in (float(x) for x in args.mu0.split(",")):
            s0 = math.sqrt(1.0 - mu0 * mu0)
            sun = firncore.SunLight((s0, 0.0, mu0), (1.0,) * 3, 0.0093)
            firncore.bake(path, optics, suns=[sun], quality="FINAL", seed=0)
            origins, directions = [], []
            for mu, az in exits:
                s, a = math.sqrt(1.0 - mu * mu), math.radians(az)
                back = np.array([s * math.cos(a), s * math.sin(a), mu])
                for o in offsets:
                    origins.append(top + o + 0.3 * back), directions.append(-back)
            origins, directions = np.array(origins), np.array(directions)
            baked = firncore.render_baked(path, optics, origins, directions)[:, 1].reshape(len(exits), -1).sum(1)
            mc, err = firncore.monte_carlo_radiance(path, optics, origins, directions, suns=[sun],
                                                    samples=args.samples, seed=5)
            mc = mc[:, 1].reshape(len(exits), -1).sum(1)
            err = np.sqrt((err[:, 1] ** 2).reshape(len(exits), -1).sum(1))
            print(f"  mu0 {mu0:.2f}: " + "  ".join(
                f"({mu:.1f},{az:3.0f}) {b / m:5.3f}±{e / m:.3f} [{m / 4:.4f}]" for (mu, az), b, m, e in zip(exits, baked, mc, err)),
                flush=True)


if __name__ == "__main__":
    main()
