"""Concave snow's light split into the snow's own light and the light that crossed the air, the bake against the core's
Monte Carlo (docs/benchmarks.md, valley-answer). Needs the temporary hooks of bench/valley_answer_hooks.diff applied to
the core (`git apply`): FIRN_CUT_AIR / FIRN_CUT_COUNT end a Monte Carlo path at its (COUNT + 1)-th flight between two
snow collisions that crosses more than CUT_AIR voxels of air; FIRN_BOUNCES overrides the bake's gathers.

Per point (9 camera rays over +-1 voxel about it) and view (azimuth:elevation, deg), channel G: the truth's own light
(air cut 1 voxel), its light crossing at most once, all of it; the bake's own light (no gather) and each --gathers
count, each against the truth's at most one crossing, and its gathered part over the truth's crossing part.

Shapes: bumpy_plate (its valleys b, c), or --corrugation: bumpy_plate's sine along x alone (--period, 14 voxels as
bumpy_plate's; --scale: the same shape on voxels that many times finer; no occluders; valleys v1, v2 and a crest),
filled along z or (--normal-fill) along the normal. Light: bumpy_plate's sun alone, --sun AZ:EL, or --sky (uniform,
alone).

    PYTHONPATH=build/python /usr/bin/python3 bench/concave_split_probe.py [--corrugation] [--normal-fill]
        [--period 14] [--scale 1] [--sun 90:30 | --sky] [--views 0:60,0:89,90:60,180:50]
        [--gathers 1,2] [--samples 1024]
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
import probe_hooks  # noqa: E402
import valley_gather_probe as vg  # noqa: E402

def corrugation_top(x, period, scale):
    """bumpy_plate's sine along x (voxels), on voxels `scale` times finer."""
    return scale * (6 + 3 * np.sin(2 * np.pi * x / (scale * period)))


def corrugation(period, scale, normal_fill):
    """Fill (0-1) under corrugation_top over 2 periods + 16 voxels along x, 24 along y (times `scale`), antialiased
    along z (bumpy's staircase) or along the normal."""
    X, Y, Z = bs.grid(tuple(int(scale * n) for n in (2 * period + 16, 24, 12)))
    depth = corrugation_top(X, period, scale) - Z
    if normal_fill:
        slope = 3 * 2 * np.pi / period * np.cos(2 * np.pi * X / (scale * period))
        depth = depth / np.sqrt(1 + slope ** 2)
    fill = np.clip(depth + 0.5, 0.0, 1.0)
    fill[:, :, 0] = 0.0
    fill[:2], fill[-2:], fill[:, :2], fill[:, -2:] = 0.0, 0.0, 0.0, 0.0
    return fill


def camera_rays(points, top, views, h):
    origins, directions = [], []
    for _, x, y in points:
        for az, el in views:
            a, e = math.radians(az), math.radians(el)
            w = np.array([math.cos(a) * math.cos(e), math.sin(a) * math.cos(e), math.sin(e)])
            for dx in (-1, 0, 1):
                for dy in (-1, 0, 1):
                    origins.append(np.array([x + dx, y + dy, top(x + dx, y + dy)]) * h + 0.3 * w)
                    directions.append(-w)
    return np.array(origins), np.array(directions)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--corrugation", action="store_true")
    parser.add_argument("--normal-fill", action="store_true")
    parser.add_argument("--period", type=float, default=bs.BUMPS[0], help="the corrugation's (voxels)")
    parser.add_argument("--scale", type=int, default=1, help="the corrugation on voxels this many times finer")
    parser.add_argument("--sun", help="AZ:EL (deg) instead of bumpy_plate's sun")
    parser.add_argument("--sky", action="store_true", help="a uniform sky alone")
    parser.add_argument("--views", default="0:60,0:89,90:60,180:50")
    parser.add_argument("--gathers", default="1,2")
    parser.add_argument("--samples", type=int, default=1024)
    args = parser.parse_args()
    probe_hooks.require_hooks("valley_answer_hooks.diff")
    case = copy.copy(bs.case("bumpy_plate"))
    scale = args.scale if args.corrugation else 1
    h = case.voxel / scale
    suns, sky = case.suns(), None
    if args.sun:
        a, e = (math.radians(float(v)) for v in args.sun.split(":"))
        suns = [firncore.SunLight((math.cos(a) * math.cos(e), math.sin(a) * math.cos(e), math.sin(e)), (1.0,) * 3,
                                  0.0093)]
    if args.sky:
        suns, sky = [], firncore.Sky((1.0,) * 3)
    if args.corrugation:
        density, occluders = corrugation(args.period, scale, args.normal_fill) * case.density.max(), []
        top = lambda x, y: corrugation_top(x, args.period, scale)  # noqa: E731
        points = [(name, scale * u * args.period, scale * 12.0)
                  for name, u in (("valley v1", 0.75), ("valley v2", 1.75), ("crest", 1.25))]
    else:
        density, occluders = case.density, case.occluders
        points, top = [p for p in vg.POINTS if p[0] in ("valley b", "valley c")], lambda x, y: bs.bumpy_top(x, y, 6, 3)
    views = [tuple(int(v) for v in s.split(":")) for s in args.views.split(",")]
    origins, directions = camera_rays(points, top, views, h)

    def per_view(radiance):
        return radiance[:, 1].reshape(len(points), len(views), 9).mean(axis=2)

    def truth(air, count):
        os.environ["FIRN_CUT_AIR"], os.environ["FIRN_CUT_COUNT"] = f"{air}", f"{count}"
        return per_view(firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=suns, sky=sky,
                                                      occluders=occluders, samples=args.samples, seed=11)[0])

    def bake(gathers):
        os.environ["FIRN_BOUNCES"] = f"{gathers}"
        firncore.bake(path, case.optics, suns=suns, sky=sky, occluders=occluders, quality="FINAL", seed=0)
        return per_view(firncore.render_baked(path, case.optics, origins, directions, occluders=occluders))

    gathers = [int(n) for n in args.gathers.split(",")]
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "snow.vdb")
        bs.write_density(path, density, h)
        own, one, everything = truth(scale, 0), truth(scale, 1), truth(0.0, 0)  # the cut: a coarse voxel of air
        baked_own = bake(0)
        baked = [bake(n) for n in gathers]
    print(f"{'point':<10s} {'view':>8s} | truth own    one    all | bake own | " +
          " | ".join(f"{n} gathers, vs one, gathered/crossing" for n in gathers))
    for i, (name, _, _) in enumerate(points):
        for j, (az, el) in enumerate(views):
            line = (f"{name:<10s} {f'({az},{el})':>8s} | {own[i, j]:9.4f} {one[i, j]:6.4f} {everything[i, j]:6.4f} | "
                    f"{baked_own[i, j]:.4f} {100 * (baked_own[i, j] / own[i, j] - 1):+4.0f}%")
            for b in baked:
                ratio = (b[i, j] - baked_own[i, j]) / (one[i, j] - own[i, j])
                line += f" | {b[i, j]:.4f} {100 * (b[i, j] / one[i, j] - 1):+6.1f}% {ratio:5.2f}"
            print(line)


if __name__ == "__main__":
    main()
