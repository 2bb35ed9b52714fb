"""A sun low over a thick flat slab: the bake against the core's Monte Carlo per sun elevation, from above and from
four sides at 30 degrees (docs/benchmarks.md, grazing-sun). The slab, views and sun (1 W/m^2 on the top) are
lamp_slab_pieces.py's; the snows its grey and issue ones, and the grey one at other optical depths per voxel
("grey2": 2 per cm, "grey20": 20 per cm; the voxel 1 cm) to tell the voxel's optical size from the angle.

    PYTHONPATH=build/python:bench python3 bench/grazing_sun.py [--snows grey,issue] [--elevations 3,5,10,15,20,30]
        [--samples 4096]
"""

import argparse
import os
import tempfile

import lamp_slab_pieces as pieces

pieces.SNOWS.update({"grey2": (0.9, 0.6, 2.0), "grey20": (0.9, 0.6, 20.0)})


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--snows", default="grey,issue")
    parser.add_argument("--elevations", default="3,5,10,15,20,30")
    parser.add_argument("--samples", type=int, default=4096)
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_grazing_sun"))
    args = parser.parse_args()
    os.makedirs(args.cache, exist_ok=True)
    print("snow    sun    bias     per view (0, 90, 180, 270 at 30 deg; above)   mean |err|")
    for snow in args.snows.split(","):
        for elevation in args.elevations.split(","):
            bias, views, error = pieces.measure(args.cache, snow, f"sun{elevation}", args.samples, args.cache)
            per = " ".join(f"{100 * v:+6.1f}" for v in views)
            print(f"{snow:6s} {elevation:>3s} deg {100 * bias:+6.1f} %   {per} %   {100 * error:5.1f} %", flush=True)


if __name__ == "__main__":
    main()
