"""A spray case's error per block by how squarely the camera looks at the snow where its ray reaches optical depth 1
(docs/benchmarks.md, spray-rims 2026-12-04).

Bakes the case (FINAL, seeds 0..N-1) against the suite's cached reference and bins the seen blocks by mu, the cosine
between the snow's outward normal there (minus the trilinear density's gradient) and the direction towards the
camera (under 0.25: a grazing ray through a lump's rim; over 0.75: a face seen squarely), lit or shadowed as
bench/edge_blocks.py (the sun's optical depth from there under or over 1). Per bin: pixels, the seeds' mean signed
error per block averaged over the bin, its mean |.| (the bias per block), and per view.

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/spray_rim_mu.py [--case spray_dense] [--seeds 2]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from grazing_ceiling import exit_cosines
from suite_regions import sun_depth

BINS = [(-1.0, 0.25), (0.25, 0.5), (0.5, 0.75), (0.75, 1.01)]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="spray_dense")
    parser.add_argument("--seeds", type=int, default=2)
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    relative = []
    with tempfile.TemporaryDirectory() as folder:
        for seed in range(args.seeds):
            path = os.path.join(folder, "s.vdb")
            run = bake_suite.baked_case(case, path, bake_suite.CACHE, "FINAL", seed)
            render = firncore.render_baked(path, case.optics, run.origins, run.directions, occluders=case.occluders)
            relative.append(render[:, 1] / np.maximum(run.mean[:, 1], 1e-30) - 1.0)
    relative = np.array(relative)
    seen = run.tau >= 1.0
    hits = bake_suite.depth_one_points(case, run.origins, run.directions, seen)
    sun = sun_depth(case, hits)
    mu = exit_cosines(case, run.origins, run.directions, seen)[0]
    view = np.arange(len(seen)) // case.pixels ** 2
    print(f"{case.name}, seeds 0-{args.seeds - 1}: per block the seeds' mean error, by mu at depth 1 and the sun")
    for lit in (True, False):
        for lo, hi in BINS:
            where = seen & (mu >= lo) & (mu < hi) & ((sun < 1.0) == lit)
            if not where.any():
                continue
            m = relative[:, where].mean(0)
            views = " ".join(f"{case.views[v]} {100 * relative[:, where & (view == v)].mean():+.1f} ({(where & (view == v)).sum()})"
                             for v in range(len(case.views)) if (where & (view == v)).any())
            print(f"  {'lit' if lit else 'shadowed':9} mu {lo:5.2f} to {hi:4.2f}: {where.sum():3d} px  signed "
                  f"{100 * m.mean():+6.1f} %  |.| {100 * np.abs(m).mean():5.1f} %  per view {views}")


if __name__ == "__main__":
    main()
