"""bumpy_plate's light split into parts that both the bake and the core's Monte Carlo can isolate (docs/benchmarks.md,
"tread-light"): each variant zeroes an occluder's albedo (the plate's send-back, the reddish ground's bounce) or keeps
one light, and the difference between the first variant and each other is that part, in the truth and in the bake,
per region of bench/plate_err_regions.py (channels averaged, sums over the region's blocks).

Variants: "full", "noplate", "noground", "sun", "sky", or several joined by "+" ("sun+noplate"). The Monte Carlo of
each (seed 11, --samples paths; 4096 take about 90 s on one free core) is cached in --cache.

    PYTHONPATH=build/python /usr/bin/python3 bench/plate_light_parts.py [--variants full,noplate,noground]
        [--samples 4096] [--cache DIR]
"""

import argparse
import copy
import os
import tempfile

import bake_suite as bs
import firncore
from plate_err_regions import REGIONS, region_of

BLACK = (0.0, 0.0, 0.0)


def variant(case, name):
    """The case with the parts of `name` taken away."""
    out = copy.copy(case)
    plate, ground = case.occluders
    for part in name.split("+"):
        if part == "noplate":
            plate = (plate[0], plate[1], BLACK)
        elif part == "noground":
            ground = (ground[0], ground[1], BLACK)
        elif part == "sun":
            out.sky = 0.0
        elif part == "sky":
            out.sun = 0.0
        elif part != "full":
            raise ValueError(f"unknown part {part!r}")
    out.occluders = [plate, ground]
    return out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--variants", default="full,noplate,noground")
    parser.add_argument("--samples", type=int, default=4096)
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_plate_parts"))
    args = parser.parse_args()
    case = bs.case("bumpy_plate")
    origins, directions, tau = bs.views(case)
    seen = tau >= 1.0
    label = region_of(case, bs.depth_one_points(case, origins, directions, seen), seen)
    names = args.variants.split(",")
    light = {}  # variant: (baked, Monte Carlo), channels averaged
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "bumpy.vdb")
        bs.write_density(path, case.density, case.voxel)
        for name in names:
            c = variant(case, name)
            file = os.path.join(args.cache, f"{name}_{args.samples}.npz")
            truth, _, _ = bs.cached_monte_carlo(file, c, path, origins, directions, args.samples, seed=11)
            firncore.bake(path, c.optics, suns=c.suns(), sky=c.skies(), occluders=c.occluders, quality="FINAL", seed=0)
            baked = firncore.render_baked(path, c.optics, origins, directions, occluders=c.occluders)
            light[name] = (baked.mean(1), truth.mean(1))
    print(f"bumpy_plate, {args.samples} paths: per variant the Monte Carlo's sum and the bake's error; per part "
          f"({names[0]} - variant) its share of {names[0]}'s light, truth / bake")
    print(f"{'region':12s}" + "".join(f"{n:>21s}" for n in names))
    first_baked, first_truth = light[names[0]]
    for region in ("all",) + REGIONS:
        m = seen if region == "all" else label == region
        line = f"{region:12s}"
        for name in names:
            baked, truth = light[name]
            line += f"  {truth[m].sum():8.4f} {100 * (baked[m].sum() / truth[m].sum() - 1):+6.1f} %"
        for name in names[1:]:
            baked, truth = light[name]
            total = first_truth[m].sum()
            line += (f" | {name} {100 * (first_truth[m].sum() - truth[m].sum()) / total:5.1f} / "
                     f"{100 * (first_baked[m].sum() - baked[m].sum()) / total:5.1f} %")
        print(line)


if __name__ == "__main__":
    main()
