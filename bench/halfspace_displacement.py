"""Where light returned by a half-space leaves, relative to where a beam entered it (docs/benchmarks.md, downstream).

A beam at cos(zenith) mu0 enters a semi-infinite homogeneous medium (Henyey-Greenstein g, albedo omega) at the
origin, travelling along +x. Each returned photon's exit point is recorded: its displacement along the beam's
tangential direction (x, downstream positive) and across it (y), in transport mean free paths 1/sigma_tr
(sigma_tr = sigma_t (1 - omega g)). Analog walk with absorption by weight (omega per event, dropped below 1e-4), seeded.

With --ball R (radius in transport mean free paths) the same beams enter a ball at angle psi from its sunward pole
(on the great circle through the sun and the zenith: 90 degrees is the terminator) and the returned light's exit
angle is recorded, against the half-space's displacement wrapped onto the sphere (psi + x / R). With --excess: the
ball's albedo against the half-space's by radius (3, 8, 20, 60 transport mean free paths) and entry angle, and over the
whole lit disc the share of the sun returned past the terminator (docs/benchmarks.md, ball-return).

    /usr/bin/python3 bench/halfspace_displacement.py [--photons 200000] [--ball 8.3 | --excess] [--omega 0.9 --g 0.6]
"""

import argparse

import numpy as np


def hg_cosine(g, u):
    if abs(g) < 1e-6:
        return 1.0 - 2.0 * u
    s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u)
    return (1.0 + g * g - s * s) / (2.0 * g)


def scatter(d, g, u0, u1):
    """New directions: HG deflection of d (n x 3) by cosines from u0, azimuth 2 pi u1."""
    cos = hg_cosine(g, u0)
    sin = np.sqrt(np.maximum(0.0, 1.0 - cos * cos))
    phi = 2.0 * np.pi * u1
    a = np.where(np.abs(d[:, 0:1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    e1 = np.cross(d, a)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(d, e1)
    return cos[:, None] * d + (sin * np.cos(phi))[:, None] * e1 + (sin * np.sin(phi))[:, None] * e2


def walk(omega, g, pos, d, outside, photons, seed):
    """Photons from pos along d until outside(start, step) gives the fraction of each step taken before leaving
    (nan where it stays inside). Returns the exit points, their weights, the photons' indices."""
    rng = np.random.default_rng(seed)
    n = photons
    w = np.ones(n)
    xs, ks, ws = [], [], []
    alive = np.arange(n)
    while alive.size:
        s = -np.log(1.0 - rng.random(alive.size))
        step = pos[alive] + s[:, None] * d[alive]
        t = outside(pos[alive], d[alive], s)
        out = ~np.isnan(t)
        if out.any():
            k = alive[out]
            xs.append(pos[k] + t[out, None] * d[k]), ws.append(w[k]), ks.append(k)
        pos[alive] = step
        alive = alive[~out]
        w[alive] *= omega
        alive = alive[w[alive] > 1e-4]
        d[alive] = scatter(d[alive], g, rng.random(alive.size), rng.random(alive.size))
    return np.concatenate(xs), np.concatenate(ws), np.concatenate(ks)


def above(p, d, s):
    """The distance to z = 0 where a step of length s from p along d crosses it (nan where it does not)."""
    t = p[:, 2] / -np.where(d[:, 2] < 0.0, d[:, 2], -1.0)
    return np.where((d[:, 2] < 0.0) & (t < s), t, np.nan)


def leaving_ball(radius):
    """The root of |p + t d| = radius in (0, s] (nan where the step stays inside the ball centred at 0)."""
    def leaving(p, d, s):
        b = np.sum(p * d, axis=1)
        c = np.sum(p * p, axis=1) - radius * radius
        t = -b + np.sqrt(np.maximum(0.0, b * b - c))
        return np.where(t < s, t, np.nan)
    return leaving


def displacement(omega, g, mu0, photons, seed):
    """Returned photons' exit points (x, y in optical depths) and weights; the plane albedo."""
    pos = np.zeros((photons, 3))
    d = np.tile([np.sqrt(1.0 - mu0 * mu0), 0.0, mu0], (photons, 1))  # z grows downwards

    points, w, _ = walk(omega, g, pos, d, above, photons, seed)
    return points[:, 0], points[:, 1], w, w.sum() / photons


def ball_exit(omega, g, radius, psi, photons, seed):
    """A beam along -x entering a ball (radius in optical depths, centred at 0) at angle psi from the +x pole in the
    x-z plane: the returned photons' exit angles psi (rad, in that plane's projection) and weights; the albedo."""
    normal = np.array([np.cos(psi), 0.0, np.sin(psi)])
    pos = np.tile(radius * normal * (1.0 - 1e-9), (photons, 1))
    d = np.tile([-1.0, 0.0, 0.0], (photons, 1))

    points, w, _ = walk(omega, g, pos, d, leaving_ball(radius), photons, seed)
    return np.arctan2(points[:, 2], points[:, 0]), w, w.sum() / photons


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--photons", type=int, default=200000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--ball", type=float, default=0.0, help="ball radius in transport mean free paths")
    parser.add_argument("--omega", type=float, default=0.98)
    parser.add_argument("--g", type=float, default=0.85)
    parser.add_argument("--excess", action="store_true", help="the ball's return beyond the half-space's, by R and mu0")
    args = parser.parse_args()
    if args.excess:
        return excess(args)
    if args.ball > 0.0:
        return ball(args)
    print("omega    g     mu0  albedo  mean_x  median_x  sd_x   sd_y   P(x>1)  P(x>2)  (x, y in 1/sigma_tr; "
          "x downstream along the sun's tangential travel)")
    for omega, g in ((0.98, 0.85), (0.9, 0.6), (0.9999, 0.85)):
        ltr = 1.0 / (1.0 - omega * g)  # optical depths per transport mean free path
        for mu0 in (1.0, 0.7, 0.5, 0.3, 0.15, 0.05):
            x, y, w, albedo = displacement(omega, g, mu0, args.photons, args.seed)
            x, y = x / ltr, y / ltr
            total = w.sum()
            mean = (w * x).sum() / total
            order = np.argsort(x)
            median = x[order][np.searchsorted(np.cumsum(w[order]), 0.5 * total)]
            sd_x = np.sqrt((w * (x - mean) ** 2).sum() / total)
            sd_y = np.sqrt((w * y * y).sum() / total)
            print(f"{omega:<7} {g:<5} {mu0:<4} {albedo:6.3f} {mean:7.2f} {median:8.2f} {sd_x:6.2f} {sd_y:6.2f} "
                  f"{(w * (x > 1)).sum() / total:7.3f} {(w * (x > 2)).sum() / total:7.3f}")


def ball(args):
    """Exit angles of the light a ball returns against the half-space's displacement wrapped onto it."""
    ltr = 1.0 / (1.0 - args.omega * args.g)
    radius = args.ball * ltr
    edges = np.arange(40.0, 181.0, 10.0)
    print(f"ball radius {args.ball} transport mean free paths, omega {args.omega}, g {args.g}: share of the returned "
          f"light (of the beam's power) leaving per 10 degrees of psi")
    print("entry psi  albedo   source | " + " ".join(f"{a:>5.0f}" for a in edges[:-1] + 5.0))
    for psi in (60.0, 75.0, 80.0, 85.0, 88.0):
        mu0 = np.cos(np.radians(psi))
        exit_psi, w, albedo = ball_exit(args.omega, args.g, radius, np.radians(psi), args.photons, args.seed)
        x, _, wh, albedo_h = displacement(args.omega, args.g, mu0, args.photons, args.seed)
        wrapped = np.radians(psi) + x / radius
        for name, angles, weights, a in (("ball", exit_psi, w, albedo), ("half-space", wrapped, wh, albedo_h)):
            share = np.histogram(np.degrees(angles), edges, weights=weights)[0] / args.photons
            print(f"{psi:>9.0f} {a:7.3f} {name:>8} | " + " ".join(f"{v:5.3f}" for v in share))


def excess(args):
    """The light a ball returns beyond a half-space, by radius (transport mean free paths) and entry angle, and the
    share of that excess leaving past the terminator (psi > 90 degrees)."""
    ltr = 1.0 / (1.0 - args.omega * args.g)
    print(f"omega {args.omega}, g {args.g}: albedo of a beam entering a ball at psi (mu0 = cos psi) against the "
          f"half-space's; excess = ball - half-space (of the beam's power); past90 = the ball's return leaving past the "
          f"terminator minus the half-space's wrapped there (psi + x / R)")
    print("     R   psi    mu0  ball   half   excess  excess*R  past90")
    for radius in (3.0, 8.0, 20.0, 60.0):
        for psi in (0.0, 30.0, 60.0, 75.0, 85.0, 88.0):
            mu0 = max(np.cos(np.radians(psi)), 1e-9)
            exit_psi, w, a_ball = ball_exit(args.omega, args.g, radius * ltr, np.radians(psi), args.photons, args.seed)
            x, _, wh, a_half = displacement(args.omega, args.g, mu0, args.photons, args.seed)
            past_ball = w[np.abs(exit_psi) > np.pi / 2].sum() / args.photons
            past_half = wh[np.radians(psi) + x / (radius * ltr) > np.pi / 2].sum() / args.photons
            print(f"{radius:6.0f} {psi:5.0f} {mu0:6.3f} {a_ball:6.3f} {a_half:6.3f} {a_ball - a_half:7.3f} "
                  f"{(a_ball - a_half) * radius:8.2f} {past_ball - past_half:7.3f}")
    print("the whole lit disc (entry points uniform over the ball's cross-section): the share of the sun's power "
          "returned, and returned past the terminator, by the ball and by the half-space wrapped onto it")
    print("     R  ball   half   past90_ball  past90_half")
    for radius in (3.0, 8.0, 20.0, 60.0):
        print(f"{radius:6.0f} " + " ".join(f"{v:6.3f}" for v in lit_disc(args.omega, args.g, radius * ltr, args.photons,
                                                                           args.seed)))


def lit_disc(omega, g, radius, photons, seed):
    """A sun along -x onto a ball (radius in optical depths): entry points uniform over its cross-section. The shares
    of the sun's power the ball returns, the half-space at each entry point returns, and each returns past the
    terminator (exit x < 0; the half-space's exit points wrapped along great circles, psi + |x, y| / R)."""
    rng = np.random.default_rng(seed + 1)
    r, a = np.sqrt(rng.random(photons)), 2.0 * np.pi * rng.random(photons)
    n = np.stack([np.sqrt(1.0 - r * r), r * np.cos(a), r * np.sin(a)], axis=1)
    d = np.tile([-1.0, 0.0, 0.0], (photons, 1))
    points, w, _ = walk(omega, g, radius * n * (1.0 - 1e-9), d.copy(), leaving_ball(radius), photons, seed)
    past_ball = w[points[:, 0] < 0.0].sum() / photons
    # the half-space's: the beam in each entry point's frame (z into the snow, x along the tangential travel)
    mu0 = n[:, 0]
    t = d - mu0[:, None] * -n  # d . n = -mu0
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-12)
    b = np.cross(n, t)
    local = np.stack([np.sqrt(1.0 - mu0 * mu0), np.zeros(photons), mu0], axis=1)
    hp, hw, k = walk(omega, g, np.zeros((photons, 3)), local, above, photons, seed)
    x, y = hp[:, 0], hp[:, 1]
    v = x[:, None] * t[k] + y[:, None] * b[k]
    length = np.linalg.norm(v, axis=1)
    angle = length / radius
    exit_x = np.cos(angle) * n[k, 0] + np.sin(angle) * v[:, 0] / np.maximum(length, 1e-12)
    past_half = hw[exit_x < 0.0].sum() / photons
    return w.sum() / photons, hw.sum() / photons, past_ball, past_half


if __name__ == "__main__":
    main()
