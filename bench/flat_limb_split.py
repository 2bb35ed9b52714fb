"""The limb's forward deficit split (docs/benchmarks.md, limb-forward): is ball_snow's forward grazing exit short on
a FLAT slab of its snow under the same low suns (then the sun return's form at low mu0 is short), or only on the ball
(then the curvature's transport along the surface past the terminator)?

A wide slab of a bench/bake_suite.py case's snow (--width x --width voxels, --layers deep) under a sun at cosine mu0
to the normal; the sun alone leaving the top's centre towards exit cosines mu whose tangent part lies at an azimuth
off the sun's travel (0 forward, 180 backward), as bench/snow_block_split.py --exits takes them on the ball. Each
exit is an n x n bundle of rays ending on a square of 3 voxels of the top (the bake's voxels averaged), started 1.2 cm
above the top (above its density ramp). The core's Monte Carlo (`firncore.monte_carlo_radiance`) against the baked
render (`firncore.render_baked`), channel G; beside them the exact single scattering of the half-space,
omega E mu0 / (mu0 + mu) HG(g, cos), the rest of the Monte Carlo being the sun's multiple scattering.

    PYTHONPATH=build/python /usr/bin/python3 bench/flat_limb_split.py [--optics ball_grey] [--mu0 0.15,0.3,0.44] \
        [--exits 0.05@29,0.18@90,0.18@209] [--samples 4096]
"""

import argparse
import math
import os
import sys
import tempfile

import numpy as np

import firncore

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bake_suite  # noqa: E402
from bake_halfspace import henyey_greenstein  # noqa: E402

EXITS = "0.05@29,0.18@29,0.4@29,0.18@209"  # mu@azimuth: the exit's tangent part, degrees off the sun's travel
HEIGHT = 0.012  # m: the rays start above the top's ramp (one voxel of 1 cm)


def single_scattering(case, sun, mu0, w):
    """A half-space's exit radiance of the sun (1 W/m^2) scattered once towards w: omega mu0 / (mu0 + mu) HG."""
    return case.omega[1] * mu0 / (mu0 + w[2]) * henyey_greenstein(case.g, float(-sun @ w))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--optics", default="ball_snow", help="the bench/bake_suite.py case whose snow to use")
    parser.add_argument("--width", type=int, default=64, help="voxels across (the lit sides far from the point)")
    parser.add_argument("--layers", type=int, default=16, help="voxels deep")
    parser.add_argument("--mu0", default="0.15,0.3,0.44", help="the sun's cosines to the normal")
    parser.add_argument("--samples", type=int, default=4096, help="Monte Carlo paths per ray")
    parser.add_argument("--n", type=int, default=2, help="rays per side of each bundle")
    parser.add_argument("--top-fill", type=float, default=0.0,
                        help="fill of one partly filled layer over the top (0: none; the exits end on it)")
    parser.add_argument("--exits", default=EXITS,
                        help="exits as mu@azimuth, the azimuth of the exit's tangent part off the sun's travel in "
                             "degrees (0 forward, 180 backward; the ball's forward limb: 27-31)")
    args = parser.parse_args()
    case = bake_suite.case(args.optics)
    h = case.voxel
    density = bake_suite.slab(args.width, args.layers) * case.density.max()
    if args.top_fill > 0.0:  # a partly filled layer over the top, as the balls' antialiased surface has
        density[2:-2, 2:-2, 2 + args.layers] = args.top_fill * case.density.max()
    exits = [tuple(float(x) for x in e.split("@")) for e in args.exits.split(",")]
    top = bake_suite.slab_top(density, args.layers + (args.top_fill > 0.0), h)  # the exits end on the top layer
    offsets = ((np.arange(args.n) + 0.5) / args.n * 2.0 - 1.0) * 1.5 * h
    print(f"flat slab of {args.optics} ({args.width} x {args.width} x {args.layers} voxels, top fill "
          f"{args.top_fill:g}), sun alone, leaving the "
          f"top: Monte Carlo (+-), of it once, bake, bake / Monte Carlo; {args.samples} "
          f"paths per ray, "
          f"{args.n ** 2} rays")
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "slab.vdb")
        for mu0 in (float(x) for x in args.mu0.split(",")):
            sun = np.array([math.sqrt(1.0 - mu0 * mu0), 0.0, mu0])  # towards the sun; its light travels along -x
            suns = [firncore.SunLight(tuple(sun), (1.0,) * 3, 0.0093)]
            starts, ways, once = [], [], []
            for mu, azimuth in exits:
                a, along = math.radians(azimuth), math.sqrt(1.0 - mu * mu)
                w = np.array([-along * math.cos(a), along * math.sin(a), mu])  # towards the camera
                once.append(single_scattering(case, sun, mu0, w))
                for x in offsets:
                    for y in offsets:
                        starts.append(top + np.array([x, y, 0.0]) + HEIGHT / mu * w)
                        ways.append(-w)
            starts, ways = np.array(starts), np.array(ways)
            bake_suite.write_density(path, density, h)
            mean, error = firncore.monte_carlo_radiance(path, case.optics, starts, ways, suns=suns,
                                                        samples=args.samples, seed=11)
            firncore.bake(path, case.optics, suns=suns, quality="FINAL", seed=0)
            baked = firncore.render_baked(path, case.optics, starts, ways)[:, 1]
            rays = args.n ** 2
            for e, (mu, azimuth) in enumerate(exits):
                part = slice(e * rays, (e + 1) * rays)
                m = mean[part, 1].mean()
                err = math.sqrt((error[part, 1] ** 2).sum()) / rays
                b = baked[part].mean()
                print(f"  mu0 {mu0:.2f}  mu {mu:.2f} az {azimuth:3.0f}: {m:.4f} ({err:.4f})  {once[e]:.4f}  {b:.4f}  "
                      f"{b / m:.2f}")


if __name__ == "__main__":
    main()
