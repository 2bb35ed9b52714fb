"""The mixed form at the renderer's volume bounces, with the renderer scattering the small pieces whole up to a bound
(docs/benchmarks.md, spray-lumpscatter, spray-gate): per case and bake seed one bake, then the bench's mixed render
(render_scattering_where_thin, traced_only, seeded 1000 + seed) for every bound on a lump's sum of (sigma_tr h)^3
and every bounce limit; mean |error|, bias of the sum, worst block and the bias per view against the cached
reference. The bound is read by the core from FIRN_LUMP at each call (bench/spray_gate_switch.diff); with `--bounces`
the render stops a path after that many scatterings past the first, each lit by the lights, as Cycles' Volume
bounces do (0: single scattering).

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/spray_gate_probe.py --cases spray_dense --bounds 0,20,1024 \
        --bounces 16,32,0 --paths 4096   (bounces 0 here: unlimited)
"""

import argparse
import os
import tempfile
import time

import numpy as np

import bake_suite
import firncore


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="spray_dense,spray_lumps")
    parser.add_argument("--cache", default=bake_suite.CACHE)
    parser.add_argument("--seeds", default="0", help="comma-separated bake seeds")
    parser.add_argument("--bounds", default="0,1024", help="FIRN_LUMP values: a lump's sum of (sigma_tr h)^3")
    parser.add_argument("--bounces", default="32,0", help="the renderer's volume bounces (0: unlimited)")
    parser.add_argument("--paths", type=int, default=4096)
    args = parser.parse_args()
    for name in args.cases.split(","):
        case = bake_suite.case(name)
        for seed in [int(s) for s in args.seeds.split(",")]:
            with tempfile.TemporaryDirectory() as folder:
                path = os.path.join(folder, name + ".vdb")
                os.environ["FIRN_LUMP"] = "0"
                run = bake_suite.baked_case(case, path, args.cache, "FINAL", seed)
                seen = run.tau >= 1.0
                baked = firncore.render_baked(path, case.optics, run.origins, run.directions, occluders=case.occluders)
                b = bake_suite.scored(case, baked, run.mean, seen)
                print(f"{name} seed {seed}: baked mean {100 * b['mean']:.2f} %, bias {100 * b['bias']:+.1f} %", flush=True)
                for bound in args.bounds.split(","):
                    os.environ["FIRN_LUMP"] = bound
                    voxels = len(firncore.scatter_voxels(path, case.optics, occluders=case.occluders))
                    for bounces in [int(x) for x in args.bounces.split(",")]:
                        start = time.perf_counter()
                        render, error = firncore.render_scattering_where_thin(
                            path, case.optics, run.origins, run.directions, suns=case.suns(), sky=case.skies(),
                            occluders=case.occluders, samples=args.paths, seed=1000 + seed, traced_only=True,
                            bounces=bounces if bounces > 0 else 1 << 30)
                        s = bake_suite.scored(case, render, run.mean, seen)
                        noise = float(np.median(error[seen] / np.maximum(render[seen], 1e-30)))
                        print(f"  bound {bound:>6} ({voxels:4d} scattered voxels), bounces {bounces or 'inf':>4}: mean "
                              f"{100 * s['mean']:5.2f} %, bias {100 * s['bias']:+6.1f} %, worst {100 * s['worst_signed']:+4.0f} %,"
                              f" views " + " ".join(f"{100 * v:+5.1f}" for v in s["view_bias"]) +
                              f"  (render noise {100 * noise:.1f} %, {time.perf_counter() - start:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
