"""A suite ball's sun alone on its own voxels and on finer ones (the same snow, the same ball): per view the blocks'
baked / Monte Carlo - 1 as the suite's pixel maps (docs/benchmarks.md, ball-issue-split). What follows the voxels'
size is the bake's resolution (or the staircase the ball is rasterized into), what does not is its model.

    PYTHONPATH=build/python python3 bench/ball_finer_views.py [--case ball_issue] [--voxels 0.01,0.005]
        [--views 90,0] [--samples 4096]
"""

import argparse
import dataclasses
import os
import re
import tempfile

import numpy as np

import bake_suite
import firncore


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_issue")
    parser.add_argument("--voxels", default="0.01,0.005", help="m")
    parser.add_argument("--views", default="90,0", help="azimuth,elevation pairs joined by ';'")
    parser.add_argument("--samples", type=int, default=4096)
    args = parser.parse_args()
    base = bake_suite.case(args.case)
    radius = float(re.search(r"r (\d+) cm", base.what).group(1)) / 100.0
    views = [tuple(int(x) for x in v.split(",")) for v in args.views.split(";")]
    for voxel in (float(v) for v in args.voxels.split(",")):
        case = dataclasses.replace(base, density=bake_suite.ball(radius, voxel) * base.density.max(), voxel=voxel,
                                   views=views)
        origins, directions, tau = bake_suite.views(case)
        seen = tau >= 1.0
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "ball.vdb")
            bake_suite.write_density(path, case.density, voxel)
            mc, err = firncore.monte_carlo_radiance(path, case.optics, origins[seen], directions[seen],
                                                    suns=case.suns(), samples=args.samples, seed=31)
            firncore.bake(path, case.optics, suns=case.suns(), quality="FINAL", seed=0)
            baked = firncore.render_baked(path, case.optics, origins[seen], directions[seen])
        e = np.full(len(seen), np.nan)
        e[seen] = baked[:, 1] / mc[:, 1] - 1.0
        per, n = case.pixels ** 2, case.pixels
        of_view = np.nonzero(seen)[0] // per  # each seen block's view
        for v, view in enumerate(views):
            bias = baked[of_view == v, 1].sum() / mc[of_view == v, 1].sum() - 1.0
            print(f"{case.name} on {100 * voxel:g} cm voxels, sun alone, view {view}: baked / Monte Carlo - 1 "
                  f"(sum {bias:+.1%}; its noise median {np.median(err[:, 1] / mc[:, 1]):.1%})")
            for r in reversed(range(n)):
                cells = e[v * per + r * n:v * per + (r + 1) * n]
                print("   " + " ".join("   .  " if np.isnan(x) else f"{100 * x:+5.0f} " for x in cells))


if __name__ == "__main__":
    main()
