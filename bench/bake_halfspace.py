"""Where the bake's balls fail: the bake and the exact half-space against the Monte Carlo reference, per pixel.

For a ball case of bench/bake_suite.py and one of its views, every pixel whose ray meets the ball's surface
(radius r, where the density is half its peak; a ray through the density's ramp only: where it passes
closest, seen at grazing) gets the radiance a semi-infinite half-space of the same snow
would send towards the camera at that surface point: the sun at the point's incidence cosine mu0 (none where
mu0 <= 0) by Monte Carlo with local estimates (Henyey-Greenstein, all orders; independent of the core), plus
the uniform sky times the plane albedo A(mu) (reciprocity). Pixels are grouped into the lit rim (mu0 > 0,
view cosine mu < 0.4), the lit face and the shadowed side; per group: mean |relative error| and bias of the
bake and of the half-space against the reference (cached by bake_suite.py). If the half-space matches the
reference where the bake does not, the bake's angular form of the surface is at fault; where neither
matches, light crossing the curved snow (not a half-space) is (docs/bake.md, Accuracy).

    PYTHONPATH=build/python python3 bench/bake_halfspace.py [--case ball_issue] [--view 2] [--photons 3000]
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

# The absorbing balls (omega 0.9-0.99 in the green channel): the half-space's walks stay short.
RADIUS = {"ball_issue": 0.05, "ball_grey": 0.05, "ball_rgb": 0.06}


def henyey_greenstein(g, cos):
    d = 1.0 + g * g - 2.0 * g * cos
    return (1.0 - g * g) / (4.0 * math.pi * d ** 1.5)


def scatter(d, g, rng):
    """The unit directions d (one per row) after a Henyey-Greenstein scattering: two uniform draws per row."""
    u = rng.random(len(d))
    cos = 1.0 - 2.0 * u if g == 0.0 else (1.0 + g * g - ((1.0 - g * g) / (1.0 - g + 2.0 * g * u)) ** 2) / (2.0 * g)
    phi = 2.0 * math.pi * rng.random(len(d))
    a = np.where(np.abs(d[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    t1 = np.cross(a, d)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    t2 = np.cross(d, t1)
    sin = np.sqrt(np.maximum(0.0, 1.0 - cos * cos))
    return cos[:, None] * d + sin[:, None] * (np.cos(phi)[:, None] * t1 + np.sin(phi)[:, None] * t2)


def half_space(omega, g, mu0, view, photons, seed):
    """pi L / (mu0 E) towards the unit `view` (frame: normal z, sun travelling towards +x), and A(mu0).

    Optical-depth units; each collision adds its local estimate towards the view; weights carry omega;
    Russian roulette below 1e-3."""
    rng = np.random.default_rng(seed)
    s0 = math.sqrt(1.0 - mu0 * mu0)
    d = np.tile([s0, 0.0, -mu0], (photons, 1))
    z = -np.log(rng.random(photons)) * mu0  # depth below the surface
    w = np.ones(photons)
    mu = max(view[2], 1e-3)
    radiance, returned = 0.0, 0.0
    while len(w):
        radiance += np.sum(w * omega * henyey_greenstein(g, d @ view) * np.exp(-z / mu) / mu)
        w = w * omega
        d = scatter(d, g, rng)
        z = z - d[:, 2] * -np.log(rng.random(len(w)))
        escaped = z < 0.0
        returned += w[escaped].sum()
        low = w < 1e-3
        survive = ~low | (rng.random(len(w)) < 0.1)
        w = np.where(low, 10.0 * w, w)
        keep = ~escaped & survive
        d, z, w = d[keep], z[keep], w[keep]
    return math.pi * radiance / photons, returned / photons


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_issue", choices=sorted(RADIUS))
    parser.add_argument("--view", type=int, default=2, help="index into the case's views (2: against the sun)")
    parser.add_argument("--photons", type=int, default=3000)
    parser.add_argument("--cache", default=bake_suite.CACHE)
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    radius, channel = RADIUS[case.name], 1
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        origins, directions, tau = bake_suite.views(case)
        reference, _, _ = bake_suite.reference(case, path, origins, directions, args.cache)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), quality="FINAL")
        baked = firncore.render_baked(path, case.optics, origins, directions)
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    sun = np.array([math.cos(bake_suite.SUN_ELEVATION), 0.0, math.sin(bake_suite.SUN_ELEVATION)])
    omega = case.omega[channel]
    per = case.pixels ** 2
    groups = {"lit rim": [], "lit face": [], "shadowed": []}
    for k in range(args.view * per, (args.view + 1) * per):
        if tau[k] < 1.0:
            continue
        o = origins[k] - centre
        b, c = o @ directions[k], o @ o - radius * radius
        # Where the ray meets the sphere; a ray through the density's ramp only, where it passes closest.
        p = o + (-b - math.sqrt(b * b - c)) * directions[k] if b * b >= c else o - b * directions[k]
        n = p / np.linalg.norm(p)
        view = -directions[k]
        mu, mu0 = max(n @ view, 0.02), n @ sun
        forward = -sun - (-sun @ n) * n
        forward = forward / np.linalg.norm(forward) if np.linalg.norm(forward) > 1e-9 else np.cross(n, [0.0, 1.0, 0.0])
        local = np.array([view @ forward, view @ np.cross(n, forward), mu])
        _, albedo = half_space(omega, case.g, mu, np.array([0.0, 0.0, 1.0]), args.photons, 2 * k + 1)
        exact = case.sky * albedo
        if mu0 > 0.0:
            exact += case.sun * mu0 / math.pi * half_space(omega, case.g, mu0, local, args.photons, 2 * k)[0]
        group = "shadowed" if mu0 <= 0.0 else "lit rim" if mu < 0.4 else "lit face"
        groups[group].append((reference[k, channel], baked[k, channel], exact))
    print(f"{case.name}, view {case.views[args.view]}, channel {channel}, {args.photons} photons per half-space")
    print(f"{'pixels':<10} {'n':>3} {'bake mean':>10} {'bake bias':>10} {'half-space mean':>16} {'half-space bias':>16}")
    for name, rows in groups.items():
        if not rows:
            continue
        r = np.array(rows)
        bake, exact = r[:, 1] / r[:, 0] - 1.0, r[:, 2] / r[:, 0] - 1.0
        print(f"{name:<10} {len(r):>3} {100 * np.abs(bake).mean():>9.1f}% {100 * (r[:, 1].sum() / r[:, 0].sum() - 1):>+9.1f}% "
              f"{100 * np.abs(exact).mean():>15.1f}% {100 * (r[:, 2].sum() / r[:, 0].sum() - 1):>+15.1f}%")


if __name__ == "__main__":
    main()
