"""Fluence inside a ball and exitance around it along the sun's great circle: the bake against Monte Carlo.

Points lie on the great circle in the sun's vertical plane through the ball's centre, at the angle theta from the
sub-solar point over the top. At each, the fluence 4 pi <L> at the given radii (a Fibonacci sphere of directions)
and the exitance through a sphere just outside the ball, sum of L mu dOmega over a uniform-z hemisphere of directions
(equal solid angles 2 pi / N) aimed at the point from 5 cm out. The sun alone, green channel, W/m^2 per W/m^2 of sun.
The baked render reads the grids (`render_baked`); the truth is `firncore.monte_carlo_radiance` on the same density.
A `--cache` file keeps the Monte Carlo for a rerun of the bake alone (`--bake-only`, e.g. with a temporary switch in
the core): docs/benchmarks.md, limb-forward 3 and 4.

    PYTHONPATH=build/python python3 bench/limb_circle.py [--case ball_snow] [--thetas 0,30,...,180]
        [--radii 7.5,6.5,5.0] [--exit-radius 8.8] [--samples 128] [--sphere 48] [--hemisphere 48] [--seed 0]
        [--cache FILE.npz] [--bake-only]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from backlit_probe import sun_towards


def fibonacci(n, hemisphere=False):
    """n unit vectors of equal solid angle: over the sphere, or over z > 0."""
    i = np.arange(n) + 0.5
    z = 1 - i / n if hemisphere else 1 - 2 * i / n
    r = np.sqrt(1 - z * z)
    phi = math.pi * (1 + 5 ** 0.5) * i
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], 1)


def frame(normal):
    """Two unit tangents and the normal."""
    t = np.cross(normal, [0, 1, 0]) if abs(normal[1]) < 0.9 else np.cross(normal, [1, 0, 0])
    t /= np.linalg.norm(t)
    return t, np.cross(normal, t), normal


def circle_rays(case, thetas, radii_m, exit_radius_m, sphere, hemisphere):
    """Fluence rays (per theta, per radius, the sphere's directions) and exitance rays (per theta, the hemisphere's)."""
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    sun = sun_towards()
    up_circle = np.array([-sun[2], 0.0, sun[0]])   # in the sun's vertical plane, towards the zenith side
    inside_o, inside_d, exit_o, exit_d = [], [], [], []
    for theta in np.radians(thetas):
        normal = math.cos(theta) * sun + math.sin(theta) * up_circle
        for r in radii_m:
            inside_o += [centre + r * normal] * len(sphere)
            inside_d += list(sphere)
        t, b, n = frame(normal)
        for h in hemisphere:
            w = h[0] * t + h[1] * b + h[2] * n
            exit_o.append(centre + exit_radius_m * normal + 0.05 * w)
            exit_d.append(-w)
    return tuple(map(np.array, (inside_o, inside_d, exit_o, exit_d)))


def monte_carlo(path, case, rays, samples, cache, run):
    """Green radiance and its standard error along the inside and the exit rays: from the cache when it matches the
    rays, else traced when run is set (and kept in the cache), else None."""
    key = np.concatenate([a.ravel() for a in rays] + [[samples]])
    if cache and os.path.exists(cache):
        stored = np.load(cache)
        if stored["key"].shape == key.shape and np.allclose(stored["key"], key):
            return stored["inside"], stored["inside_err"], stored["exit"], stored["exit_err"]
    if not run:
        return None
    inside, inside_err = firncore.monte_carlo_radiance(path, case.optics, rays[0], rays[1], suns=case.suns(),
                                                       samples=samples, seed=7)
    out, out_err = firncore.monte_carlo_radiance(path, case.optics, rays[2], rays[3], suns=case.suns(),
                                                 samples=samples, seed=11)
    result = inside[:, 1], inside_err[:, 1], out[:, 1], out_err[:, 1]
    if cache:
        np.savez(cache, key=key, inside=result[0], inside_err=result[1], exit=result[2], exit_err=result[3])
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--case", default="ball_snow")
    parser.add_argument("--thetas", default="0,30,60,75,90,105,120,150,180", help="degrees from the sub-solar point")
    parser.add_argument("--radii", default="7.5,6.5,5.0", help="cm from the ball's centre, for the fluence")
    parser.add_argument("--exit-radius", type=float, default=8.8, help="cm, the sphere the exitance crosses")
    parser.add_argument("--samples", type=int, default=128, help="Monte Carlo paths per direction")
    parser.add_argument("--sphere", type=int, default=48, help="directions per fluence point")
    parser.add_argument("--hemisphere", type=int, default=48, help="directions per exitance point")
    parser.add_argument("--seed", type=int, default=0, help="the bake's seed")
    parser.add_argument("--cache", help="an .npz file keeping the Monte Carlo between runs")
    parser.add_argument("--bake-only", action="store_true", help="no Monte Carlo run (ratios only from --cache)")
    args = parser.parse_args()

    case = bake_suite.case(args.case)
    thetas = [float(x) for x in args.thetas.split(",")]
    radii = [float(x) for x in args.radii.split(",")]
    sphere, hemisphere = fibonacci(args.sphere), fibonacci(args.hemisphere, hemisphere=True)
    rays = circle_rays(case, thetas, [r / 100 for r in radii], args.exit_radius / 100, sphere, hemisphere)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "snow.vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        firncore.bake(path, case.optics, suns=case.suns(), quality="FINAL", seed=args.seed)
        baked_inside = firncore.render_baked(path, case.optics, rays[0], rays[1])[:, 1]
        baked_exit = firncore.render_baked(path, case.optics, rays[2], rays[3])[:, 1]
        truth = monte_carlo(path, case, rays, args.samples, args.cache, run=not args.bake_only)

    mu = hemisphere[:, 2]
    solid = 2 * math.pi / args.hemisphere
    print(f"{case.name}, the sun alone, green; fluence (W/m^2) at r cm and exitance through r {args.exit_radius} cm:"
          + ("" if truth is None else " Monte Carlo (+-), bake, bake / Monte Carlo"))
    print("theta  mu0  " + "  ".join(f"r {r}" for r in radii) + "  exitance")
    for i, theta in enumerate(thetas):
        row = f"{theta:5.0f} {math.cos(math.radians(theta)):+.2f}"
        for k in range(len(radii)):
            part = slice((i * len(radii) + k) * args.sphere, (i * len(radii) + k + 1) * args.sphere)
            bake = 4 * math.pi * baked_inside[part].mean()
            if truth is None:
                row += f"  {bake:.4f}"
                continue
            mc = 4 * math.pi * truth[0][part].mean()
            err = 4 * math.pi * math.sqrt((truth[1][part] ** 2).sum()) / args.sphere
            row += f"  {mc:.4f} ({err:.4f}) {bake:.4f} {bake / mc:.2f} |"
        part = slice(i * args.hemisphere, (i + 1) * args.hemisphere)
        bake = solid * (baked_exit[part] * mu).sum()
        if truth is None:
            print(row + f"  {bake:.4f}")
            continue
        mc = solid * (truth[2][part] * mu).sum()
        err = solid * math.sqrt(((truth[3][part] * mu) ** 2).sum())
        print(row + f"  {mc:.4f} ({err:.4f}) {bake:.4f} {bake / mc:.2f}")


if __name__ == "__main__":
    main()
