"""bumpy_plate's error by the ground's albedo (docs/benchmarks.md, "plate-valleys"): the snow's optics are grey, so
the ground's three channels set to --albedo (0, 0.45, 0.9 by default) give three grounds in one Monte Carlo and one
bake. Blocks in three groups: the edge columns (each view's first and last pixel column: rays along the layer's
cut sides 0.35 voxel outside its outer voxel centres, meeting the top at its cut edge), the shadowed wall (rays whose
depth-one point lies past the layer's -x cut side, x < -h/4: the wall the sun does not light, seen from (180, 50)),
and the rest. Per group and channel: the bias (sum baked / sum reference - 1), the mean |relative error|, and the
truth's and the bake's gain from the darkest ground to the brightest (their radiance ratio).

Lights: "sky" or "sun" alone, "full" both; the core's Monte Carlo of --samples paths (seed 11) cached in --cache.

    PYTHONPATH=build/python /usr/bin/python3 bench/plate_ground_albedo.py [--lights sky,sun] [--albedo 0,0.45,0.9]
        [--samples 2048] [--cache DIR]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore
from plate_err_regions import light_case


def groups(case, origins, hit, seen):
    """Masks of the edge columns, the shadowed -x wall and the rest (the module's docstring)."""
    column = np.arange(len(origins)) % case.pixels
    edge = seen & ((column == 0) | (column == case.pixels - 1))
    wall = seen & ~edge & (np.nan_to_num(hit[:, 0], nan=1.0) < -0.25 * case.voxel)
    return [("edge columns", edge), ("shadowed wall", wall), ("the rest", seen & ~edge & ~wall)]


def over_ground(case, light, albedo):
    """The case under `light` alone (light_case) with its ground's albedo set to `albedo` (R, G, B)."""
    c = light_case(case, light)
    plate, ground = c.occluders
    c.occluders = [plate, (ground[0], ground[1], albedo)]
    return c


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--lights", default="sky,sun")
    parser.add_argument("--albedo", default="0,0.45,0.9", help="the ground's albedo in R, G, B")
    parser.add_argument("--samples", type=int, default=2048)
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_plate_ground"))
    args = parser.parse_args()
    albedo = tuple(float(a) for a in args.albedo.split(","))
    case = bs.case("bumpy_plate")
    origins, directions, tau = bs.views(case)
    seen = tau >= 1.0
    hit = bs.depth_one_points(case, origins, directions, seen)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "bumpy.vdb")
        bs.write_density(path, case.density, case.voxel)
        for light in args.lights.split(","):
            c = over_ground(case, light, albedo)
            file = os.path.join(args.cache, f"{light}_{args.albedo}_{args.samples}.npz")
            truth, error, _ = bs.cached_monte_carlo(file, c, path, origins, directions, args.samples, seed=11)
            firncore.bake(path, c.optics, suns=c.suns(), sky=c.skies(), occluders=c.occluders, quality="FINAL", seed=0)
            baked = firncore.render_baked(path, c.optics, origins, directions, occluders=c.occluders)
            noise = np.median(error[seen] / truth[seen])
            print(f"{light} alone, ground albedo {albedo} (R, G, B), {args.samples} paths, median noise "
                  f"{100 * noise:.1f} %")
            print(f"  {'group':14s} {'px':>3s}   bias R, G, B             mean |error| R, G, B     "
                  f"gain dark -> bright ground: truth, bake")
            for name, m in groups(case, origins, hit, seen):
                bias = 100 * (baked[m].sum(0) / truth[m].sum(0) - 1)
                mean = 100 * np.abs(baked[m] / truth[m] - 1).mean(0)
                dark, bright = int(np.argmin(albedo)), int(np.argmax(albedo))
                gain = [x[m, bright].sum() / x[m, dark].sum() for x in (truth, baked)]
                print(f"  {name:14s} {m.sum():3d}   " + " ".join(f"{b:+6.1f}" for b in bias) + " %      " +
                      " ".join(f"{e:5.1f}" for e in mean) + f" %        {gain[0]:.2f}, {gain[1]:.2f}")


if __name__ == "__main__":
    main()
