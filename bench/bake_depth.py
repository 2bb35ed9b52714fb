"""Where along a camera ray the bake's light differs from the reference's (docs/bake.md, Accuracy: the lit rim).

For pixels of a bench/bake_suite.py case and view, the ray's origin is moved along it in half-voxel steps from a
voxel before the snow: at each point the core's Monte Carlo (`firncore.monte_carlo_radiance`, all orders) and the
baked render (`firncore.render_baked`) give the light scattered beyond that point towards the camera. What a stretch
of the ray adds is the radiance at its start less the transmitted radiance at its end, so the two columns show at
which optical depth along the ray the bake's source is too dark or too bright (channel G; the reference's standard
error beside it).

    PYTHONPATH=build/python /usr/bin/python3 bench/bake_depth.py --case ball_issue --view 2 --pixels 0:3,0:2
"""

import argparse
import os
import sys
import tempfile

import numpy as np

import firncore

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bake_suite  # noqa: E402


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_issue")
    parser.add_argument("--view", type=int, default=2, help="index into the case's views (2: against the sun)")
    parser.add_argument("--pixels", default="0:3", help="row:column pairs, row 0 at the top as --maps prints them")
    parser.add_argument("--samples", type=int, default=4096, help="Monte Carlo paths per point")
    parser.add_argument("--steps", type=int, default=18, help="points along each ray, half a voxel apart")
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        origins, directions, tau = bake_suite.views(case)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders, quality="FINAL")
        n = case.pixels
        for pixel in args.pixels.split(","):
            row, column = (int(v) for v in pixel.split(":"))
            k = args.view * n * n + (n - 1 - row) * n + column
            o, d = origins[k], directions[k]
            step = 0.25 * case.voxel
            along = np.arange(0.0, 6.0 * 0.55 * max(case.density.shape) * case.voxel, step)
            density = bake_suite.trilinear(case.density, (o + along[:, None] * d) / case.voxel)
            extinction = density * case.sigma_t / case.rho
            depth = np.cumsum(extinction) * step
            entry = along[np.argmax(extinction > 0.0)]
            t = entry - case.voxel + 0.5 * case.voxel * np.arange(args.steps)
            points, rays = o + t[:, None] * d, np.tile(d, (len(t), 1))
            reference, error = firncore.monte_carlo_radiance(path, case.optics, points, rays, suns=case.suns(),
                                                             sky=case.skies(), occluders=case.occluders,
                                                             samples=args.samples, seed=5)
            baked = firncore.render_baked(path, case.optics, points, rays, occluders=case.occluders)
            print(f"{case.name} view {case.views[args.view]} pixel row {row} column {column}: "
                  f"optical depth {tau[k]:.1f}")
            print(f"{'from cm':>8} {'depth':>6} {'index x, y, z':>22} {'reference':>17} {'baked':>8} "
                  f"{'baked/ref-1':>11}")
            for ti, p, r, e, b in zip(t, points, reference[:, 1], error[:, 1], baked[:, 1]):
                x = ", ".join(f"{v:.2f}" for v in p / case.voxel)
                relative = f"{b / r - 1.0:+.2f}" if r > 0.0 else "-"
                print(f"{100 * (ti - entry):>+8.1f} {np.interp(ti, along, depth):>6.2f} {x:>22} {r:>9.4f} ± {e:.4f} "
                      f"{b:>8.4f} {relative:>11}")


if __name__ == "__main__":
    main()
