"""How the half-space's exit under a high sun changes shape with the snow's albedo (issue 10 item 1).

Clean snow's lit face reads +5-6 % seen near the normal: its exit is flat towards the normal, which the grids'
HG lobe (convex towards its axis) overshoots (docs/benchmarks.md lobe-form, surface-quad). Where the snow absorbs
(ball_grey omega 0.9, ball_rgb's red 0.95) is the truth as flat, or HG-like? For each (omega, g, mu0): the exact
half-space (bench/lobe_form.py's half_space_exits: local estimates, numpy), pi L / (mu0 E) by exit ring, and
three forms fitted to it with the exitance kept (relative error weighted by mu dw, as lobe_form.fit_surface):
  HG(lin)  the HG fitted to the linear exit form a + b mu + c t.w (itself fitted to the truth): the bake's lobe;
  HG       the HG fitted to the truth itself (the best any HG does);
  poly     max(0, 1 + l1.w + q P2(m.w)) fitted to the truth (surface-quad's clamped polynomial; q relative to l0).
Run: /usr/bin/python3 bench/lit_exit_albedo.py --photons 8000
"""
import argparse
import math

import numpy as np

from lobe_form import (SURFACE_VIEWS, half_space_exits, hg_shape, linear_p2_shape, mirrored, nelder_mead,
                       ring_means, sphere_grid)

SNOWS = [(0.9, 0.6, "ball_grey"), (0.95, 0.7, "ball_rgb red"), (0.98, 0.85, "ball_issue"),
         (0.99, 0.7, "ball_rgb green"), (0.999, 0.7, "ball_rgb blue"), (0.9999, 0.85, "ball_snow")]


def similarity(omega, g):
    """y = sqrt((1 - omega) / (1 - omega g)): the sun lobe table's albedo coordinate."""
    return math.sqrt((1.0 - omega) / (1.0 - omega * g))


def fit(shape, starts, target, views, dw):
    """A shape fitted to target with the exitance kept: relative to the ring's level, weighted by mu dw."""
    weight = views[:, 2] * dw
    flux = (target * weight).sum()
    level = np.repeat(target.reshape(SURFACE_VIEWS).mean(1), SURFACE_VIEWS[1])

    def model(p):
        f = shape(p, views)
        return f * flux / max((f * weight).sum(), 1e-30)

    def cost(p):
        return (weight * ((model(p) - target) / level) ** 2).sum() / weight.sum()

    p = min((nelder_mead(cost, x0) for x0 in starts), key=cost)
    return p, model(p)


def linear_shape(p, v):
    """a + b mu + c t.w with a = 1 (the scale is the exitance's): t the sun's tangent direction (+x)."""
    return np.maximum(0.0, 1.0 + p[0] * v[:, 2] + p[1] * v[:, 0])


def measure(omega, g, mu0, photons, seed):
    views, dw = sphere_grid(*SURFACE_VIEWS, upper_only=True)
    single, multiple = half_space_exits(omega, g, mu0, views, photons, seed)
    truth = mirrored(single + multiple, SURFACE_VIEWS)
    _, linear = fit(linear_shape, [[1.0, 0.0]], truth, views, dw)
    _, hg_of_linear = fit(hg_shape, [[0.3, 0.3, 0.0]], linear, views, dw)
    _, hg = fit(hg_shape, [[0.3, 0.3, 0.0]], truth, views, dw)
    p, poly = fit(linear_p2_shape,
                  [[0.9, 0.3, 0.0, 0.0], [0.5, 0.3, 0.0, -0.3], [0.5, 0.0, 0.0, -0.8], [0.3, 0.6, 0.0, 0.3]],
                  truth, views, dw)
    return truth, {"HG(lin)": hg_of_linear, "HG": hg, "poly": poly}, p


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--photons", type=int, default=8000)
    parser.add_argument("--mu0", type=float, nargs="+", default=[1.0, 0.87])
    parser.add_argument("--omega-max", type=float, default=1.0, help="only the snows of omega up to this")
    args = parser.parse_args()
    mus = 1.0 - (np.arange(SURFACE_VIEWS[0]) + 0.5) / SURFACE_VIEWS[0]
    for mu0 in args.mu0:
        print(f"mu0 {mu0}: truth pi L/(mu0 E) by exit ring mu {' '.join(f'{m:.2f}' for m in mus[::-1])}; "
              "then each form's error at the top ring (mu 0.94), at mu 0.81 and at grazing (mu 0.06), %")
        for k, (omega, g, name) in enumerate(SNOWS):
            if omega > args.omega_max:
                continue
            truth, forms, p = measure(omega, g, mu0, args.photons, 17 + k)
            t = ring_means(truth)
            errors = "  ".join(label + " " + " ".join(f"{100 * (ring_means(f)[r] / t[r] - 1):+5.1f}"
                                                      for r in (-1, -2, 0)) for label, f in forms.items())
            print(f"  omega {omega:<6} g {g:.2f} y {similarity(omega, g):.3f} ({name:14s}) "
                  f"{' '.join(f'{v:.3f}' for v in t)}  top/mean {t[-1] / t.mean():.3f}\n"
                  f"      {errors}   poly q/l0 {p[3]:+.3f}", flush=True)


if __name__ == "__main__":
    main()
