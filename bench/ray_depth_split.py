"""Where along a suite case's camera rays the baked render's light and the Monte Carlo's come from, voxel cell by
voxel cell (docs/benchmarks.md, spray-core).

For the pixels of one region (bench/suite_regions.py's: lit or shadowed where the ray reaches optical depth 1, a
lump's core or a rim), each camera ray is cut where it crosses the voxel cells' faces (cells centred on the voxels,
one voxel across), from the snow's first density to optical depth 8. The light the render and the Monte Carlo send
back from the ray beyond a point is the radiance of a ray started there (`firncore.render_baked` and
`firncore.monte_carlo_radiance` from a point inside the snow); what a cell [a, b] sends to the camera is
T(a) L(a) - T(b) L(b), T the snow's transmittance from the camera (the same trilinear density both use). The cuts and T
count the snow alone, not the case's occluders (the render and the Monte Carlo do count them). Each ray is scanned 2.0 m
from its camera, as bake_suite.depth_one_points does: past the far side of every suite case (its rays span 6 of the
view's radii, 0.99 m at most, bumpy_plate's). Reported per crossing (first cell, second, ...) and per cell kind (traced
or not, by its optical depth sigma_t h): each one's share of the Monte Carlo's light and the render's over it.

    PYTHONPATH=build/python python3 bench/ray_depth_split.py [--case spray_dense] [--region "lit & core"]
        [--seed 0] [--samples 4096]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import firncore
import suite_regions

MAX_DEPTH = 8.0  # optical depth from the camera where the cuts stop (exp(-8) of the light lies beyond)


def cuts(case, origin, direction):
    """Distances (m) where the ray crosses the voxel cells' faces, from the snow's first density to optical depth
    MAX_DEPTH, and the transmittance from the origin at each."""
    h, step = case.voxel, case.voxel / 64.0
    t = np.arange(0.0, 2.0, step)
    rho = bake_suite.trilinear(case.density, (origin + t[:, None] * direction) / h)
    tau = np.concatenate([[0.0], np.cumsum(0.5 * (rho[1:] + rho[:-1]) * step)]) * case.sigma_t / case.rho
    start, stop = t[max(np.argmax(rho > 0.0) - 1, 0)], t[min(np.searchsorted(tau, MAX_DEPTH), len(t) - 1)]
    out = {start, stop}
    for a in range(3):
        if abs(direction[a]) > 1e-9:
            for face in np.arange(-0.5, case.density.shape[a] + 0.5):
                d = (face * h - origin[a]) / direction[a]
                if start < d < stop:
                    out.add(d)
    out = np.array(sorted(out))
    return out, np.exp(-np.interp(out, t, tau))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="spray_dense")
    parser.add_argument("--region", default="lit & core", help="a numpy expression of lit, core (boolean per pixel)")
    parser.add_argument("--seed", type=int, default=0, help="the bake's")
    parser.add_argument("--samples", type=int, default=4096, help="Monte Carlo paths per point")
    parser.add_argument("--cache", default=bake_suite.CACHE)
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    origins, directions, tau = bake_suite.views(case)
    seen, lit, core = suite_regions.regions(case, origins, directions, tau)
    pick = np.nonzero(seen & eval(args.region, {}, {"lit": lit, "core": core}))[0]
    points, owner, distance, transmittance = [], [], [], []
    for p in pick:
        t, T = cuts(case, origins[p], directions[p])
        for j in range(len(t)):
            points.append(origins[p] + t[j] * directions[p])
            owner.append(p)
            distance.append(t[j])
            transmittance.append(T[j])
    points, owner, transmittance = np.array(points), np.array(owner), np.array(transmittance)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        reference, _, _ = bake_suite.reference(case, path, origins, directions, args.cache)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                      quality="FINAL", seed=args.seed)
        render = firncore.render_baked(path, case.optics, points, directions[owner], occluders=case.occluders)
        mc, _ = firncore.monte_carlo_radiance(path, case.optics, points, directions[owner], suns=case.suns(),
                                              sky=case.skies(), occluders=case.occluders, samples=args.samples, seed=23)
    render, mc = render.mean(1), mc.mean(1)
    light = {"render": [], "mc": []}
    order, kind = [], []
    for p in pick:
        idx = np.nonzero(owner == p)[0]
        for n, j in enumerate(idx[:-1]):
            k = idx[n + 1]
            for name, L in (("render", render), ("mc", mc)):
                light[name].append(transmittance[j] * L[j] - transmittance[k] * L[k])
            order.append(n)
            middle = 0.5 * (distance[j] + distance[k])
            c = tuple(np.round((origins[p] + middle * directions[p]) / case.voxel).astype(int))
            inside = all(0 <= c[a] < case.density.shape[a] for a in range(3))
            kind.append(case.density[c] * case.sigma_t / case.rho * case.voxel if inside else 0.0)
    r, m, order, kind = np.array(light["render"]), np.array(light["mc"]), np.array(order), np.array(kind)
    first = [np.nonzero(owner == p)[0][0] for p in pick]
    print(f"{case.name}, region {args.region}: {len(pick)} pixels, {len(points)} points, bake seed {args.seed}, "
          f"{args.samples} paths per point")
    print(f"  from the camera: render {render[first].sum():.4f}, Monte Carlo {mc[first].sum():.4f} "
          f"(the suite's reference {reference[pick].mean(1).sum():.4f}); render / Monte Carlo "
          f"{render[first].sum() / mc[first].sum():.3f}")
    total = m.sum()

    def line(label, where):
        if where.any():
            print(f"  {label:<28} {where.sum():4d} cells  Monte Carlo {100 * m[where].sum() / total:5.1f} %  "
                  f"render {100 * r[where].sum() / total:5.1f} %  "
                  f"render / Monte Carlo {r[where].sum() / m[where].sum():5.2f}")

    for n in range(4):
        line(f"crossing {n + 1}", order == n)
    line("crossing 5 and later", order >= 4)
    line("cells of sigma_t h 0 (air)", kind == 0.0)
    line("cells of sigma_t h (0, 2]", (kind > 0.0) & (kind <= 2.0))
    line("cells of sigma_t h (2, 8)", (kind > 2.0) & (kind < 8.0))
    line("cells of sigma_t h >= 8", kind >= 8.0)


if __name__ == "__main__":
    main()
