"""bumpy_plate's per-block error decomposed by where the camera ray meets the snow, per view and per light
(docs/benchmarks.md, "plate-err").

Regions (by the point where each block's ray reaches optical depth 1; precedence in this order): the layer's cut
sides (within 1.5 voxels of the grid's x or y bounds), under the plate's footprint, the plate's edge (a 3 cm ring
around its footprint), and the bumps by the height of the surface's sine there, s = sin(2πx/14h)·cos(2πy/11h):
tops (s > 0.5), valleys (s < −0.5), and the sides between, split into those facing the sun (azimuth 0: the
surface falls towards +x) and those facing away. Printed per region: its blocks, its share of the summed
|relative error|, its mean |error| and its bias (sum baked / sum reference − 1).

Lights: "full" against the suite's cached 4096-path reference; "sun only" and "sky only" against fresh core Monte
Carlo references of --samples paths (cached in --cache; their median relative noise printed).

--worst N lists the N worst blocks of the first light (green): view, pixel (row from the top, column), the depth-one
point, region, and each light's error and reference radiance there.

    PYTHONPATH=build/python python3 bench/plate_err_regions.py [--samples 2048] [--cache DIR] [--lights full,sun,sky]
        [--worst N]
"""

import argparse
import copy
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore

REGIONS = ("cut sides", "under plate", "plate edge", "bump tops", "sides to sun", "sides away", "valleys")


def region_of(case, hit, seen):
    """Each block's region name (the module's docstring) from its depth-one point; "" for blocks not seen."""
    h = case.voxel
    x, y = hit[:, 0], hit[:, 1]
    last = (case.density.shape[0] - 1) * h
    side = (x < 1.5 * h) | (x > last - 1.5 * h) | (y < 1.5 * h) | (y > last - 1.5 * h)
    plate = case.occluders[0][0]
    lo, hi = plate.min(0), plate.max(0)
    under = (x >= lo[0]) & (x <= hi[0]) & (y >= lo[1]) & (y <= hi[1])
    ring = (x >= lo[0] - 0.03) & (x <= hi[0] + 0.03) & (y >= lo[1] - 0.03) & (y <= hi[1] + 0.03)
    s = np.sin(2 * np.pi * x / (14 * h)) * np.cos(2 * np.pi * y / (11 * h))
    falls_to_sun = np.cos(2 * np.pi * x / (14 * h)) * np.cos(2 * np.pi * y / (11 * h)) < 0.0  # d(top)/dx < 0
    label = np.full(len(hit), "", dtype=object)
    order = [("cut sides", side), ("under plate", under), ("plate edge", ring), ("bump tops", s > 0.5),
             ("valleys", s < -0.5), ("sides to sun", falls_to_sun), ("sides away", np.ones(len(hit), bool))]
    for name, mask in order:
        label[(label == "") & mask & seen] = name
    return label


def light_case(case, light):
    c = copy.copy(case)
    if light == "sun":
        c.sky = 0.0
    elif light == "sky":
        c.sun = 0.0
    return c


def report(title, baked, reference, label, view, views):
    with np.errstate(invalid="ignore", divide="ignore"):  # blocks not seen: NaN, left out below
        rel = np.abs(baked / reference - 1.0)  # (N, 3)
    seen = label != ""
    total = rel[seen].sum()
    print(f"{title}: mean {100 * rel[seen].mean():.1f} %, bias {100 * (baked[seen].sum() / reference[seen].sum() - 1):+.1f} %")
    print(f"  {'region':<13} {'blocks':>6} {'share':>6} {'mean':>6} {'bias':>7}   " +
          "   ".join(f"{str(v):>9} share/mean/bias" for v in views))
    for name in REGIONS:
        m = label == name
        if not m.any():
            continue
        per_view = []
        for v in range(len(views)):
            mv = m & (view == v)
            per_view.append(f"{100 * rel[mv].sum() / total:5.1f} {100 * rel[mv].mean():5.1f} "
                            f"{100 * (baked[mv].sum() / reference[mv].sum() - 1):+6.1f}" if mv.any() else " " * 18)
        print(f"  {name:<13} {3 * m.sum():>6} {100 * rel[m].sum() / total:5.1f}% {100 * rel[m].mean():5.1f}% "
              f"{100 * (baked[m].sum() / reference[m].sum() - 1):+6.1f}%   " + "     ".join(per_view), flush=True)


def worst_blocks(count, results, label, hit, case):
    """The `count` worst blocks of the first light by green |relative error|, with every light's error there."""
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = {light: baked[:, 1] / reference[:, 1] - 1.0 for light, (baked, reference) in results.items()}
    first = np.where(label != "", np.abs(rel[next(iter(results))]), -1.0)
    order = np.argsort(-np.nan_to_num(first, nan=-1.0))[:count]
    per = case.pixels ** 2
    print("worst blocks (green): view, row from the top, column, depth-one point (cm), region, " +
          ", ".join(f"{light} error / reference" for light in results))
    for i in order:
        v, p = divmod(int(i), per)
        row, column = case.pixels - 1 - p // case.pixels, p % case.pixels
        point = " ".join(f"{100 * x:5.1f}" for x in hit[i])
        errors = "   ".join(f"{100 * rel[light][i]:+6.1f} % / {results[light][1][i, 1]:.4g}" for light in results)
        print(f"  {str(case.views[v]):>9} {row:2d} {column:2d}  ({point})  {label[i]:<12} {errors}")


def light_arguments(parser):
    """baked_against_lights' options: --samples, --cache, --suite-cache, --lights."""
    parser.add_argument("--samples", type=int, default=2048)
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_plate_err"))
    parser.add_argument("--suite-cache", default=bs.CACHE)
    parser.add_argument("--lights", default="full,sun,sky")


def baked_against_lights(case, args, origins, directions, seen):
    """Per light of args.lights: (light, title with the reference's median relative noise, baked, reference), the
    FINAL bake (seed 0) rendered along the rays; "full" against the suite's cached reference (args.suite_cache), "sun"
    and "sky" against bake_suite.cached_monte_carlo of args.samples paths (seed 11) in args.cache."""
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "bumpy.vdb")
        bs.write_density(path, case.density, case.voxel)
        for light in args.lights.split(","):
            c = light_case(case, light)
            if light == "full":
                reference, error, _ = bs.reference(case, path, origins, directions, args.suite_cache)
                title = f"full (suite reference, {case.samples} paths)"
            else:
                file = os.path.join(args.cache, f"{light}_{args.samples}.npz")
                reference, error, _ = bs.cached_monte_carlo(file, c, path, origins, directions, args.samples, seed=11)
                title = f"{light} only ({args.samples} paths)"
            noise = np.median(error[seen] / np.maximum(reference[seen], 1e-30))
            firncore.bake(path, c.optics, suns=c.suns(), sky=c.skies(), occluders=c.occluders, quality="FINAL", seed=0)
            baked = firncore.render_baked(path, c.optics, origins, directions, occluders=c.occluders)
            yield light, f"{title}, reference noise {100 * noise:.1f} %", baked, reference


def main():
    parser = argparse.ArgumentParser()
    light_arguments(parser)
    parser.add_argument("--worst", type=int, default=0, help="list this many worst blocks")
    args = parser.parse_args()
    case = bs.case("bumpy_plate")
    origins, directions, tau = bs.views(case)
    seen = tau >= 1.0
    hit = bs.depth_one_points(case, origins, directions, seen)
    label = region_of(case, hit, seen)
    view = np.repeat(np.arange(len(case.views)), case.pixels ** 2)
    results = {}
    for light, title, baked, reference in baked_against_lights(case, args, origins, directions, seen):
        report(title, baked, reference, label, view, case.views)
        results[light] = (baked, reference)
    if args.worst:
        worst_blocks(args.worst, results, label, hit, case)


if __name__ == "__main__":
    main()
