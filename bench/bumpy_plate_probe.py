"""bumpy_plate's error by where the camera ray meets the snow, with the scene's light terms switched one at a time in
the Monte Carlo and the bake alike (docs/bake.md, "bumpy_plate's shadow and cut sides, measured").

Regions: blocks whose ray meets the snow (optical depth 1) under the plate's footprint, the cut sides (the views'
first and last columns) and the rest of the top. Variants: full, no plate, black plate, white plate, grey ground,
sun only, sky only. References are cached per variant and path count in --cache (its own folder, not the suite's).

    PYTHONPATH=build/python python3 bench/bumpy_plate_probe.py [--samples 1024] [--cache DIR] [VARIANT ...]
"""

import argparse
import copy
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore

VARIANTS = ("full", "no plate", "black plate", "white plate", "grey ground", "sun only", "sky only")


def variant(case, name):
    c = copy.copy(case)
    plate, ground = case.occluders
    if name == "no plate":
        c.occluders = [ground]
    elif name in ("black plate", "white plate"):
        c.occluders = [(plate[0], plate[1], (0.0 if name == "black plate" else 0.8,) * 3), ground]
    elif name == "grey ground":
        c.occluders = [plate, (ground[0], ground[1], (0.3,) * 3)]
    elif name == "sun only":
        c.sky = 0.0
    elif name == "sky only":
        c.sun = 0.0
    return c


def regions(case, origins, directions, seen):
    """Masks of the blocks by where each ray meets optical depth 1."""
    column = np.tile(np.arange(case.pixels), len(case.views) * case.pixels)
    side = (column == 0) | (column == case.pixels - 1)
    hit = bs.depth_one_points(case, origins, directions, seen)
    under = ~side & (hit[:, 0] > 0.08) & (hit[:, 0] < 0.22) & (hit[:, 1] > 0.03) & (hit[:, 1] < 0.27)
    return {"under plate": under & seen, "cut sides": side & seen, "rest of top": ~side & ~under & seen}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("variants", nargs="*", default=list(VARIANTS))
    parser.add_argument("--samples", type=int, default=1024)
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_bumpy_probe"))
    args = parser.parse_args()
    os.makedirs(args.cache, exist_ok=True)
    case = next(c for c in bs.cases() if c.name == "bumpy_plate")
    origins, directions, tau = bs.views(case)
    seen = tau >= 1.0
    masks = regions(case, origins, directions, seen)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "bumpy.vdb")
        bs.write_density(path, case.density, case.voxel)
        for name in args.variants:
            c = variant(case, name)
            file = os.path.join(args.cache, f"{name.replace(' ', '_')}_{args.samples}.npz")
            if os.path.exists(file):
                reference = np.load(file)["reference"]
            else:
                reference = np.full((len(origins), 3), np.nan)
                reference[seen] = firncore.monte_carlo_radiance(path, c.optics, origins[seen], directions[seen],
                                                                suns=c.suns(), sky=c.skies(), occluders=c.occluders,
                                                                samples=args.samples, seed=11)[0]
                np.savez(file, reference=reference)
            firncore.bake(path, c.optics, suns=c.suns(), sky=c.skies(), occluders=c.occluders, quality="FINAL", seed=0)
            baked = firncore.render_baked(path, c.optics, origins, directions, occluders=c.occluders)
            parts = []
            for region, m in masks.items():
                bias = ",".join(f"{100 * (baked[m, k].sum() / reference[m, k].sum() - 1):+5.1f}" for k in range(3))
                parts.append(f"{region}: bias R,G,B {bias} mean|e| {100 * np.abs(baked[m] / reference[m] - 1).mean():4.1f}")
            every = np.abs(baked[seen] / reference[seen] - 1).mean()
            print(f"{name:>12}: all mean {100 * every:4.1f} bias {100 * (baked[seen].sum() / reference[seen].sum() - 1):+5.1f} | "
                  + " | ".join(parts), flush=True)


if __name__ == "__main__":
    main()
