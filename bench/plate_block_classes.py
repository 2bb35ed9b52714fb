"""bumpy_plate's per-block error split by the block's light and geometry classes, with each class's weight in the
case's mean (docs/benchmarks.md, "bumpy-sides").

Each seen block (one camera ray; bench/bake_suite.py) is classed by the point where its ray reaches optical depth 1
and the trilinear density's normal there (n = −∇ρ / |∇ρ|, central differences of half a voxel), first match wins:
  cut sides    within 1.5 voxels of the layer's x or y bounds;
  plate shadow the sun's ray from the point, half a voxel out along n, meets the plate;
  sky only     the sun's cosine n·s ≤ 0.05, or that ray crosses more than 2 optical depths of snow (self-shadow);
  grazing      the exit cosine n·(−d) < 0.3 (limb-dark's grazing class);
  slopes to sun / slopes away   n tilted more than 15° from +z, its horizontal part towards / away from the sun (+x);
  lit top      the rest.
Printed per class: blocks, its points of the mean (its summed |relative error| over all blocks' count: the
points add up to the mean), share, mean |error|, bias (sum baked / sum reference − 1), per view points and bias.

Lights: "full" against the suite's cached reference; "sun" and "sky" against fresh core Monte Carlo of --samples paths
(bench/plate_err_regions.py's cache). --worst N lists the N worst blocks of the first light (green).

    PYTHONPATH=build/python:bench python3 bench/plate_block_classes.py [--samples 2048] [--lights full,sun,sky]
        [--worst N]
"""

import argparse
import math
import os

import numpy as np

import bake_suite as bs
from plate_err_regions import baked_against_lights, light_arguments

CLASSES = ("cut sides", "plate shadow", "sky only", "grazing", "slopes to sun", "slopes away", "lit top")
SUN = np.array([math.cos(bs.SUN_ELEVATION), 0.0, math.sin(bs.SUN_ELEVATION)])


def normals(case, points):
    """−∇ρ / |∇ρ| of the trilinear density at world points (N, 3)."""
    p = points / case.voxel
    grad = np.stack([bs.trilinear(case.density, p + 0.5 * e) - bs.trilinear(case.density, p - 0.5 * e)
                     for e in np.eye(3)], axis=1)
    return -grad / np.maximum(np.linalg.norm(grad, axis=1), 1e-12)[:, None]


def sun_depth(case, points):
    """Optical depth of snow along the sun from each point, up to the grid's top."""
    steps = np.arange(0.0, 0.6, 0.25 * case.voxel)
    tau = np.array([bs.trilinear(case.density, (p + steps[:, None] * SUN) / case.voxel).sum() for p in points])
    return tau * (steps[1] - steps[0]) * case.sigma_t / case.rho


def classes(case, origins, directions, seen):
    """Each block's class name (the module's docstring), its depth-one point, normal, sun and exit cosines."""
    h = case.voxel
    hit = bs.depth_one_points(case, origins, directions, seen)
    label = np.full(len(hit), "", dtype=object)
    idx = np.nonzero(seen)[0]
    p = hit[idx]
    n = normals(case, p)
    out = p + 0.5 * h * n
    mu0, mu = n @ SUN, -(n * directions[idx]).sum(1)
    plate = np.array([bs.plate_hit(case, o, SUN) < math.inf for o in out])
    blocked = sun_depth(case, out) > 2.0
    last = (case.density.shape[0] - 1) * h
    x, y = p[:, 0], p[:, 1]
    side = (x < 1.5 * h) | (x > last - 1.5 * h) | (y < 1.5 * h) | (y > last - 1.5 * h)
    tilted = n[:, 2] < math.cos(math.radians(15.0))
    order = [("cut sides", side), ("plate shadow", plate & (mu0 > 0.05)), ("sky only", (mu0 <= 0.05) | blocked),
             ("grazing", mu < 0.3), ("slopes to sun", tilted & (n[:, 0] > 0.0)), ("slopes away", tilted),
             ("lit top", np.ones(len(p), bool))]
    sub = label[idx]
    for name, mask in order:
        sub[(sub == "") & mask] = name
    label[idx] = sub
    geometry = {k: np.full(len(hit), np.nan) for k in ("mu0", "mu", "nz")}
    geometry["mu0"][idx], geometry["mu"][idx], geometry["nz"][idx] = mu0, mu, n[:, 2]
    geometry["hit"] = hit
    return label, geometry


def side_split(geometry, case):
    """The cut sides' blocks by bound (−x, +x, −y, +y: the nearest) and by the normal: wall (|n_z| < 0.5) or top edge."""
    last = (case.density.shape[0] - 1) * case.voxel
    p, nz = geometry["hit"], geometry["nz"]
    d = np.stack([p[:, 0], last - p[:, 0], p[:, 1], last - p[:, 1]], axis=1)
    bound = np.array(["-x", "+x", "-y", "+y"])[np.argmin(np.nan_to_num(d, nan=1.0), axis=1)]
    return np.where(np.abs(nz) < 0.5, np.char.add(bound, " wall"), np.char.add(bound, " top edge"))


def report(title, baked, reference, label, view, views, parts=None):
    """Per class (and, given parts, per part of the cut sides): blocks, points, share, mean |error|, bias, per view."""
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.abs(baked / reference - 1.0)
    seen = label != ""
    count, total = rel[seen].size, rel[seen].sum()

    def bias(m):
        return 100 * (baked[m].sum() / reference[m].sum() - 1)

    def row(name, m, indent):
        cells = [f"{100 * rel[k].sum() / count:5.2f} {bias(k):+6.1f}" if k.any() else " " * 12
                 for k in (m & (view == v) for v in range(len(views)))]
        print(f"{' ' * indent}{name:<{15 - indent}} {3 * m.sum():>6} {100 * rel[m].sum() / count:6.2f} "
              f"{100 * rel[m].sum() / total:5.1f}% {100 * rel[m].mean():5.1f}% {bias(m):+6.1f}%   " + "        ".join(cells),
              flush=True)

    print(f"{title}: mean {100 * rel[seen].mean():.2f} %, bias {bias(seen):+.1f} %")
    print(f"  {'class':<13} {'blocks':>6} {'points':>6} {'share':>6} {'mean':>6} {'bias':>7}   " +
          "   ".join(f"{str(v):>9} points/bias" for v in views))
    for name in CLASSES:
        m = label == name
        if m.any():
            row(name, m, 2)
        if m.any() and parts is not None and name == "cut sides":
            for part in sorted(set(parts[m])):
                row(part, m & (parts == part), 4)


def main():
    parser = argparse.ArgumentParser()
    light_arguments(parser)
    parser.add_argument("--worst", type=int, default=0)
    args = parser.parse_args()
    os.makedirs(args.cache, exist_ok=True)
    case = bs.case("bumpy_plate")
    origins, directions, tau = bs.views(case)
    seen = tau >= 1.0
    label, geometry = classes(case, origins, directions, seen)
    view = np.repeat(np.arange(len(case.views)), case.pixels ** 2)
    results = {}
    for light, title, baked, reference in baked_against_lights(case, args, origins, directions, seen):
        report(title, baked, reference, label, view, case.views, side_split(geometry, case))
        results[light] = (baked, reference)
    if args.worst:
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = {k: b[:, 1] / r[:, 1] - 1.0 for k, (b, r) in results.items()}
        first = np.where(label != "", np.abs(np.nan_to_num(rel[next(iter(results))])), -1.0)
        per = case.pixels ** 2
        print("worst blocks (green): view, row from the top, column, depth-one point (cm), class, mu0, mu, " +
              ", ".join(f"{k} error" for k in results))
        for i in np.argsort(-first)[:args.worst]:
            v, q = divmod(int(i), per)
            point = " ".join(f"{100 * x:5.1f}" for x in geometry["hit"][i])
            print(f"  {str(case.views[v]):>9} {case.pixels - 1 - q // case.pixels:2d} {q % case.pixels:2d}  ({point})  "
                  f"{label[i]:<13} {geometry['mu0'][i]:+.2f} {geometry['mu'][i]:+.2f}  " +
                  "  ".join(f"{100 * rel[k][i]:+6.1f} %" for k in results))


if __name__ == "__main__":
    main()
