"""bumpy_plate's sunlit +x wall seen from behind through its density ramp (docs/benchmarks.md, "bumpy-plate"): what
its corners' worst blocks see.

A camera over the layer's top looking towards +x (the suite's view (180, 50)) skims the layer's far corners through
the outer part of the +x wall's ramp, from behind the wall's exit: the light travelling into the wall. Rays of that
view start inside the ramp (x index 29.55, 29.7, 29.85: from 1.5 down to 0.17 optical depths of ramp left before
the air along the wall's normal, 2.4 down to 0.26 along the ray), 10 x 2 of them over the wall's middle (y 10-19, z 3 and 4), and leave through it; printed per depth: the
baked render against the core's Monte Carlo (green, summed), under the case's full light, the sun alone and the sky
alone.

    PYTHONPATH=build/python /usr/bin/python3 bench/ramp_from_behind.py [--samples 2048]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore
from plate_err_regions import light_case

STARTS_X = (29.55, 29.7, 29.85)  # voxel index: the wall's last voxel centre at 29, the air beyond 30


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=2048)
    args = parser.parse_args()
    case = next(c for c in bs.cases() if c.name == "bumpy_plate")
    h = case.voxel
    e = math.radians(50.0)
    along = np.array([math.cos(e), 0.0, -math.sin(e)])  # the (180, 50) camera's rays
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "bumpy.vdb")
        bs.write_density(path, case.density, h)
        for light in ("full", "sun", "sky"):
            c = light_case(case, light)
            firncore.bake(path, c.optics, suns=c.suns(), sky=c.skies(), occluders=c.occluders, quality="FINAL", seed=0)
            parts = []
            for x in STARTS_X:
                starts = np.array([[x * h, y * h, z * h] for y in range(10, 20) for z in (3.0, 4.0)])
                directions = np.tile(along, (len(starts), 1))
                reference = firncore.monte_carlo_radiance(path, c.optics, starts, directions, suns=c.suns(),
                                                          sky=c.skies(), occluders=c.occluders, samples=args.samples,
                                                          seed=3)[0]
                baked = firncore.render_baked(path, c.optics, starts, directions, occluders=c.occluders)
                parts.append(f"x {x}: baked {baked[:, 1].mean():.4f}, Monte Carlo {reference[:, 1].mean():.4f} "
                             f"({100 * (baked[:, 1].sum() / reference[:, 1].sum() - 1):+.0f} %)")
            print(f"{light:>4}: " + "; ".join(parts), flush=True)


if __name__ == "__main__":
    main()
