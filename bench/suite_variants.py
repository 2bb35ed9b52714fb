"""A suite case's per-region split (bench/suite_regions.py) for several variants of one build over the same seeds,
each variant named and chosen by environment variables that temporary switches in the core read (docs/benchmarks.md,
spray-lit-cores). Each (variant, seed)'s relative errors are cached in --runs, so a variant is baked once and main's
seeds serve every comparison; the core must read its switches at each call, not once per process.

    PYTHONPATH=build/python:bench python3 bench/suite_variants.py main wide:FIRN_SWITCH=1,FIRN_OTHER=2 --seeds 8
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import suite_regions


def variant(text):
    """'name:VAR=value,VAR=value' (or 'name' alone: no switch) as (name, {VAR: value})."""
    name, _, assignments = text.partition(":")
    return name, dict(a.split("=", 1) for a in assignments.split(",") if a)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("variants", nargs="+", type=variant)
    parser.add_argument("--case", default="spray_dense")
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--first", type=int, default=0, help="the first seed")
    parser.add_argument("--runs", default=os.path.join(tempfile.gettempdir(), "firn_suite_variants"))
    parser.add_argument("--cache", default=bake_suite.CACHE)
    args = parser.parse_args()
    if args.seeds < 2:
        parser.error("--seeds must be 2 or more (the spread across seeds)")
    seeds = range(args.first, args.first + args.seeds)
    switches = {var for _, env in args.variants for var in env}
    case = bake_suite.case(args.case)
    origins, directions, tau = bake_suite.views(case)
    seen, lit, core = suite_regions.regions(case, origins, directions, tau)
    os.makedirs(args.runs, exist_ok=True)
    run_file = lambda name, seed: os.path.join(args.runs, f"{case.name}_{name}_{seed}.npz")
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        reference, _, _ = bake_suite.reference(case, path, origins, directions, args.cache)
        for name, env in args.variants:
            for var in switches:
                os.environ.pop(var, None)
            os.environ.update(env)
            for seed in seeds:
                if not os.path.exists(run_file(name, seed)):
                    r = bake_suite.run_case(case, folder, args.cache, seed=seed)
                    np.savez(run_file(name, seed), relative=r["relative"], trace_cpu_s=r["trace_cpu_s"])
    reference = reference[seen]
    lit, core = lit[seen], core[seen]
    view = np.repeat(np.arange(len(case.views)), case.pixels ** 2)[seen]
    groups = [("all", np.ones(len(reference), bool)), ("lit, core", lit & core), ("lit, rim or thin", lit & ~core),
              ("shadowed, core", ~lit & core), ("shadowed, rim or thin", ~lit & ~core)]
    groups += [(f"view {v}", view == i) for i, v in enumerate(case.views)]
    for name, _ in args.variants:
        runs = [np.load(run_file(name, seed)) for seed in seeds]
        relative = np.array([r["relative"] for r in runs])  # seeds x blocks x channels
        renders = (relative + 1.0) * reference
        mean_render = renders.mean(0)
        spread = renders.std(0, ddof=1) / np.maximum(mean_render, 1e-30)
        print(f"{name}: one seed's means " + " ".join(f"{100 * np.abs(r).mean():.1f}" for r in relative) +
              f" %, mean {100 * np.abs(relative).mean():.2f} %, trace " +
              f"{np.mean([float(r['trace_cpu_s']) for r in runs]):.2f} processor s")
        for label, where in groups:
            print(suite_regions.row(label, relative[:, where], spread[where], mean_render[where], reference[where]))


if __name__ == "__main__":
    main()
