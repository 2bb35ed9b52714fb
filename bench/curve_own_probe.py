"""The own sunlit light of a corrugation (bumpy_plate's sine along x alone) against a flat slab of the same snow under
the same sun (docs/benchmarks.md, curve-own): the bake's with no gather, or the core Monte Carlo's with every path ended
at its first flight between two snow collisions through density at or under --cut x the largest (0: air alone, the
"strictest own light" of valley-answer). Per point, from VIEWS, channel G, over the flat slab's.

Needs the temporary hooks of bench/curve_own_hooks.diff (valley-answer's hooks, and FIRN_CUT_DENSITY,
FIRN_ORDER_MIN / FIRN_ORDER_MAX: the Monte Carlo's scattering orders kept; the bake's switches FIRN_SUN_DEEP,
FIRN_NO_AVG, FIRN_NO_DRIFT, FIRN_SHAPE_U, FIRN_EXIT_WHOLE, FIRN_EXIT_PATCH, FIRN_AREA_FOOTPRINT, FIRN_RB,
FIRN_RAMP_SCALE, FIRN_LAT_SCALE, set in the environment; and fringe-node's: FIRN_FILL_DEPTH k, a surface voxel of
fill f (its density over its 3^3 block's largest) under FIRN_FILL_MAX (default 1) has its air faces' ramp k (1 - f) of a
full voxel's resistance longer; FIRN_FILL_SIDE c, its air faces at a cosine to the patch's normal under c extrapolate
at full density (ramp / f); FIRN_FRINGE_RAMP s, the fringe's part of an air face's ramp (past the voxel's own half)
times s, -1 the face's cosine to the normal). --profile: every column's centre across a period from the
normal instead of valley, crest and the two views.

    PYTHONPATH=build/python /usr/bin/python3 bench/curve_own_probe.py [--period 14] [--lift 0] [--scale 1]
        [--truth PATHS [--cut 0]] [--profile] [--sun 90:30]
"""
import argparse
import copy
import math
import os
import sys
import tempfile

import numpy as np

import firncore

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bake_suite as bs  # noqa: E402
import concave_split_probe as cs  # noqa: E402
import probe_hooks  # noqa: E402


def fill_under(top, shape):
    """Fill (0-1) under `top(x)` (voxels), antialiased along z, its borders empty as the corrugation's."""
    X, _, Z = bs.grid(shape)
    fill = np.clip(top(X) - Z + 0.5, 0.0, 1.0)
    fill[:, :, 0] = 0.0
    fill[:2], fill[-2:], fill[:, :2], fill[:, -2:] = 0.0, 0.0, 0.0, 0.0
    return fill


def own_light(fill, h, case, suns, points, top, views, truth):
    """The own light (channel G) at `points` from `views`, (points, views): the bake's with no gather, or with `truth`
    (paths, cut as a share of the largest density) the Monte Carlo's."""
    origins, directions = cs.camera_rays(points, top, views, h)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "snow.vdb")
        bs.write_density(path, fill * case.density.max(), h)
        if truth:
            paths, cut = truth
            os.environ.update(FIRN_CUT_AIR="0.1", FIRN_CUT_COUNT="0",
                              FIRN_CUT_DENSITY=f"{cut * case.density.max()}")
            radiance = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=suns,
                                                     samples=paths, seed=11)[0]
        else:
            os.environ["FIRN_BOUNCES"] = "0"
            firncore.bake(path, case.optics, suns=suns, quality="FINAL", seed=0)
            radiance = firncore.render_baked(path, case.optics, origins, directions)
    return radiance[:, 1].reshape(len(points), len(views), 9).mean(axis=2)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--period", type=float, default=bs.BUMPS[0], help="voxels")
    parser.add_argument("--lift", type=float, default=0.0, help="both shapes raised by this (voxels)")
    parser.add_argument("--scale", type=int, default=1, help="the same shapes on voxels this many times finer")
    parser.add_argument("--sun", default="90:30", help="AZ:EL (deg)")
    parser.add_argument("--truth", type=int, default=0, help="the Monte Carlo's own light with this many paths")
    parser.add_argument("--cut", type=float, default=0.0, help="its air: density at most this share of the largest")
    parser.add_argument("--profile", action="store_true")
    args = parser.parse_args()
    probe_hooks.require_hooks("curve_own_hooks.diff")
    case = copy.copy(bs.case("bumpy_plate"))
    k, h = args.scale, case.voxel / args.scale
    a, e = (math.radians(float(v)) for v in args.sun.split(":"))
    suns = [firncore.SunLight((math.cos(a) * math.cos(e), math.sin(a) * math.cos(e), math.sin(e)), (1.0,) * 3, 0.0093)]
    truth = (args.truth, args.cut) if args.truth else None
    shape = cs.corrugation(args.period, k, False).shape
    top = lambda x: cs.corrugation_top(x, args.period, k) + k * args.lift  # noqa: E731
    level = k * (6.0 + args.lift)
    if args.profile:
        views = [(0, 89)]
        points = [(f"{x:.1f}", k * x, k * 12.0) for x in np.arange(0.25, 1.26, 1.0 / args.period) * args.period]
    else:
        views = [(0, 89), (90, 60)]
        points = [(name, k * u * args.period, k * 12.0) for name, u in (("valley", 0.75), ("crest", 1.25))]
    curved = own_light(fill_under(top, shape), h, case, suns, points, lambda x, y: top(x), views, truth)
    flat = own_light(fill_under(lambda x: level + 0.0 * x, shape), h, case, suns, points[-1:], lambda x, y: level,
                     views, truth)[0]
    print(f"flat slab {' / '.join(f'{v:.4f}' for v in flat)}   (views {views})")
    if args.profile:
        print("x (voxels)  " + " ".join(f"{name:>5s}" for name, _, _ in points))
        print("/ flat      " + " ".join(f"{r[0] / flat[0]:5.2f}" for r in curved))
        return
    for (name, _, _), r in zip(points, curved):
        print(f"{name:<7s} {' / '.join(f'{v:.4f}' for v in r)}   / flat {' / '.join(f'{v:.3f}' for v in r / flat)}")


if __name__ == "__main__":
    main()
