"""bumpy_plate's top seen row by row across the layer (docs/benchmarks.md, "plate-ramp"): where along y the baked top
is too bright or too dark.

Parallel rays of one view from the points (x, y, 14 voxels), above the snow and under the plate (z 22 voxels: rays
started further back would meet it), for x 3-26 (every voxel: the bumps' phases along x averaged out), one row per y
(voxel index; the cut sides' half density at -0.5 and 29.5); per row the baked render against the core's Monte Carlo
(green, summed over the row), FINAL, seed 0.
The rows y 0, 11 and 22 cross the bumps at the same phase (cos(2 pi y / 11 h) = 1).

    PYTHONPATH=build/python /usr/bin/python3 bench/plate_edge_profile.py [--view 180,50] [--light full|sun|sky]
        [--rows -0.35,0,0.5,1,2,4,8,11,22,29] [--samples 2048]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore
from plate_err_regions import light_case


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--view", default="180,50", help="azimuth, elevation (degrees)")
    parser.add_argument("--light", default="full", choices=("full", "sun", "sky"))
    parser.add_argument("--rows", default="-0.35,0,0.5,1,2,4,8,11,22,29")
    parser.add_argument("--samples", type=int, default=2048)
    args = parser.parse_args()
    case = light_case(next(c for c in bs.cases() if c.name == "bumpy_plate"), args.light)
    h = case.voxel
    azimuth, elevation = (math.radians(float(v)) for v in args.view.split(","))
    back = np.array([math.cos(azimuth) * math.cos(elevation), math.sin(azimuth) * math.cos(elevation),
                     math.sin(elevation)])  # towards the camera
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "bumpy.vdb")
        bs.write_density(path, case.density, h)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders, quality="FINAL",
                      seed=0)
        print(f"bumpy_plate, view ({args.view}), {args.light} light: green, rows summed over x 3-26")
        for y in (float(v) for v in args.rows.split(",")):
            origins = np.array([[x * h, y * h, 14 * h] for x in range(3, 27)])
            directions = np.tile(-back, (len(origins), 1))
            reference = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                                      sky=case.skies(), occluders=case.occluders,
                                                      samples=args.samples, seed=5)[0]
            baked = firncore.render_baked(path, case.optics, origins, directions, occluders=case.occluders)
            print(f"  y {y:6.2f}: baked {baked[:, 1].mean():.4f}, Monte Carlo {reference[:, 1].mean():.4f}, "
                  f"{100 * (baked[:, 1].sum() / reference[:, 1].sum() - 1):+.1f} %", flush=True)


if __name__ == "__main__":
    main()
