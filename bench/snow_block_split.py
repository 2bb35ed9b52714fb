"""One suite block's light cell by cell along its camera ray, split into the sun's single scattering and the rest
(docs/benchmarks.md, snow-block): ball_snow's worst block, view (180 deg, 0 deg), the third row's outer blocks.

The ray is cut where it crosses the voxel cells' faces (bench/ray_depth_split.py's cuts); what a cell [a, b] sends to
the camera is T(a) L(a) - T(b) L(b), L the radiance of a ray started there: the baked render's (its grids whole and
with the peaked lobes' grids firn_source_peak* cleared: the peak's part; and a bake of the sun alone: its sun), the
core's Monte Carlo's (sun and sky; and the sun alone, the sky the difference). The sun's single scattering in the
cell is exact: the trilinear density, midpoint rule on 0.25 mm steps, the sun's uncollided transmittance marched on
0.5 mm steps, Henyey-Greenstein at the ray's angle to the sun's travel; the rest of the Monte Carlo's sun alone is
its multiple scattering (sun more). Per cell also the voxel's density and mu0, the sun's cosine to the ball's normal
there (the ball's centre to the voxel).
--exits: the sun alone leaving the limb along the block's ray, by direction (exits' docstring).

    PYTHONPATH=build/python python3 bench/snow_block_split.py [--case ball_snow] [--view 180,0] [--pixels 40,47]
        [--seed 0] [--samples 2048] [--exits]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from backlit_probe import sun_towards, write_without_peaks
from ray_depth_split import cuts

STEP = 0.00025  # m, along the camera ray
SUN_STEP = 0.0005  # m, towards the sun


def single_scattering(case, origin, direction, a, b):
    """The sun's single scattering sent to the camera from the ray's stretch [a, b] (m from the origin)."""
    k, albedo, g = case.sigma_t / case.rho, case.omega[1], case.g
    s = np.arange(STEP / 2, b, STEP)
    rho = bake_suite.trilinear(case.density, (origin + s[:, None] * direction) / case.voxel)
    camera = np.exp(-k * (np.cumsum(rho) - rho / 2) * STEP)
    inside = (s >= a) & (rho > 0)
    if not inside.any():
        return 0.0
    points = origin + s[inside, None] * direction
    towards = np.arange(SUN_STEP / 2, 0.2, SUN_STEP)[:, None] * sun_towards()
    sun = np.array([math.exp(-k * bake_suite.trilinear(case.density, (p + towards) / case.voxel).sum() * SUN_STEP)
                    for p in points])
    mu = float(np.dot(direction, sun_towards()))  # the scattering angle's cosine (towards the camera)
    phase = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * mu) ** 1.5)
    return float((k * rho[inside] * albedo * phase * case.sun * camera[inside] * sun).sum() * STEP)


def exits(case, args):
    """The sun alone leaving the ball along the block's limb: at points at the block ray's optical depth 1 radius,
    (x, 7.7, 3.3) voxels off the centre (x -1.94 is the ray's own), towards exit cosines mu whose tangent part points
    the camera's way (azimuth 0, the sun's travel 30 deg off it) or away (180): the Monte Carlo against the bake."""
    origins, directions, _ = bake_suite.views(case)
    view = case.views.index(tuple(int(x) for x in args.view.split(",")))
    j = view * case.pixels ** 2 + int(args.pixels.split(",")[0])
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    depth_one = bake_suite.depth_one_points(case, origins[j:j + 1], directions[j:j + 1], [True])[0]
    radius = np.linalg.norm(depth_one - centre)
    starts, ways, labels = [], [], []
    for x in (-1.94, -0.5, 1.0, 2.5):
        n = np.array([x, 7.7, 3.3]) / np.linalg.norm([x, 7.7, 3.3])
        camera = -directions[j] - (-directions[j] @ n) * n
        camera /= np.linalg.norm(camera)
        for mu, azimuth in ((0.05, 0), (0.18, 0), (0.4, 0), (0.18, 180)):
            w = mu * n + math.sqrt(1 - mu * mu) * (camera if azimuth == 0 else -camera)
            starts.append(centre + radius * n + 0.05 * w)
            ways.append(-w)
            labels.append(f"x {x:+.2f} mu0 {n @ sun_towards():+.2f}  mu {mu:.2f} azimuth {azimuth:3d}")
    starts, ways = np.array(starts), np.array(ways)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        firncore.bake(path, case.optics, suns=case.suns(), quality="FINAL", seed=args.seed)
        baked = firncore.render_baked(path, case.optics, starts, ways)[:, 1]
        mc, err = firncore.monte_carlo_radiance(path, case.optics, starts, ways, suns=case.suns(),
                                                samples=args.samples, seed=5)
    print(f"{case.name}, sun alone, leaving the limb: Monte Carlo (+-), bake, bake / Monte Carlo")
    for label, m, e, b in zip(labels, mc[:, 1], err[:, 1], baked):
        print(f"  {label}: {m:.4f} ({e:.4f})  {b:.4f}  {b / m:.2f}")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_snow")
    parser.add_argument("--view", default="180,0", help="azimuth, elevation (deg)")
    parser.add_argument("--pixels", default="40,47", help="blocks within the view, row-major from the bottom")
    parser.add_argument("--seed", type=int, default=0, help="the bake's")
    parser.add_argument("--samples", type=int, default=2048, help="Monte Carlo paths per point")
    parser.add_argument("--cache", default=bake_suite.CACHE)
    parser.add_argument("--exits", action="store_true", help="the sun alone leaving the limb, by direction")
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    if args.exits:
        return exits(case, args)
    origins, directions, _ = bake_suite.views(case)
    view = case.views.index(tuple(int(x) for x in args.view.split(",")))
    pick = [view * case.pixels ** 2 + int(p) for p in args.pixels.split(",")]
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        reference, _, _ = bake_suite.reference(case, path, origins, directions, args.cache)
        sun_path = os.path.join(folder, "sun.vdb")
        bake_suite.write_density(sun_path, case.density, case.voxel)
        firncore.bake(sun_path, case.optics, suns=case.suns(), quality="FINAL", seed=args.seed)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), quality="FINAL", seed=args.seed)
        broad_path = os.path.join(folder, "broad.vdb")
        write_without_peaks(path, broad_path)
        for p in pick:
            t, T = cuts(case, origins[p], directions[p])
            points = origins[p] + t[:, None] * directions[p]
            along = np.repeat(directions[p][None], len(t), 0)
            render = firncore.render_baked(path, case.optics, points, along)[:, 1]
            broad = firncore.render_baked(broad_path, case.optics, points, along)[:, 1]
            baked_sun = firncore.render_baked(sun_path, case.optics, points, along)[:, 1]
            mc, err = firncore.monte_carlo_radiance(path, case.optics, points, along, suns=case.suns(),
                                                    sky=case.skies(), samples=args.samples, seed=23)
            sun, _ = firncore.monte_carlo_radiance(path, case.optics, points, along, suns=case.suns(),
                                                   samples=args.samples, seed=29)
            mc, err, sun = mc[:, 1], err[:, 1], sun[:, 1]
            block = p - view * case.pixels ** 2
            print(f"{case.name} view {args.view} block {block}: reference {reference[p, 1]:.4f}, render "
                  f"{render[0]:.4f} ({render[0] / reference[p, 1] - 1:+.0%}), Monte Carlo from the first cut "
                  f"{mc[0]:.4f} (+- {err[0]:.4f}); {args.samples} paths per point")
            print("  cell (voxel)   density  mu0    MC      sun once  sun more  sky      render  its peak  its sun  "
                  "render-MC")
            total = np.zeros(7)
            for j in range(len(t) - 1):
                def sent(L):  # what the cell [t_j, t_j+1] sends to the camera
                    return T[j] * L[j] - T[j + 1] * L[j + 1]
                middle = origins[p] + 0.5 * (t[j] + t[j + 1]) * directions[p]
                c = np.round(middle / case.voxel).astype(int)
                rho = case.density[tuple(c)] if all(0 <= c[a] < case.density.shape[a] for a in range(3)) else 0.0
                normal = (c * case.voxel - centre) / np.linalg.norm(c * case.voxel - centre)
                once = single_scattering(case, origins[p], directions[p], t[j], t[j + 1])
                row = np.array([sent(mc), once, sent(sun) - once, sent(mc) - sent(sun), sent(render),
                                sent(render) - sent(broad), sent(baked_sun)])
                total += row
                print(f"  {str(tuple(int(x) for x in c)):<13} {rho:6.1f}  {normal @ sun_towards():+.2f}  "
                      + "  ".join(f"{x:+.4f}" for x in row) + f"  {row[4] - row[0]:+.4f}")
            print(f"  all cells                   " + "  ".join(f"{x:+.4f}" for x in total)
                  + f"  {total[4] - total[0]:+.4f}")

if __name__ == "__main__":
    main()
