"""A flat half-space at any angle to the voxel grid against a ball's limb block (docs/benchmarks.md, lit-hg-blend 2).

A 48^3-voxel block of a bench/bake_suite.py case's snow cut by a plane of unit normal --normal (grid axes) through a
point --offset voxels off the block's middle, antialiased as bake_suite.ball is (fill 0.5 - distance / h); the
suite's sun (30 deg up from azimuth 0) alone; --rays x --rays rays along --ray (towards the camera; default the (0, 0)
view's) aimed half a voxel under the plane on a square of --width voxels (default 2 x 2 over 3: +-0.75 voxel; a
staircase's texture averages over whole steps, 1 / tan(tilt) voxels), started ABOVE voxels over it (along its normal),
past the trilinear density's reach (1.5 voxels over the plane): started 1.2 cm along the ray from their aim, as before
lead-93, they began inside that reach at some phases and read the flat top of ball_grey's snow at phase 0.25 1.18
where from above it reads 1.04-1.07. The core's Monte Carlo against the baked render, channel G (the rays' sums). With
a ball block's depth-one normal it is that block without the curvature. --mixed N: the mixed form too (N paths a ray), as
bake_suite.py's mixed rows render it; a thin partial layer over the plane showed it too bright (docs/benchmarks.md,
lead-94).

    PYTHONPATH=build/python /usr/bin/python3 bench/oblique_plane_probe.py --optics ball_grey --normal 0.396,-0.909,-0.13
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

SIDE = 48  # voxels
ABOVE = 2.0  # voxels over the plane (along its normal) where the rays start: past the density's reach


def oblique_density(case, normal, offset):
    h = case.voxel
    X, Y, Z = bake_suite.grid((SIDE, SIDE, SIDE))
    point = np.full(3, (SIDE - 1) / 2 + offset) * h
    distance = (X * h - point[0]) * normal[0] + (Y * h - point[1]) * normal[1] + (Z * h - point[2]) * normal[2]
    fill = np.clip(0.5 - distance / h, 0.0, 1.0)
    inner = np.zeros_like(fill)
    inner[2:-2, 2:-2, 2:-2] = 1.0  # two voxels of air around the block
    return fill * inner * case.density.max(), point


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--optics", default="ball_grey")
    parser.add_argument("--normal", default="0.396,-0.909,-0.13", help="the plane's outward normal (grid axes)")
    parser.add_argument("--offset", type=float, default=0.23, help="voxels: the plane's phase in the grid")
    parser.add_argument("--ray", default="1,0,0", help="towards the camera (grid axes)")
    parser.add_argument("--samples", type=int, default=8192)
    parser.add_argument("--rays", type=int, default=2, help="per side of the square bundle the rays end on")
    parser.add_argument("--width", type=float, default=3.0,
                        help="voxels: the bundle's side (a staircase's texture averages over whole steps)")
    parser.add_argument("--mixed", type=int, default=0,
                        help="paths per ray for the mixed form too (the renderer scattering in the bake's thin traced "
                             "snow, as bake_suite.py's mixed rows; 0: the baked form alone)")
    args = parser.parse_args()
    if args.rays < 1 or args.width < 0.0 or args.samples < 1 or args.mixed < 0:
        parser.error("--rays and --samples at least 1, --width and --mixed not negative")
    case = bake_suite.case(args.optics)
    h = case.voxel
    normal = np.array([float(x) for x in args.normal.split(",")])
    normal /= np.linalg.norm(normal)
    w = np.array([float(x) for x in args.ray.split(",")])
    w /= np.linalg.norm(w)
    if w @ normal <= 0.05:
        parser.error(f"--ray {args.ray} meets the plane from behind or at grazing (ray . normal {w @ normal:.2f} <= 0.05)")
    sun = np.array([math.cos(bake_suite.SUN_ELEVATION), 0.0, math.sin(bake_suite.SUN_ELEVATION)])
    density, point = oblique_density(case, normal, args.offset)
    across = np.cross(normal, [0.0, 0.0, 1.0] if abs(normal[2]) < 0.9 else [1.0, 0.0, 0.0])
    across /= np.linalg.norm(across)
    along = np.cross(normal, across)
    end = point - 0.5 * h * normal
    spots = ((np.arange(args.rays) + 0.5) / args.rays - 0.5) * args.width  # voxels across the bundle
    starts = np.array([end + (x * across + y * along) * h + (ABOVE + 0.5) * h / (w @ normal) * w
                       for x in spots for y in spots])
    ways = np.tile(-w, (len(starts), 1))
    suns = [firncore.SunLight(tuple(sun), (1.0,) * 3, 0.0093)]
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "plane.vdb")
        bake_suite.write_density(path, density, h)
        mean, error = firncore.monte_carlo_radiance(path, case.optics, starts, ways, suns=suns,
                                                    samples=args.samples, seed=11)
        stats = firncore.bake(path, case.optics, suns=suns, quality="FINAL", seed=0)
        baked = firncore.render_baked(path, case.optics, starts, ways)[:, 1]
        if args.mixed:
            scattered = stats["scatter_voxels"]
            mixed, mixed_error = firncore.render_scattering_where_thin(path, case.optics, starts, ways, suns=suns,
                                                                       samples=args.mixed, seed=3, traced_only=True)
    m, b = mean[:, 1].mean(), baked.mean()
    e = math.sqrt((error[:, 1] ** 2).sum()) / len(starts)
    print(f"{args.optics} plane normal {np.round(normal, 3)} offset {args.offset:g}: mu0 {normal @ sun:.2f} "
          f"mu {normal @ w:.2f}: Monte Carlo {m:.4f} (+- {e:.4f}) bake {b:.4f} bake / Monte Carlo {b / m:.3f}")
    if args.mixed:
        x = mixed[:, 1].mean()
        print(f"  mixed {x:.4f} (+- {math.sqrt((mixed_error[:, 1] ** 2).sum()) / len(starts):.4f}) mixed / Monte Carlo "
              f"{x / m:.3f}; the renderer scatters in {scattered} voxels")


if __name__ == "__main__":
    main()
