"""The sun alone across ball_issue's +y plateau, seen from the side (view (90, 0): rays along -y), point by point
every quarter of a 1 cm voxel, on the case's voxels and on finer ones: the bake against the core's Monte Carlo of the
same density (docs/benchmarks.md, plateau-sun). The sun runs parallel to the plateau's air faces (it comes from +x,
30 deg up); the smooth sphere's terminator crosses the plateau near x = -0.3 cm. What the 1 cm bake misses here
and the 0.5 cm bake does not is how it places the light across a voxel the terminator crosses.
The Monte Carlo is cached per voxel size and row (--cache; it takes minutes), so a changed bake reruns in seconds.

    PYTHONPATH=build/python python3 bench/plateau_sun_profile.py [--case ball_issue] [--voxels 0.01,0.005]
        [--rows 0.5,1.5] [--samples 4096]
"""

import argparse
import dataclasses
import os
import re
import tempfile

import numpy as np

import bake_suite
import firncore

OFFSETS = np.arange(-3.0, 3.76, 0.25)  # cm from the ball's centre along x (the sun's side is +x)


def rays(case, row_cm):
    """Rays along -y through (x, ., z) at OFFSETS and z = row_cm from the ball's centre."""
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    origins = np.array([centre + np.array([x / 100.0, 0.3, row_cm / 100.0]) for x in OFFSETS])
    return origins, np.repeat(np.array([[0.0, -1.0, 0.0]]), len(OFFSETS), 0)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_issue")
    parser.add_argument("--voxels", default="0.01,0.005", help="m")
    parser.add_argument("--rows", default="0.5,1.5", help="cm above the ball's centre")
    parser.add_argument("--samples", type=int, default=4096)
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_plateau_sun"))
    args = parser.parse_args()
    base = bake_suite.case(args.case)
    radius = float(re.search(r"r (\d+) cm", base.what).group(1)) / 100.0
    os.makedirs(args.cache, exist_ok=True)
    rows = [float(r) for r in args.rows.split(",")]
    print(f"{base.name}, sun alone, rays along -y at x (cm from the centre; sun from +x): baked / Monte Carlo - 1 (%)")
    print("voxel row  " + " ".join(f"{x:+5.2f}" for x in OFFSETS))
    for voxel in (float(v) for v in args.voxels.split(",")):
        case = dataclasses.replace(base, density=bake_suite.ball(radius, voxel) * base.density.max(), voxel=voxel)
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "ball.vdb")
            bake_suite.write_density(path, case.density, voxel)
            references = []
            for row in rows:
                origins, directions = rays(case, row)
                cached = os.path.join(args.cache, f"{case.name}_{voxel:g}_{row:g}_{args.samples}.npy")
                if not os.path.exists(cached):
                    mc, _ = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                                          samples=args.samples, seed=37)
                    np.save(cached, mc[:, 1])
                references.append(np.load(cached))
            firncore.bake(path, case.optics, suns=case.suns(), quality="FINAL", seed=0)
            sum_e2 = 0.0
            for row, mc in zip(rows, references):
                baked = firncore.render_baked(path, case.optics, *rays(case, row))[:, 1]
                e = baked / np.maximum(mc, 1e-12) - 1.0
                seen = mc > 1e-3
                sum_e2 += float((e[seen] ** 2).sum())
                print(f"{100 * voxel:g} cm MC {row:+.1f} " + " ".join(f"{1000 * m:5.1f}" for m in mc))
                print(f"{100 * voxel:g} cm    {row:+.1f} " +
                      " ".join(f"{100 * x:+5.0f}" if s else "   . " for x, s in zip(e, seen)))
            print(f"{100 * voxel:g} cm: sum e^2 over the rows' points {sum_e2:.3f}")


if __name__ == "__main__":
    main()
