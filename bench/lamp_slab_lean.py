"""A near lamp over a flat slab seen from one side: the lit face's lean along the surface against the core's Monte Carlo
(docs/benchmarks.md, grey-lamps2).

A point lamp `--height` over the middle of a flat slab (bake_suite.slab(40, 6), voxels of 1 cm); the camera looks down
at 45 degrees from +y. Points on the top along y (x = 0) lie on the camera's side of the point under the lamp (y > 0,
whose light flows away from the lamp's foot, towards the camera) or beyond it (y < 0, flowing away from the camera);
along x (y = 0) the flow crosses the view. Per point: baked / Monte Carlo; then the lean, the ratio of the two sides'
radiance at equal |y|, bake against truth. Under a sun the slab has no lean: the lamp's falling irradiance makes it.

    PYTHONPATH=build/python python3 bench/lamp_slab_lean.py [--snow grey|issue] [--height 0.03] [--samples 4096]
        [--voxel 0.005]  (the same slab, 40 x 40 x 6 cm, and snow per metre on finer voxels)
"""

import argparse
import math
import os
import tempfile

import numpy as np

import firncore
import bake_suite

SNOWS = {"grey": (0.9, 0.6, 5.0), "issue": (0.98, 0.85, 10.0)}  # omega, g, optical depth per cm


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--snow", default="grey", choices=sorted(SNOWS))
    parser.add_argument("--height", type=float, default=0.03, help="m, the lamp over the top, less half a cm")
    parser.add_argument("--samples", type=int, default=4096)
    parser.add_argument("--voxel", type=float, default=0.01, help="m")
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_lamp_slab_lean"))
    args = parser.parse_args()
    omega, g, tau = SNOWS[args.snow]
    h = args.voxel
    per_cm = round(0.01 / h)
    layers = 6 * per_cm
    density = bake_suite.slab(40 * per_cm, layers) * 100.0
    optics = firncore.VolumeOptics(tau / 0.01 / 100.0, (omega,) * 3, g)  # tau per cm
    os.makedirs(args.cache, exist_ok=True)
    path = os.path.join(args.cache, f"slab_{h}.vdb")
    bake_suite.write_density(path, density, h)
    top = bake_suite.slab_top(density, layers, h) + [0.0, 0.0, h / 2]  # the surface
    # the height over the 1 cm slab's top layer's centre, as the tests take it
    lamp = firncore.Lamp("POINT", tuple(top + [0.0, 0.0, args.height - 0.005]), (1.0,) * 3)
    view = np.array([0.0, -math.sqrt(0.5), -math.sqrt(0.5)])
    offsets = np.arange(-7, 8) * 0.01
    points = [top + [0.0, y, 0.0] for y in offsets] + [top + [x, 0.0, 0.0] for x in offsets]
    origins, directions = np.array(points) - 0.5 * view, np.tile(view, (len(points), 1))
    file = os.path.join(args.cache, f"{args.snow}_{args.height}_{args.samples}_{h}.npy")
    if os.path.exists(file):
        reference = np.load(file)
    else:
        reference, _ = firncore.monte_carlo_radiance(path, optics, origins, directions, lamps=[lamp],
                                                     samples=args.samples, seed=11)
        np.save(file, reference)
    firncore.bake(path, optics, lamps=[lamp], quality="FINAL", seed=0)
    baked = firncore.render_baked(path, optics, origins, directions)
    ratio = baked[:, 1] / reference[:, 1]
    n = len(offsets)
    print(f"{args.snow} snow, voxel {h * 100:g} cm, point lamp {args.height * 100:.0f} cm up, {args.samples} paths; "
          "baked / Monte Carlo - 1 (%)")
    print("offset cm    " + " ".join(f"{o * 100:+5.0f}" for o in offsets))
    print("along y      " + " ".join(f"{100 * (r - 1):+5.1f}" for r in ratio[:n]))
    print("along x      " + " ".join(f"{100 * (r - 1):+5.1f}" for r in ratio[n:]))
    half = n // 2
    lean = lambda v: v[half + 1:n] / v[half - 1::-1]  # the camera's side over the far side, |y| 1..7 cm
    print("lean truth   " + " " * 36 + " ".join(f"{v:5.2f}" for v in lean(reference[:n, 1])))
    print("lean baked   " + " " * 36 + " ".join(f"{v:5.2f}" for v in lean(baked[:n, 1])))
    print(f"bias along y {100 * (baked[:n, 1].sum() / reference[:n, 1].sum() - 1):+.1f} %, "
          f"along x {100 * (baked[n:, 1].sum() / reference[n:, 1].sum() - 1):+.1f} %")


if __name__ == "__main__":
    main()
