"""The radiance leaving points of a ball's surface at several exit angles: the bake against the core's Monte Carlo
(docs/bake.md, Accuracy: the shadowed side).

For a bench/bake_suite.py ball case, camera rays aimed at points of the ball's surface (its radius from the case's
description) from cos(exit angle) mu = 1, 0.6, 0.2 to the point's normal, at four azimuths about it: the core's
Monte Carlo (`firncore.monte_carlo_radiance`, all orders) against the baked render (`firncore.render_baked`) of the
same rays, channel G. The points: the centre of the shadowed side (-x, the sun shines from +x, 30 degrees high),
30 degrees under it, 40 degrees around it at the equator, and the bottom.

    PYTHONPATH=build/python /usr/bin/python3 bench/bake_exit_angles.py --case ball_issue [--quality REFERENCE]
"""

import argparse
import math
import os
import re
import sys
import tempfile

import numpy as np

import firncore

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bake_suite  # noqa: E402

POINTS = {  # outward normals
    "shadowed centre (-x)": (-1.0, 0.0, 0.0),
    "30 deg under it": (-math.cos(0.5), 0.0, -math.sin(0.5)),
    "40 deg around it": (-math.cos(0.7), math.sin(0.7), 0.0),
    "bottom (-z)": (0.0, 0.0, -1.0),
}


def rays(case):
    n = np.array(case.density.shape)
    centre = (n - 1) / 2 * case.voxel
    radius = float(re.search(r"r (\d+) cm", case.what).group(1)) / 100.0
    origins, directions, labels = [], [], []
    for name, normal in POINTS.items():
        normal = np.array(normal) / np.linalg.norm(normal)
        point = centre + radius * normal
        t = np.cross(normal, [0.0, 1.0, 0.0]) if abs(normal[1]) < 0.9 else np.cross(normal, [1.0, 0.0, 0.0])
        t /= np.linalg.norm(t)
        b = np.cross(normal, t)
        for mu in (1.0, 0.6, 0.2):
            for azimuth in ((0,) if mu == 1.0 else (0, 90, 180, 270)):
                a, s = math.radians(azimuth), math.sqrt(1.0 - mu * mu)
                w = mu * normal + s * (math.cos(a) * t + math.sin(a) * b)
                origins.append(point + 0.3 * w)
                directions.append(-w)
                labels.append((name, mu, azimuth))
    return np.array(origins), np.array(directions), labels


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_issue")
    parser.add_argument("--quality", default="FINAL")
    parser.add_argument("--samples", type=int, default=2048, help="Monte Carlo paths per ray")
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    origins, directions, labels = rays(case)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        reference, error = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                                         sky=case.skies(), samples=args.samples, seed=7)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), quality=args.quality)
        baked = firncore.render_baked(path, case.optics, origins, directions)
    print(f"{case.name}, {args.quality}: baked / reference - 1 (channel G) at cos(exit angle) mu, azimuths 0, 90, "
          f"180, 270 deg")
    for name in POINTS:
        cells = []
        for mu in (1.0, 0.6, 0.2):
            k = [i for i, label in enumerate(labels) if label[0] == name and label[1] == mu]
            ratios = ", ".join(f"{100 * (baked[i, 1] / reference[i, 1] - 1):+.0f}" for i in k)
            noise = max(error[i, 1] / reference[i, 1] for i in k)
            cells.append(f"mu {mu:.1f}: {ratios} % (ref {np.mean(reference[k, 1]):.4f} +- {100 * noise:.0f} %)")
        print(f"  {name:<22} " + "; ".join(cells))


if __name__ == "__main__":
    main()
