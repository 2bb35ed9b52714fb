"""Thin snow scattered by the renderer instead of baked (docs/benchmarks.md, thin-ring): the suite's cases rendered
as Cycles would render a material that scatters in voxels of optical depth sigma_t h under a threshold and draws
the baked emission elsewhere (`firncore.render_scattering_where_thin`), against the suite's cached Monte Carlo
references; beside the baked render (`render_baked`), with each render's processor seconds per camera ray.

    PYTHONPATH=build/python /usr/bin/python3 bench/thin_scatter.py [--cases a,b] [--thin 1,2,4] [--samples 64,256]
        [--scales 1,2]

`--scales`: the shares read from voxels that many times the density's (the bake's firn_scatter: SCATTER_SCALE).
"""

import argparse
import itertools
import os
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import bake_suite  # noqa: E402
import firncore  # noqa: E402


def scores(case, estimate, reference, tau):
    """The suite's figures of one render: mean |error| and bias over the seen blocks, and each view's bias."""
    seen = tau >= 1.0
    per = case.pixels ** 2
    relative = estimate[seen] / np.maximum(reference[seen], 1e-30) - 1.0
    views = [estimate[v * per:(v + 1) * per][seen[v * per:(v + 1) * per]].sum() /
             reference[v * per:(v + 1) * per][seen[v * per:(v + 1) * per]].sum() - 1.0 for v in range(len(case.views))]
    return float(np.abs(relative).mean()), float(np.abs(relative).max() * np.sign(relative.flat[np.abs(relative).argmax()])), \
        float(estimate[seen].sum() / reference[seen].sum() - 1.0), views


def row(label, case, estimate, reference, tau, seconds, rays):
    mean, worst, bias, views = scores(case, estimate, reference, tau)
    return (f"  {label:<26} {100 * mean:5.1f} % {100 * worst:+5.0f} % {100 * bias:+5.1f} %  "
            + " ".join(f"{100 * b:+4.0f}" for b in views) + f"   {1e3 * seconds / rays:8.3f} ms/ray")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="slab_thin_forward,ball_forward")
    parser.add_argument("--thin", default="2", help="thresholds of sigma_t h under which the renderer scatters")
    parser.add_argument("--samples", default="256", help="paths per camera ray of the scattering render")
    parser.add_argument("--bounces", default="", help="the renderer's volume bounces to try (default: unlimited)")
    parser.add_argument("--traced-only", action="store_true", help="scatter only in voxels the bake traces")
    parser.add_argument("--scales", default=str(firncore.SCATTER_SCALE),
                        help="the shares' voxels in density voxels (1: the density's own)")
    parser.add_argument("--cache", default=bake_suite.CACHE)
    args = parser.parse_args()
    print(f"firncore {firncore.__version__}, {firncore.hardware_threads()} threads; per case: mean, worst, bias, "
          "per-view bias, render cost (wall seconds per camera ray over the threads)")
    with tempfile.TemporaryDirectory() as folder:
        for name in args.cases.split(","):
            case = bake_suite.case(name)
            path = os.path.join(folder, name + ".vdb")
            run = bake_suite.baked_case(case, path, args.cache)
            origins, directions, tau, reference = run.origins, run.directions, run.tau, run.mean
            depth = case.sigma_t / case.rho * case.density.max() * case.voxel
            print(f"{name} (densest voxel's sigma_t h {depth:.2f}; views {case.views})")
            start = time.perf_counter()
            baked = firncore.render_baked(path, case.optics, origins, directions, occluders=case.occluders)
            print(row("baked (render_baked)", case, baked, reference, tau, time.perf_counter() - start, len(origins)))
            bounces = [int(x) for x in args.bounces.split(",")] if args.bounces else [1 << 30]
            for thin, samples, bounce, scale in itertools.product(
                    [float(x) for x in args.thin.split(",")], [int(x) for x in args.samples.split(",")], bounces,
                    [int(x) for x in args.scales.split(",")]):
                start = time.perf_counter()
                mixed, _ = firncore.render_scattering_where_thin(
                    path, case.optics, origins, directions, suns=case.suns(), sky=case.skies(),
                    occluders=case.occluders, samples=samples, seed=5, thin_depth=thin, bounces=bounce,
                    traced_only=args.traced_only, scatter_scale=scale)
                label = (f"scatter below {thin:g}, {samples} spp" + (f", {bounce} b" if bounce < 1 << 30 else "")
                         + f", x{scale}")
                print(row(label, case, mixed, reference, tau, time.perf_counter() - start, len(origins)),
                      flush=True)


if __name__ == "__main__":
    main()
