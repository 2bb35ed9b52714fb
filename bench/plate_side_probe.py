"""bumpy_plate's cut side by height and by the ground's albedo (docs/benchmarks.md, "plate-side"): whether the side's
excess over a dark ground is the bake's light (the side's voxels too bright whatever the camera) or the render's
blend of the edge voxel with the air beside it (only rays grazing the side's ramp too bright).

The snow's optics are grey, so the ground's three channels set to --albedo (0, 0.45, 0.9 by default) give three
grounds in one Monte Carlo and one bake. Ray sets, each against the core's Monte Carlo (--samples paths, seed 5):
  wall z=K     horizontal rays along +y at height K voxels onto the -y cut side (its half density at y -0.5), x 3-26
               (head on: the side's own radiance; the columns whose top is under K + 1 left out)
  top y=Y      rays straight down onto the top at row y Y voxels (x 3-26), Y -0.35 the suite's edge columns' plane
  graze y=Y    the suite's view (180, 50) at y Y (rays along the side's plane, started at x 3-26, z 14 voxels)
--shape slab: the same layer with a flat top 6 voxels thick (its half density at z 6.5), no bumps.
--edge-air above|across|all: rendered with edge_air_copied (the air around the cut top edge given the edge voxel's
own values). Printed per set and channel: the bake's error (sum baked / sum Monte Carlo - 1), the truth's and the
bake's gain from the darkest ground to the brightest, and the truth's radiance per ray.
--suite: instead, bumpy_plate's suite score (the cached reference) baked and with each edge_air_copied variant.

    PYTHONPATH=build/python /usr/bin/python3 bench/plate_side_probe.py [--shape bumpy|slab] [--lights sky,sun]
        [--albedo 0,0.45,0.9] [--samples 1024] [--walls 1,2,3,4,5,6] [--rows=-0.35,0,0.5,1,2,4,8]
        [--edge-air above|across|all] [--suite]
"""

import argparse
import math
import os
import tempfile

import numpy as np
import pyopenvdb

import bake_suite as bs
import firncore
from plate_ground_albedo import over_ground


def slab(side, depth, extra):
    X, Y, Z = bs.grid((side, side, depth + extra))
    fill = np.clip(depth - Z + 0.5, 0.0, 1.0)
    fill[:, :, 0] = 0.0
    return fill


def edge_air_copied(path, density, which, out):
    """The baked file at path written to out with the air voxels around the layer's cut top edge holding the edge
    voxel's own source values (an oracle: the render's blend of the edge with the air beside it, without the
    neighbours' light that facingAverage mixes in): "above" the air voxel over each cut side column's top snow voxel,
    "across" the one beyond the side beside it and the one diagonally above, "all" both."""
    grids, metadata = pyopenvdb.readAll(path)
    n = density.shape[0]
    targets = []
    for x in range(n):
        for y in range(n):
            outward = [o for o, on in (((-1, 0), x == 0), ((1, 0), x == n - 1), ((0, -1), y == 0),
                                       ((0, 1), y == n - 1)) if on]
            if not outward:
                continue
            z = int(np.nonzero(density[x, y] > 0)[0].max())
            if which in ("above", "all"):
                targets.append(((x, y, z), (x, y, z + 1)))
            if which in ("across", "all"):
                for dx, dy in outward:
                    targets += [((x, y, z), (x + dx, y + dy, z)), ((x, y, z), (x + dx, y + dy, z + 1))]
    copy_source_values(grids, metadata, targets, out)


def copy_source_values(grids, metadata, targets, out):
    """The baked grids (pyopenvdb.readAll's) written to out with each target voxel of targets ((source, target) index
    pairs) holding the source voxel's values in every firn_source grid."""
    for g in grids:
        if not g.name.startswith("firn_source"):
            continue
        accessor = g.getAccessor()
        values = [accessor.getValue(source) for source, _ in targets]
        for (_, target), value in zip(targets, values):
            accessor.setValueOn(target, value)
    pyopenvdb.write(out, grids=grids, metadata=metadata)


def suite_oracle():
    """bumpy_plate's suite score (the cached reference) baked, and with each edge_air_copied variant."""
    case = bs.case("bumpy_plate")
    origins, directions, tau = bs.views(case)
    seen = tau >= 1.0
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "bumpy.vdb")
        bs.write_density(path, case.density, case.voxel)
        reference = bs.reference(case, path, origins, directions,
                                 bs.CACHE)[0]
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                      quality="FINAL", seed=0)
        for which in ("none", "above", "across", "all"):
            shown = path
            if which != "none":
                shown = os.path.join(folder, which + ".vdb")
                edge_air_copied(path, case.density, which, shown)
            baked = firncore.render_baked(shown, case.optics, origins, directions, occluders=case.occluders)
            rel = np.abs(baked[seen] / reference[seen] - 1.0)
            print(f"bumpy_plate, edge air {which:6s}: mean {100 * rel.mean():.2f} %, worst {100 * rel.max():.0f} %, "
                  f"bias {100 * (baked[seen].sum() / reference[seen].sum() - 1):+.2f} %", flush=True)


def ray_sets(case, walls, rows, top_of):
    h = case.voxel
    xs = np.arange(3, 27)
    sets = []
    for z in walls:
        keep = [x for x in xs if top_of(x, 0) >= z + 1.0]
        sets.append((f"wall z={z:g}", np.array([[x * h, -10 * h, z * h] for x in keep]),
                     np.tile([0.0, 1.0, 0.0], (len(keep), 1))))
    for y in rows:
        sets.append((f"top y={y:g}", np.array([[x * h, y * h, 14 * h] for x in xs]),
                     np.tile([0.0, 0.0, -1.0], (len(xs), 1))))
    a, e = math.radians(180.0), math.radians(50.0)
    back = np.array([math.cos(a) * math.cos(e), math.sin(a) * math.cos(e), math.sin(e)])
    for y in rows[:3]:
        sets.append((f"graze y={y:g}", np.array([[x * h, y * h, 14 * h] for x in xs]), np.tile(-back, (len(xs), 1))))
    return sets


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--shape", default="bumpy", choices=("bumpy", "slab"))
    parser.add_argument("--lights", default="sky,sun")
    parser.add_argument("--albedo", default="0,0.45,0.9", help="the ground's albedo in R, G, B")
    parser.add_argument("--samples", type=int, default=1024)
    parser.add_argument("--walls", default="1,2,3,4,5,6")
    parser.add_argument("--rows", default="-0.35,0,0.5,1,2,4,8")
    parser.add_argument("--edge-air", choices=("above", "across", "all"), help="render with edge_air_copied")
    parser.add_argument("--suite", action="store_true", help="bumpy_plate's suite score with each edge_air_copied")
    args = parser.parse_args()
    if args.suite:
        suite_oracle()
        return
    albedo = tuple(float(a) for a in args.albedo.split(","))
    case = bs.case("bumpy_plate")
    if args.shape == "slab":
        case.density = slab(30, 6, 6) * case.rho

        def top_of(x, y):
            return 6.0
    else:
        def top_of(x, y):
            return bs.bumpy_top(x, y, 6, 3)
    sets = ray_sets(case, [float(v) for v in args.walls.split(",")], [float(v) for v in args.rows.split(",")],
                    top_of)
    origins = np.concatenate([o for _, o, _ in sets])
    directions = np.concatenate([d for _, _, d in sets])
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "plate.vdb")
        bs.write_density(path, case.density, case.voxel)
        for light in args.lights.split(","):
            c = over_ground(case, light, albedo)
            truth = firncore.monte_carlo_radiance(path, c.optics, origins, directions, suns=c.suns(), sky=c.skies(),
                                                  occluders=c.occluders, samples=args.samples, seed=5)[0]
            firncore.bake(path, c.optics, suns=c.suns(), sky=c.skies(), occluders=c.occluders, quality="FINAL", seed=0)
            shown = path
            if args.edge_air:
                shown = os.path.join(folder, "oracle.vdb")
                edge_air_copied(path, case.density, args.edge_air, shown)
            baked = firncore.render_baked(shown, c.optics, origins, directions, occluders=c.occluders)
            print(f"{args.shape}, {light} alone, ground {albedo} (R, G, B)"
                  + (f", edge air {args.edge_air}" if args.edge_air else "") + f", {args.samples} paths: bake error R, G, B; gain dark -> bright ground truth, bake; truth R, G, B per ray")
            start = 0
            dark, bright = int(np.argmin(albedo)), int(np.argmax(albedo))
            for name, o, _ in sets:
                m = slice(start, start + len(o))
                start += len(o)
                t, b = truth[m].sum(0), baked[m].sum(0)
                print(f"  {name:12s} " + " ".join(f"{100 * (b[i] / t[i] - 1):+6.1f}" for i in range(3)) +
                      f" %   {t[bright] / t[dark]:.2f}, {b[bright] / b[dark]:.2f}   " + " ".join(f"{v / len(o):.4f}" for v in t), flush=True)


if __name__ == "__main__":
    main()
