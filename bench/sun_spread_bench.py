"""The sun's light on a lump behind another, against the core's Monte Carlo (branch sun-spread, docs/benchmarks.md
"sun-spread").

Two lumps as the skier sample's (lumps_between_bench.lump(): 1.2 cm balls on 1 cm voxels, 40 optical depths per
voxel at the centre, g 0.845) in line with a sun 26.6 degrees high (towards (2, 0, 1)), A towards the sun and B k (2, 0, 1) cm behind it, over a
black ground, 400 far lumps putting them over the tracing budget (light tracing off: the diffusion takes every lump). B
is seen from 14 directions, its disk of pixels from just outside it; B alone, then with A in front at each
separation: baked (DRAFT) / Monte Carlo - 1, and the share of B's light A leaves it, baked and Monte Carlo. The
beams onto B's sunlit patches cross A: what A scatters forwards reaches B in full when B lies right behind, a
fraction further off (bake.md Method 2). Usage:
  PYTHONPATH=build/python /usr/bin/python3 bench/sun_spread_bench.py [--steps 1,2,3,5] [--cache DIR]
"""

import argparse
import os
import tempfile
import time

import numpy as np

from lumps_between_bench import H, lump, measure, plane, views_of


TOWARDS_SUN = np.array([2, 0, 1])  # voxels


def pair_density(steps):
    """B's corner at index m, A `steps` times TOWARDS_SUN from it (0: none), 400 far lumps beside them."""
    piece = lump()
    s = piece.shape[0]
    m, far, step = s + 2, 20, s + 5
    a = np.array([m, m, m]) + steps * TOWARDS_SUN
    density = np.zeros((a[0] + s + 2, 2 * m + 60 + far * step, max(a[2] + s + 2, far * step)))
    corners = [np.array([m, m, m])] + ([a] if steps else [])
    corners += [np.array([0, 2 * m + 60 + j * step, k * step]) for j in range(far) for k in range(far)]
    for c in corners:
        box = tuple(slice(a, a + s) for a in c)
        density[box] = np.maximum(density[box], piece)
    return density, (np.array([m, m, m]) + (s - 1) / 2) * H, 0.55 * s * H


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", default="1,2,3,5", help="A's centre ahead of B's, in steps of (2, 0, 1) cm")
    parser.add_argument("--samples", type=int, default=64, help="Monte Carlo paths per pixel")
    parser.add_argument("--pixels", type=int, default=8, help="across B's disk per view")
    parser.add_argument("--cache", default=None, help="keep and reuse the Monte Carlo's sums in this folder")
    args = parser.parse_args()
    import firncore

    folder = tempfile.mkdtemp()
    if args.cache:
        os.makedirs(args.cache, exist_ok=True)
    path = os.path.join(folder, "pair.vdb")
    sun = dict(suns=[firncore.SunLight(tuple(TOWARDS_SUN / np.linalg.norm(TOWARDS_SUN)), (1.0,) * 3, 0.0093)], sky=firncore.Sky((0.0,) * 3))
    ground = [plane(-0.05, 0.0)]
    start = time.time()
    print(f"samples {args.samples} per pixel; B's light baked / Monte Carlo - 1 (noise); B behind A / B alone")
    alone = None
    for steps in [0] + [int(k) for k in args.steps.split(",")]:
        density, centre, radius = pair_density(steps)
        origins, directions = views_of(centre, radius, 14, args.pixels)
        cached = os.path.join(args.cache, f"pair_{steps}_{args.pixels}_{args.samples}.json") if args.cache else None
        b, m, e = measure(firncore, path, density, origins, directions, sun, ground, args.samples, cached)
        if not steps:
            alone = (b, m)
            print(f"  B alone: {100 * (b / m - 1):+.1f} % ({100 * e / m:.1f})", flush=True)
            continue
        print(f"  A {steps * np.linalg.norm(TOWARDS_SUN):4.1f} cm ahead: {100 * (b / m - 1):+.1f} % ({100 * e / m:.1f}); B keeps baked "
              f"{b / alone[0]:.3f}, Monte Carlo {m / alone[1]:.3f}", flush=True)
    print(f"{time.time() - start:.0f} s wall, load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
