"""A ball case's light: the power that leaves the bake against the power that enters, and its distribution over the
angle to the sun, baked against the core's Monte Carlo (docs/benchmarks.md, "snow-bias").

Where the snow absorbs (almost) nothing, every watt entering the ball leaves it. The sun alone: the power leaving,
integrated over all directions, must equal E times the ball's cross-section to the sun. The ball is seen by
orthographic views at angle theta from the sun (in the sun's plane: towards the horizon, theta 30 is the suite's
view (0, 0), towards the zenith its view (0, 60)); each view's power sum(L) dA (W/sr) is integrated over the sphere
assuming the truth's symmetry about the sun's direction, 2 pi int f(theta) sin(theta) dtheta (midpoint rule), and
the bake's also over a Fibonacci sphere of views (no symmetry assumed). The peaked lobes' part (grids
firn_source_peak*) apart. --samples > 0 adds the Monte Carlo per theta towards the horizon (the same rays). --sky:
the uniform sky alone instead, each view's power over L_sky sum(1 - T) dA (exactly 1 at omega 1, every view).
--omega, --g, --sigma-t (1/m at the case's density) and --radius (m, on the case's voxels) change the case's snow or
ball: at --omega 0.9999999 what leaves must equal what enters, so the bake alone measures its energy balance, at any
size and snow (docs/benchmarks.md, lead-90). Where the snow absorbs, --mc-views N sets the bake's power over the
Fibonacci views against the core's Monte Carlo on the same rays (N paths per ray), by 30 degrees from the sun
(docs/benchmarks.md, lead-92).

    PYTHONPATH=build/python python3 bench/ball_energy_balance.py [--case ball_clean] [--pixels 24] [--samples 0] [--sky]
        [--omega W] [--g G] [--sigma-t S] [--radius R] [--mc-views N]
"""

import argparse
import dataclasses
import math
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore
from backlit_probe import sun_towards, write_without_peaks


def view_rays(case, back, pixels):
    """Orthographic rays towards -back covering the ball and their pixel area (m^2)."""
    n = np.array(case.density.shape)
    centre, half = (n - 1) / 2 * case.voxel, 0.5 * n.max() * case.voxel
    up = np.array([0.0, 1.0, 0.0]) if abs(back[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    right = np.cross(up, back)
    right /= np.linalg.norm(right)
    up = np.cross(back, right)
    s = ((np.arange(pixels) + 0.5) / pixels * 2.0 - 1.0) * half
    origins = np.array([centre + 3.0 * half * back + u * right + v * up for v in s for u in s])
    return origins, np.tile(-back, (len(origins), 1)), (2.0 * half / pixels) ** 2


def optical_depths(case, origins, directions):
    """Each ray's optical depth through the trilinear density."""
    step = 0.25 * case.voxel
    steps = np.arange(0.0, 6.0 * np.linalg.norm(origins[0] - origins[-1]) / math.sqrt(2.0), step)
    points = (origins[:, None, :] + steps[None, :, None] * directions[:, None, :]) / case.voxel
    return bs.trilinear(case.density, points.reshape(-1, 3)).reshape(len(origins), -1).sum(1) * step * \
        case.sigma_t / case.rho


def intercepted(case, back, pixels):
    """The ball's cross-section seen from `back` (m^2): sum (1 - T) dA."""
    origins, directions, area = view_rays(case, back, pixels)
    return area * (1.0 - np.exp(-optical_depths(case, origins, directions))).sum()


def sun_entering(case, pixels):
    """The sun's power entering the ball (W): E times its cross-section seen from the sun, on a view of 2 * pixels^2."""
    return case.sun * intercepted(case, sun_towards(), 2 * pixels)


def towards_camera(theta):
    """The camera's direction at angle theta (deg) from the sun, in the sun's plane (negative: towards the horizon)."""
    s = sun_towards()
    p = np.array([-s[2], 0.0, s[0]])  # the sun's plane, 90 degrees above the sun
    t = math.radians(theta)
    return math.cos(t) * s + math.sin(t) * p


def fibonacci(count):
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    phi = math.pi * (1.0 + 5.0 ** 0.5) * k
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def over_sphere(thetas, power):
    """2 pi int f sin(theta) dtheta by the midpoint rule (thetas the cells' middles, evenly spaced)."""
    t = np.radians(thetas)
    return 2.0 * math.pi * float((power * np.sin(t)).sum() * (t[1] - t[0]))


def changed(case, args):
    """The case with the snow and ball the arguments give (None: the case's own)."""
    changes = {"omega": (args.omega,) * 3 if args.omega is not None else None, "g": args.g, "sigma_t": args.sigma_t,
               "density": bs.ball(args.radius, case.voxel) * case.density.max() if args.radius is not None else None}
    return dataclasses.replace(case, **{k: v for k, v in changes.items() if v is not None})


def sun_balance(case, pixels=16, views=100, seed=0):
    """The bake's power leaving per W of sun entering the ball (FINAL, `seed`), over `views` Fibonacci views of
    `pixels`^2 px: 1 where the snow absorbs nothing."""
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "snow.vdb")
        bs.write_density(path, case.density, case.voxel)
        firncore.bake(path, case.optics, quality="FINAL", seed=seed, suns=case.suns())
        leaving = baked_power(case, path, fibonacci(views), pixels).sum()  # W/sr summed over the views
    return 4.0 * math.pi * leaving / views / sun_entering(case, pixels)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_clean")
    parser.add_argument("--pixels", type=int, default=24, help="per side of each view")
    parser.add_argument("--samples", type=int, default=0, help="Monte Carlo paths per ray (0: the bake only)")
    parser.add_argument("--views", type=int, default=200, help="the bake's Fibonacci views")
    parser.add_argument("--step", type=float, default=5.0, help="deg between the views in the sun's plane")
    parser.add_argument("--sky", action="store_true", help="the uniform sky alone instead of the sun")
    parser.add_argument("--seed", type=int, default=0, help="the bake's")
    parser.add_argument("--omega", type=float, help="the snow's single-scattering albedo, all channels")
    parser.add_argument("--g", type=float, help="the snow's Henyey-Greenstein g")
    parser.add_argument("--sigma-t", type=float, help="1/m at the case's density")
    parser.add_argument("--radius", type=float, help="m: a ball of this radius on the case's voxels and density")
    parser.add_argument("--mc-views", type=int, default=0,
                        help="Monte Carlo paths per ray over the Fibonacci views too (0: none): the sun's power "
                             "leaving against the truth's where the snow absorbs, by angle to the sun")
    args = parser.parse_args()
    ranges = (("--omega", args.omega, lambda w: 0.0 < w <= 1.0), ("--g", args.g, lambda g: -1.0 < g < 1.0),
              ("--sigma-t", args.sigma_t, lambda s: s > 0.0), ("--radius", args.radius, lambda r: r > 0.0),
              ("--mc-views", args.mc_views, lambda n: n >= 0), ("--samples", args.samples, lambda n: n >= 0),
              ("--views", args.views, lambda n: n > 0), ("--pixels", args.pixels, lambda n: n > 0),
              ("--step", args.step, lambda d: 0.0 < d <= 180.0))
    for name, value, valid in ranges:  # before the bake, not after it in the core
        if value is not None and not valid(value):
            parser.error(f"{name} {value}: out of range (omega in (0, 1], g in (-1, 1), sigma_t and radius > 0, "
                         "views and pixels > 0, samples and mc-views >= 0, step in (0, 180])")
    case = changed(bs.case(args.case), args)
    light = {"sky": firncore.Sky((case.sky,) * 3)} if args.sky else {"suns": case.suns()}
    thetas = np.arange(args.step / 2, 180.0, args.step)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "snow.vdb")
        bs.write_density(path, case.density, case.voxel)
        firncore.bake(path, case.optics, quality="FINAL", seed=args.seed, **light)
        write_without_peaks(path, path + ".broad.vdb")

        def power(back, traced):
            """The view's power (W/sr): baked, its peaked lobes' part, traced, what it intercepts (m^2), and baked
            and traced over the rays of optical depth 1 or more (the suite's seen blocks; the rest is the halo)."""
            origins, directions, area = view_rays(case, back, args.pixels)
            baked = firncore.render_baked(path, case.optics, origins, directions)[:, 1] * area
            broad = firncore.render_baked(path + ".broad.vdb", case.optics, origins, directions)[:, 1] * area
            tau = optical_depths(case, origins, directions)
            seen, thick = (1.0 - np.exp(-tau)).sum() * area, tau >= 1.0
            if not traced:
                return baked.sum(), (baked - broad).sum(), math.nan, seen, baked[thick].sum(), math.nan
            mean, _ = firncore.monte_carlo_radiance(path, case.optics, origins, directions, samples=args.samples,
                                                    seed=7, **light)
            traced = mean[:, 1] * area
            return baked.sum(), (baked - broad).sum(), traced.sum(), seen, baked[thick].sum(), traced[thick].sum()

        views = {side: np.array([power(towards_camera(side * t), args.samples > 0 and side < 0) for t in thetas])
                 for side in (-1, +1)}
        fibonacci_power = np.array([power(b, False)[:2] for b in fibonacci(args.views)]) if not args.sky else None
        traced = (traced_power(case, path, light, fibonacci(args.views), args.pixels, args.mc_views)
                  if args.mc_views and not args.sky else None)
    if args.sky:
        report_sky(case, args, thetas, views)
    else:
        report_sun(case, args, thetas, views, fibonacci_power)
        if traced is not None:
            report_traced(case, args, fibonacci_power[:, 0], traced)


def traced_power(case, path, light, backs, pixels, samples):
    """The core's Monte Carlo power (W/sr) towards each view `backs` (rows), on the bake's own rays (one call, one
    seed), `samples` paths per ray."""
    rays = [view_rays(case, back, pixels) for back in backs]
    mean, _ = firncore.monte_carlo_radiance(path, case.optics, np.concatenate([o for o, _, _ in rays]),
                                            np.concatenate([d for _, d, _ in rays]), samples=samples, seed=11, **light)
    return mean[:, 1].reshape(len(rays), -1).sum(1) * rays[0][2]


def baked_power(case, path, backs, pixels):
    """The baked power (W/sr) towards each view `backs` (rows)."""
    power = []
    for back in backs:
        origins, directions, area = view_rays(case, back, pixels)
        power.append(firncore.render_baked(path, case.optics, origins, directions)[:, 1].sum() * area)
    return np.array(power)


def report_traced(case, args, baked, traced):
    """The power leaving, baked against the Monte Carlo, over the Fibonacci views and by 30 degrees from the sun."""
    entering = sun_entering(case, args.pixels)
    whole = 4.0 * math.pi / entering
    print(f"  leaving over the {args.views} Fibonacci views, per W entering: baked {whole * baked.mean():.4f}, "
          f"Monte Carlo ({args.mc_views} paths per ray) {whole * traced.mean():.4f}: baked / MC "
          f"{baked.sum() / traced.sum():.4f}")
    angle = np.degrees(np.arccos(np.clip(fibonacci(args.views) @ np.asarray(sun_towards()), -1.0, 1.0)))
    for low in range(0, 180, 30):
        k = (angle >= low) & (angle < low + 30)
        print(f"    {low:3d}-{low + 30:3d} deg from the sun: {k.sum():3d} views, baked / MC "
              f"{baked[k].sum() / traced[k].sum():.3f}, share of the MC's power {traced[k].sum() / traced.sum():.3f}")


def report_sun(case, args, thetas, views, fibonacci_power):
    entering = sun_entering(case, args.pixels)  # W
    print(f"{case.name} (sigma_t {case.sigma_t:g} 1/m, omega {case.omega[0]:.8g}, g {case.g:g}, grid "
          f"{case.density.shape[0]} voxels of {case.voxel:g} m wide), sun alone ({case.sun} W/m^2, 30 deg up), "
          f"bake seed {args.seed}, "
          f"{args.pixels}^2 px per view"
          + (f", Monte Carlo {args.samples} paths per ray" if args.samples else ""))
    print(f"  entering: {entering * 1e3:.4f} mW (cross-section {entering / case.sun * 1e4:.3f} cm^2)")
    whole, peak = 4 * math.pi * fibonacci_power.mean(0) / entering
    print(f"  leaving, baked, over {args.views} Fibonacci views, per W entering: {whole:.4f} ({whole - 1:+.2%}), of "
          f"it the peaked lobes {peak:.4f}")
    for side, name in ((-1, "towards the horizon"), (+1, "towards the zenith")):
        v = views[side]
        line = (f"  leaving by theta {name}, per W entering: baked {over_sphere(thetas, v[:, 0]) / entering:.4f} "
                f"(peaked {over_sphere(thetas, v[:, 1]) / entering:.4f})")
        if args.samples and side < 0:
            line += (f", Monte Carlo {over_sphere(thetas, v[:, 2]) / entering:.4f}; over rays of optical depth >= 1 "
                     f"baked {over_sphere(thetas, v[:, 4]) / entering:.4f}, Monte Carlo "
                     f"{over_sphere(thetas, v[:, 5]) / entering:.4f}")
        print(line)
    print("  theta  view power per W entering, per sr: baked (-, +), of it peaked (-, +)"
          + ("   Monte Carlo (-)   baked / MC (-);  over rays of optical depth >= 1: baked, MC (-), baked / MC"
             if args.samples else ""))
    for i, t in enumerate(thetas):
        b, p = [views[s][i, 0] / entering for s in (-1, 1)], [views[s][i, 1] / entering for s in (-1, 1)]
        line = f"  {t:5.1f}  {b[0]:.4f} {b[1]:.4f}   {p[0]:.4f} {p[1]:.4f}"
        if args.samples:
            m, bt, mt = (views[-1][i, k] / entering for k in (2, 4, 5))
            line += f"       {m:.4f}      {b[0] / m - 1:+6.1%}       {bt:.4f} {mt:.4f} {bt / mt - 1:+6.1%}"
        print(line)


def report_sky(case, args, thetas, views):
    print(f"{case.name}, uniform sky alone ({case.sky} W/m^2/sr), bake seed {args.seed}, {args.pixels}^2 px per view; "
          "each view's power over L_sky sum(1 - T) dA (1 where nothing is absorbed)")
    for side, name in ((-1, "towards the horizon"), (+1, "towards the zenith")):
        v = views[side]
        albedo = v[:, 0] / (case.sky * v[:, 3])
        print(f"  {name}: mean {albedo.mean():.4f}, by theta " + " ".join(f"{a:.3f}" for a in albedo[::3]))
        if args.samples and side < 0:
            traced = v[:, 2] / (case.sky * v[:, 3])
            print(f"  Monte Carlo: mean {traced.mean():.4f}, by theta " + " ".join(f"{a:.3f}" for a in traced[::3]))


if __name__ == "__main__":
    main()
