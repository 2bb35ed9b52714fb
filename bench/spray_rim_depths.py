"""Where along a camera ray a spray case's worst blocks take their error (docs/benchmarks.md, spray-rims).

Bakes the case (FINAL, --seed) against the suite's cached reference and, for its --worst blocks, starts the same ray
at the points where it has crossed optical depth 0, 0.25, 0.5, 1, 1.5, 2, 3 and 5 of snow: the radiance from each
start, baked (render_baked) and by the core's Monte Carlo (--paths per start). A segment's own light is
L(start) - T L(next start), T its transmittance; the baked over the Monte Carlo per segment says at which depth of
the ray the baked source is off (the first segments: the rim's first optical depth; deeper: the lump's inside).
Also prints, per segment, the voxel holding most of its extinction and that voxel's σt h.

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/spray_rim_depths.py [--case spray_dense] [--worst 8]
        [--paths 16384] [--seed 0]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import firncore

DEPTHS = np.array([0.0, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0])


def depth_profile(case, origin, direction):
    """Distances (m) along the ray where it has crossed DEPTHS of snow (inf past its total) and the ray's steps."""
    step = 0.02 * case.voxel
    s = np.arange(0.0, 2.0, step)
    sigma = bake_suite.trilinear(case.density, (origin + s[:, None] * direction) / case.voxel) * case.sigma_t / case.rho
    tau = np.concatenate([[0.0], np.cumsum(sigma[:-1] * step)])
    first = np.argmax(sigma > 0.0) - 1
    at = np.array([s[max(first, 0)] if d == 0.0 else (s[np.searchsorted(tau, d)] if d < tau[-1] else np.inf)
                   for d in DEPTHS])
    return at, s, tau, sigma


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="spray_dense")
    parser.add_argument("--worst", type=int, default=8)
    parser.add_argument("--paths", type=int, default=16384)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "s.vdb")
        run = bake_suite.baked_case(case, path, bake_suite.CACHE, "FINAL", args.seed)
        seen = run.tau >= 1.0
        render = firncore.render_baked(path, case.optics, run.origins, run.directions, occluders=case.occluders)
        s = bake_suite.scored(case, render[:, 1], run.mean[:, 1], seen)
        print(f"{case.name} seed {args.seed}: mean {100 * s['mean']:.2f} %, bias {100 * s['bias']:+.2f} %")
        rel = np.full(len(seen), 0.0)
        rel[seen] = s["relative"]
        order = np.argsort(-np.abs(rel))[:args.worst]
        starts, dirs, rows = [], [], []
        for b in order:
            at, steps, tau, sigma = depth_profile(case, run.origins[b], run.directions[b])
            ok = np.isfinite(at)
            rows.append((b, at, steps, tau, sigma, ok))
            for a in at[ok]:
                starts.append(run.origins[b] + a * run.directions[b])
                dirs.append(run.directions[b])
        starts, dirs = np.array(starts), np.array(dirs)
        baked = firncore.render_baked(path, case.optics, starts, dirs, occluders=case.occluders)[:, 1]
        mc, err = firncore.monte_carlo_radiance(path, case.optics, starts, dirs, suns=case.suns(), sky=case.skies(),
                                                occluders=case.occluders, samples=args.paths, seed=23)
        mc, err = mc[:, 1], err[:, 1]
    per = case.pixels ** 2
    i = 0
    for b, at, steps, tau, sigma, ok in rows:
        n = int(ok.sum())
        v, q = divmod(b, per)
        print(f"\nblock view {case.views[v]} row {q // case.pixels} col {q % case.pixels}: error {100 * rel[b]:+.1f} % "
              f"(reference {run.mean[b, 1]:.4f}), ray tau {run.tau[b]:.1f}")
        B, M, E = baked[i:i + n], mc[i:i + n], err[i:i + n]
        d = DEPTHS[ok]
        for k in range(n):
            line = (f"  from depth {d[k]:4.2f}: baked {B[k]:.4f}  MC {M[k]:.4f} +- {E[k]:.4f}  "
                    f"{100 * (B[k] / M[k] - 1):+6.1f} %")
            if k + 1 < n:
                T = np.exp(-(d[k + 1] - d[k]))
                cb, cm = B[k] - T * B[k + 1], M[k] - T * M[k + 1]
                ce = np.hypot(E[k], T * E[k + 1])
                mid = 0.5 * (at[ok][k] + at[ok][k + 1])
                lo, hi = np.searchsorted(steps, at[ok][k]), np.searchsorted(steps, at[ok][k + 1])
                j = lo + int(np.argmax(sigma[lo:hi])) if hi > lo else lo
                p = run.origins[b] + steps[j] * run.directions[b]
                voxel = tuple(int(x) for x in np.rint(p / case.voxel))
                vt = case.sigma_t * case.density[voxel] / case.rho * case.voxel
                line += (f"   segment {d[k]:.2f}-{d[k + 1]:.2f}: baked {cb:.4f} MC {cm:.4f} +- {ce:.4f} "
                         f"({100 * (cb / cm - 1) if cm > 0 else float('nan'):+6.1f} %), densest voxel {voxel} "
                         f"σt h {vt:.1f}")
            print(line)
        i += n


if __name__ == "__main__":
    main()
