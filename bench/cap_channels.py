"""A ball's error per colour channel and per region of its surface, against the suite's Monte Carlo reference
(docs/benchmarks.md, cap-rgb).

bench/bake_suite.py's ball cases (FINAL, --seed, their cached references; none computed): every view's seen blocks
split by the ball's normal at the block ray's optical depth 1 point, mu0 its cosine to the sun (the lit cap
mu0 > 0.5, the lit side 0.15..0.5, the terminator |mu0| < 0.15, the shadow below), and per channel each region's
mean |relative error| and its bias (baked sum over reference sum).

    PYTHONPATH=build/python:bench python3 bench/cap_channels.py [--cases ball_rgb,ball_snow] [--seed 0]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite as S
from backlit_probe import sun_towards

REGIONS = ((0.5, 1.01, "cap"), (0.15, 0.5, "lit side"), (-0.15, 0.15, "terminator"), (-1.01, -0.15, "shadow"))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="ball_rgb")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--cache", default=S.CACHE)
    args = parser.parse_args()
    for case in [c for c in S.cases() if c.name in args.cases.split(",")]:
        with tempfile.TemporaryDirectory() as folder:
            r = S.run_case(case, folder, args.cache, "FINAL", args.seed)
            path = os.path.join(folder, case.name + ".vdb")
            origins, directions, tau = S.views(case)
            mean, _, _ = S.reference(case, path, origins, directions, args.cache)
            baked = S.firncore.render_baked(path, case.optics, origins, directions, occluders=case.occluders)
        seen = tau >= 1.0
        hit = S.depth_one_points(case, origins, directions, seen)
        centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
        mu0 = ((hit - centre) / np.linalg.norm(hit - centre, axis=1)[:, None]) @ sun_towards()
        print(f"{case.name}: mean {100 * r['mean']:.2f} %, bias {100 * r['bias']:+.2f} %")
        for lo, hi, what in ((-1.01, 1.01, "all"),) + REGIONS:
            k = seen & (mu0 >= lo) & (mu0 < hi)
            cells = []
            for c in range(3):
                m, b = mean[k, c], baked[k, c]
                rel = b / np.maximum(m, 1e-30) - 1.0
                cells.append(f"{100 * np.abs(rel).mean():5.2f} ({100 * (b.sum() / m.sum() - 1):+6.2f})")
            print(f"  {what:<10} {k.sum():3d} blocks  R " + "  G ".join(cells[:2]) + "  B " + cells[2], flush=True)


if __name__ == "__main__":
    main()
