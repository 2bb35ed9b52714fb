"""Where the suite's balls seen against the sun miss their light (docs/benchmarks.md, against-sun).

bench/bake_suite.py's cases (FINAL, --seed, their cached Monte Carlo references): each case's mean |relative error| to
two decimals, its bias and its views' biases; for a ball's view (180, 0) its seen blocks (green channel) split by the
ball's normal at the block ray's optical depth 1 point (backlit_probe's regions): mu0, the cosine from that normal to
the sun, in bands (the lit limb, the terminator band |mu0| < 0.15, the shadowed limb, the shadowed face), and by the
ray's whole optical depth (rim: under 30, the light the skin carries round the limb; core: light through the ball):
reference and baked sums, the baked render's peaked lobes' part (its grids firn_source_peak* cleared), the share of
the view's deficit each holds; --blocks lists the limb ring's blocks. The sum of the means when all 17 run.

    PYTHONPATH=build/python:bench python3 bench/against_sun.py [--cases ball_issue,ball_rgb] [--seed 0] [--blocks]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite as S
from backlit_probe import sun_towards, write_without_peaks

BANDS = ((0.15, 1.01, "lit limb"), (-0.15, 0.15, "terminator"), (-0.35, -0.15, "dark limb"),
         (-1.01, -0.35, "dark face"))


def limb_bands(case, origins, directions, tau):
    """The view (180, 0)'s rays by the ball's normal at their optical depth 1 point: mu0 band and rim (tau under 30)
    or core, as (band label, rim label, mask over the view's rays); the view's seen mask and its slice of the rays.
    None where the case has no such view or is no ball."""
    per = case.pixels ** 2
    v = [i for i, view in enumerate(case.views) if tuple(view) == (180, 0)]
    if not v or not case.name.startswith("ball"):
        return None
    s = slice(v[0] * per, (v[0] + 1) * per)
    seen = tau[s] >= 1.0
    hit = S.depth_one_points(case, origins[s], directions[s], seen)
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    normal = (hit - centre) / np.linalg.norm(hit - centre, axis=1)[:, None]
    mu0 = normal @ sun_towards()
    bands = [(what, label, seen & (mu0 >= lo) & (mu0 < hi) & ((tau[s] < 30.0) == rim), lo, mu0)
             for lo, hi, what in BANDS for rim, label in ((True, "rim"), (False, "core"))]
    return s, seen, bands


def against_regions(case, origins, directions, tau, mean, baked, broad, blocks=False):
    split = limb_bands(case, origins, directions, tau)
    if split is None:
        return
    s, seen, bands = split
    m, b, p = mean[s, 1], baked[s, 1], baked[s, 1] - broad[s, 1]
    missing = m[seen].sum() - b[seen].sum()
    print(f"    (180, 0): reference {m[seen].sum():.4f}, baked {b[seen].sum():.4f}, missing {missing:+.4f}")
    for what, label, k, lo, mu0 in bands:
        if k.sum():
            gap = m[k].sum() - b[k].sum()
            print(f"      {what:<10} {label:<4} {k.sum():2d} blocks: reference {m[k].sum():.4f}, "
                  f"baked {b[k].sum():.4f} ({b[k].sum() / m[k].sum() - 1:+6.1%}; peaked {p[k].sum():.4f}), "
                  f"missing {gap:+.4f} ({gap / missing:+5.0%} of the view's)")
            if blocks and label == "rim" and lo > -0.3:
                for j in np.nonzero(k)[0]:
                    print(f"        block {j:2d}: tau {tau[s][j]:5.1f}, mu0 {mu0[j]:+.2f}, reference {m[j]:.4f}, "
                          f"baked {b[j]:.4f} ({b[j] / m[j] - 1:+6.1%}; peaked {p[j]:.4f})")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--blocks", action="store_true", help="list the limb ring's blocks (view (180, 0))")
    parser.add_argument("--cache", default=S.CACHE)
    args = parser.parse_args()
    chosen = [c for c in S.cases() if not args.cases or c.name in args.cases.split(",")]
    total = 0.0
    with tempfile.TemporaryDirectory() as folder:
        for case in chosen:
            r = S.run_case(case, folder, args.cache, "FINAL", args.seed)
            total += 100 * r["mean"]
            print(f"  {case.name:<18} mean {100 * r['mean']:5.2f} %  worst {100 * r['worst_signed']:+4.0f} %  bias "
                  f"{100 * r['bias']:+5.2f} %  views " + " ".join(f"{100 * x:+5.1f}" for x in r["view_bias"]) +
                  f"  traced {r['traced']} x {r['traced_paths']} ({r['light_traced']} light traced, {r['trace_cpu_s']:.2f} processor s)",
                  flush=True)
            path = os.path.join(folder, case.name + ".vdb")
            origins, directions, tau = S.views(case)
            mean, _, _ = S.reference(case, path, origins, directions, args.cache)
            baked = S.firncore.render_baked(path, case.optics, origins, directions, occluders=case.occluders)
            write_without_peaks(path, path + ".broad.vdb")
            broad = S.firncore.render_baked(path + ".broad.vdb", case.optics, origins, directions,
                                            occluders=case.occluders)
            against_regions(case, origins, directions, tau, mean, baked, broad, args.blocks)
    print(f"  sum of the {len(chosen)} means {total:.2f}")


if __name__ == "__main__":
    main()
