"""The balls baked and rendered as Cycles renders firn_scatter (docs/benchmarks.md, limb-trace): per case the baked
render's mean |error| and view biases, the mixed render's (the renderer scatters in the bake's thin traced snow and
the air beside it, bake_suite.run_case's `mixed`), and with --regions the mixed render's view (180, 0) by
against_sun.py's bands. With bench/limb_trace_switch.diff applied, FIRN_LIMB_SCATTER=1 FIRN_LIMB_TRACE="lo hi 0"
renders the renderer scattering in the skin voxels that switch selects.

    PYTHONPATH=build/python:bench python3 bench/limb_mixed.py [--paths 256] [--cases ball_issue,ball_grey] [--regions]
"""

import argparse
import os
import tempfile

import bake_suite as S
from against_sun import against_regions


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="ball_issue,ball_grey,ball_rgb,ball_snow,ball_clean,ball_forward")
    parser.add_argument("--paths", type=int, default=256, help="the mixed render's paths per block")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--regions", action="store_true")
    parser.add_argument("--cache", default=S.CACHE)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        for case in [c for c in S.cases() if c.name in args.cases.split(",")]:
            r = S.run_case(case, folder, args.cache, "FINAL", args.seed, 0, args.paths)
            for label, row in (("baked", r), ("mixed", r["mixed"])):
                print(f"  {case.name:<14} {label} mean {100 * row['mean']:5.2f} %  views " +
                      " ".join(f"{100 * x:+5.1f}" for x in row["view_bias"]), flush=True)
            if args.regions:
                path = os.path.join(folder, case.name + ".vdb")
                origins, directions, tau = S.views(case)
                mean, _, _ = S.reference(case, path, origins, directions, args.cache)
                mixed, _ = S.firncore.render_scattering_where_thin(
                    path, case.optics, origins, directions, suns=case.suns(), sky=case.skies(),
                    occluders=case.occluders, samples=args.paths, seed=1000 + args.seed, traced_only=True)
                against_regions(case, origins, directions, tau, mean, mixed, mixed)


if __name__ == "__main__":
    main()
