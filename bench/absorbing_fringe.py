"""ball_grey's ball (5 cm on 1 cm voxels, g 0.6, the suite's sun and sky and views) at other extinctions and albedos,
baked and rendered in both forms against its own Monte Carlo reference (docs/benchmarks.md, lead-88): where absorbing
snow is thin enough for a diffused body's fringe to be traced (σt h (1 − ω g) < 2), the mixed form draws that fringe's
traced values rather than scattering in it (bake::scatteredVoxels), and reads as the baked form does.

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/absorbing_fringe.py [--optics 300:0.9,200:0.9,300:0.95]
        [--mixed 32768]

--optics: sigma_t (1/m at the case's density) : omega pairs. The references are cached beside the suite's.
"""

import argparse
import dataclasses
import os
import tempfile

import bake_suite


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--optics", default="300:0.9,200:0.9,300:0.95")
    parser.add_argument("--mixed", type=int, default=bake_suite.MIXED_PATHS)
    args = parser.parse_args()
    base = bake_suite.case("ball_grey")
    os.makedirs(bake_suite.CACHE, exist_ok=True)
    for pair in args.optics.split(","):
        sigma_t, omega = (float(v) for v in pair.split(":"))
        case = dataclasses.replace(base, name=f"grey_{sigma_t:g}_{omega:g}", sigma_t=sigma_t, omega=(omega,) * 3)
        with tempfile.TemporaryDirectory() as folder:
            row = bake_suite.run_case(case, folder, bake_suite.CACHE, mixed=args.mixed)
        for r in (row, row["mixed"]):
            print(f"{r['case']}: sigma_t h {sigma_t * case.voxel:.1f}, omega {omega:g}, {row['traced']} traced voxels: "
                  f"mean {100 * r['mean']:.2f} %, worst {100 * r['worst_signed']:+.0f} %, bias {100 * r['bias']:+.2f} %",
                  flush=True)


if __name__ == "__main__":
    main()
