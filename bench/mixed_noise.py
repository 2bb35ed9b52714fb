"""The mixed render's own path noise in the suite's mean |error| (docs/bake.md, the mixed form; docs/benchmarks.md,
mixed-head).

bench/bake_suite.py's mixed rows render the bake as Cycles renders Scatter Thin Snow (`render_scattering_where_thin`,
path traced in the traced thin voxels): a Monte Carlo render whose noise adds to each block's error, so a case's mean
|error| reads too high by an amount that shrinks with the paths per block. Per case (seed-0 bake, the cached
references): independent renders (each its own seed) at each count of paths, two apiece, and their pool (every
path of every render, weighted by its count), the nearest to a converged render this run has. Printed per count:
the two renders' mean |error|, their difference (the seed-to-seed spread), the excess of their mean over the pool's
(the noise's inflation of the mean error), the blocks' median relative standard error and the render's wall
seconds. The pool's own excess is about the largest count's times largest / pooled paths (the inflation of a block
whose error exceeds its noise falls as 1 / paths). Cases whose renderer scatters nowhere (no traced thin voxel: a
render with no noise) are skipped.

    PYTHONPATH=build/python python3 bench/mixed_noise.py [--cases ball_thin,spray_dense] [--paths 2048,4096,8192]
"""

import argparse
import os
import tempfile
import time

import numpy as np

import bake_suite as S


def mixed_render(case, path, run, paths, seed):
    """The bake rendered as bake_suite's mixed rows render it: (mean, standard error) per block, wall seconds."""
    start = time.perf_counter()
    mean, error = S.firncore.render_scattering_where_thin(path, case.optics, run.origins, run.directions,
                                                          suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                                                          samples=paths, seed=seed, traced_only=True)
    return mean, error, time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="", help="comma-separated case names (default: all with thin snow scattered)")
    parser.add_argument("--paths", default="1024,2048,4096,8192,16384", help="paths per block of the renders")
    parser.add_argument("--cache", default=S.CACHE)
    args = parser.parse_args()
    counts = [int(x) for x in args.paths.split(",")]
    chosen = [c for c in S.cases() if not args.cases or c.name in args.cases.split(",")]
    print(f"firncore {S.firncore.__version__}: the mixed render's noise, two renders per count (seeds 2000 + 2 k, "
          f"2001 + 2 k), their pool of {2 * sum(counts)} paths per block", flush=True)
    with tempfile.TemporaryDirectory() as folder:
        for case in chosen:
            path = os.path.join(folder, case.name + ".vdb")
            run = S.baked_case(case, path, args.cache)
            seen = run.tau >= 1.0
            probe, error, _ = mixed_render(case, path, run, 16, 1)
            if not error[seen].any():
                print(f"  {case.name}: no thin snow scattered (the mixed render is the baked one)", flush=True)
                continue
            renders, pooled = [], np.zeros_like(probe)
            for k, paths in enumerate(counts):
                for s in range(2):
                    mean, error, seconds = mixed_render(case, path, run, paths, 2000 + 2 * k + s)
                    renders.append((paths, S.scored(case, mean, run.mean, seen)["mean"],
                                    float(np.median(error[seen] / np.maximum(mean[seen], 1e-30))), seconds))
                    pooled += paths * mean
            pool = S.scored(case, pooled / (2 * sum(counts)), run.mean, seen)["mean"]
            print(f"  {case.name}: pooled {2 * sum(counts)} paths: mean {100 * pool:.2f} % (ref noise "
                  f"{100 * np.median(run.error[seen] / np.maximum(run.mean[seen], 1e-30)):.1f} %)", flush=True)
            for k, paths in enumerate(counts):
                (_, a, noise, ta), (_, b, _, tb) = renders[2 * k], renders[2 * k + 1]
                print(f"    {paths:>6} paths: means {100 * a:5.2f} {100 * b:5.2f} %, apart {100 * abs(a - b):4.2f}, "
                      f"over the pool {100 * ((a + b) / 2 - pool):+5.2f} points; block noise {100 * noise:4.1f} %; "
                      f"render {(ta + tb) / 2:6.1f} s", flush=True)


if __name__ == "__main__":
    main()
