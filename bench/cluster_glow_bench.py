"""What a cluster's lumps send one another, without the shadows, against the core's Monte Carlo (branch block-depth,
docs/benchmarks.md "block-depth").

lumps_between_bench.py's cluster over the black ground (B at the centre of 3 x 3 x 3 lumps 6 cm apart, 400 far lumps)
under a sun that no neighbour hides B from: azimuth 22.5, elevation 17.6 degrees, every neighbour's centre at least
2.7 cm off B's sun line (the lumps are 2.4 cm wide). What the neighbours add to B is then their glow (and the light
they shade off one another), not B's shadow: baked (DRAFT) against the Monte Carlo's gain. Usage:
  PYTHONPATH=build/python /usr/bin/python3 bench/cluster_glow_bench.py [--samples 128] [--cache DIR]
"""

import argparse
import math
import os
import tempfile

from lumps_between_bench import cluster_density, measure, plane, views_of


# Towards the sun: azimuth 22.5, elevation 17.6 degrees, no neighbour's centre within 2.7 cm of B's sun line.
SUN_TOWARDS = (math.cos(math.radians(17.6)) * math.cos(math.radians(22.5)),
               math.cos(math.radians(17.6)) * math.sin(math.radians(22.5)), math.sin(math.radians(17.6)))


def sun_off_the_neighbours(firncore):
    return dict(suns=[firncore.SunLight(SUN_TOWARDS, (1.0,) * 3, 0.0093)], sky=firncore.Sky((0.0,) * 3))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=128, help="Monte Carlo paths per pixel")
    parser.add_argument("--cache", default=None, help="keep and reuse the Monte Carlo's sums in this folder")
    args = parser.parse_args()
    import firncore

    sun = sun_off_the_neighbours(firncore)
    path = os.path.join(tempfile.mkdtemp(), "lumps.vdb")
    sums = {}
    for neighbours in (False, True):
        density, centre, radius = cluster_density(1, neighbours)
        origins, directions = views_of(centre, radius, 14, 16)
        cached = os.path.join(args.cache, f"glow_{int(neighbours)}_{args.samples}.json") if args.cache else None
        sums[neighbours] = measure(firncore, path, density, origins, directions, sun, [plane(-0.03, 0.0)], args.samples,
                                   cached)
    (b0, m0, _), (b1, m1, e1) = sums[False], sums[True]
    print(f"cluster over black, the sun off every neighbour's line: B alone {100 * (b0 / m0 - 1):+.1f} %, among the "
          f"others {100 * (b1 / m1 - 1):+.1f} % ({100 * e1 / m1:.1f}); they add baked {100 * (b1 / b0 - 1):+.1f} %, "
          f"Monte Carlo {100 * (m1 / m0 - 1):+.1f} %")


if __name__ == "__main__":
    main()
