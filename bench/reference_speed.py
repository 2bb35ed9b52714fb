"""The Monte Carlo reference's speed and sameness across two builds: a suite case's views
(`firncore.monte_carlo_radiance`, `--samples` paths per ray, seed 11) rendered by each build in its own process,
alternating pairs (A B, B A, ...: the machine's load shared alike), with the processor seconds of each render and
the load average; then whether both builds' radiances are identical to the bit, and the same for the render that
scatters in the thin snow (`render_scattering_where_thin` on the case baked once by the first build).

    /usr/bin/python3 bench/reference_speed.py BUILD_A/python BUILD_B/python [--case ball_forward] [--samples 256]
        [--rounds 3]
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

RENDER = r"""
import hashlib, json, os, sys, time
sys.path.insert(0, sys.argv[1])
sys.path.insert(1, sys.argv[2])
import bake_suite, firncore
case, path, samples, what = bake_suite.case(sys.argv[3]), sys.argv[4], int(sys.argv[5]), sys.argv[6]
origins, directions, _ = bake_suite.views(case)
load = os.getloadavg()[0]
began, wall = time.process_time(), time.perf_counter()
if what == "reference":
    mean, _ = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(), sky=case.skies(),
                                            occluders=case.occluders, samples=samples, seed=11)
else:
    mean, _ = firncore.render_scattering_where_thin(path, case.optics, origins, directions, suns=case.suns(),
                                                    sky=case.skies(), occluders=case.occluders, samples=samples, seed=5)
print(json.dumps({"cpu_s": time.process_time() - began, "wall_s": time.perf_counter() - wall, "load": load,
                  "sha": hashlib.sha256(mean.tobytes()).hexdigest()[:16]}))
"""


def render(build, case, path, samples, what):
    bench = os.path.dirname(os.path.abspath(__file__))
    out = subprocess.run([sys.executable, "-c", RENDER, os.path.abspath(build), bench, case, path, str(samples), what],
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("builds", nargs=2, help="two folders holding firncore (build/python)")
    parser.add_argument("--case", default="ball_forward")
    parser.add_argument("--samples", type=int, default=256)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    sys.path[:0] = [os.path.abspath(args.builds[0]), os.path.dirname(os.path.abspath(__file__))]
    import bake_suite
    import firncore

    case = bake_suite.case(args.case)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        runs = {b: [] for b in args.builds}
        for r in range(args.rounds):
            for b in (args.builds if r % 2 == 0 else args.builds[::-1]):
                runs[b].append(render(b, case.name, path, args.samples, "reference"))
        for b in args.builds:
            cpu = [x["cpu_s"] for x in runs[b]]
            print(f"{b}: reference {args.case}, {args.samples} paths per ray: processor s "
                  + ", ".join(f"{x:.2f}" for x in cpu) + f" (min {min(cpu):.2f}); load "
                  + ", ".join(f"{x['load']:.1f}" for x in runs[b]) + f"; radiance sha {runs[b][0]['sha']}")
        same = len({x["sha"] for b in args.builds for x in runs[b]}) == 1
        print(f"reference radiances identical across builds and runs: {same}")
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders, quality="FINAL")
        mixed = {b: render(b, case.name, path, args.samples, "mixed") for b in args.builds}
        print("render_scattering_where_thin: " + ", ".join(f"{b} sha {m['sha']} ({m['cpu_s']:.2f} processor s)"
                                                          for b, m in mixed.items())
              + f"; identical: {len({m['sha'] for m in mixed.values()}) == 1}")


if __name__ == "__main__":
    main()
