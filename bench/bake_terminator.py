"""The light leaving a ball's surface across the terminator: the bake against the core's Monte Carlo, sun and sky apart
(docs/bake.md, Accuracy: the terminator).

For a bench/bake_suite.py ball case, points on the great circle through the sun's direction and the zenith, at angle
psi from the sunward pole (90 degrees: the terminator at the top; past it the shadowed side), seen along three exit
directions: towards the camera against the sun (-x, the suite's view (180, 0)), along the normal, and forwards along
the sun's travel where that leaves the surface. Camera rays are aimed at each point from 0.3 m out, as
bench/bake_exit_angles.py does: the core's Monte Carlo (`firncore.monte_carlo_radiance`, all orders) against the baked
render (`firncore.render_baked`), channel G, for the sun alone and the sky alone (the bake and the reference are
linear in the lights).

    PYTHONPATH=build/python /usr/bin/python3 bench/bake_terminator.py --case ball_issue [--samples 4096]
"""

import argparse
import dataclasses
import math
import os
import re
import sys
import tempfile

import numpy as np

import firncore

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bake_suite  # noqa: E402

SUN = np.array([math.cos(bake_suite.SUN_ELEVATION), 0.0, math.sin(bake_suite.SUN_ELEVATION)])  # towards the sun
UP = np.array([-SUN[2], 0.0, SUN[0]])  # perpendicular to it in the x-z plane, upwards


def rays(case, angles):
    n = np.array(case.density.shape)
    centre = (n - 1) / 2 * case.voxel
    radius = float(re.search(r"r (\d+) cm", case.what).group(1)) / 100.0
    exits = {"camera (-x)": np.array([-1.0, 0.0, 0.0]), "normal": None, "forward (sun's travel)": -SUN}
    origins, directions, labels = [], [], []
    for psi in angles:
        normal = math.cos(math.radians(psi)) * SUN + math.sin(math.radians(psi)) * UP
        point = centre + radius * normal
        for name, w in exits.items():
            w = normal if w is None else w
            mu = float(np.dot(w, normal))
            if mu < 0.1:
                continue
            origins.append(point + 0.3 * w)
            directions.append(-w)
            labels.append((psi, name, mu))
    return np.array(origins), np.array(directions), labels


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_issue")
    parser.add_argument("--samples", type=int, default=4096, help="Monte Carlo paths per ray")
    parser.add_argument("--voxel", type=float, default=0.0,
                        help="rasterize the case's ball on voxels of this size (m) instead (same snow)")
    parser.add_argument("--quality", default="FINAL")
    parser.add_argument("--angles", default="60,75,85,90,95,100,105,110,120,135,150",
                        help="psi, degrees from the sunward pole through the top (90: the terminator)")
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    angles = [float(a) for a in args.angles.split(",")]
    if args.voxel > 0.0:
        radius = float(re.search(r"r (\d+) cm", case.what).group(1)) / 100.0
        case = dataclasses.replace(case, density=bake_suite.ball(radius, args.voxel) * case.density.max(),
                                   voxel=args.voxel)
    origins, directions, labels = rays(case, angles)
    lights = {"sun": dict(suns=case.suns(), sky=None), "sky": dict(suns=[], sky=case.skies())}
    result = {}
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        for name, light in lights.items():
            reference, error = firncore.monte_carlo_radiance(path, case.optics, origins, directions,
                                                             samples=args.samples, seed=7, **light)
            firncore.bake(path, case.optics, quality=args.quality, **light)
            baked = firncore.render_baked(path, case.optics, origins, directions)
            result[name] = (reference[:, 1], error[:, 1], baked[:, 1])
    print(f"{case.name} ({case.voxel * 100:g} cm voxels, {args.quality}): radiance leaving the surface at psi degrees "
          f"from the sunward pole (90: terminator), channel G; reference +- its standard error, baked, "
          f"baked / reference - 1")
    print(f"{'psi':>5} {'exit':>23} {'mu':>5} | {'sun ref':>15} {'baked':>8} {'err':>6} | {'sky ref':>15} {'baked':>8} "
          f"{'err':>6} | {'both err':>8}")
    for i, (psi, exit_name, mu) in enumerate(labels):
        cells = []
        for name in lights:
            r, e, b = (v[i] for v in result[name])
            cells.append(f"{r:.5f} +- {100 * e / max(r, 1e-30):3.0f}% {b:8.5f} {100 * (b / max(r, 1e-30) - 1):+5.0f}%")
        total = (result["sun"][2][i] + result["sky"][2][i]) / max(result["sun"][0][i] + result["sky"][0][i], 1e-30) - 1
        print(f"{psi:5.0f} {exit_name:>23} {mu:5.2f} | " + " | ".join(cells) + f" | {100 * total:+7.0f}%")


if __name__ == "__main__":
    main()
