"""Where along a suite case's camera ray the baked light is wrong (docs/bake.md, Accuracy, "Forward-scattering ball
and thin slab"): the radiance seen from origins stepped into the snow along the block's ray, baked
(`firncore.render_baked`) against the core's Monte Carlo (`firncore.monte_carlo_radiance`, same scene), and the
case's blocks split into rays that reach half the snow's full density (core) and rays through its fringe only (rim).

In snow of several optical depths per voxel the radiance seen from a point inside is the source within the next
fraction of a voxel: the ratio by depth says whether the surface voxels or the inside are off. Pixels are (row,
column) of bench/bake_suite.py --maps (row 0 at the top).

    PYTHONPATH=build/python python3 bench/bake_ray_probe.py ball_forward --view 1 --pixels 3,2 3,5 [--samples 4096]
    PYTHONPATH=build/python python3 bench/bake_ray_probe.py ball_forward --classes [--seeds 3]
"""

import argparse
import os
import tempfile

import numpy as np

import firncore
import bake_suite

DEPTHS = (-1.0, 0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0)  # voxels past where the ray first meets half the density


def first_half_density(case, origin, direction):
    """Distance (m) along the ray to where the density first reaches half its largest value; None if never."""
    steps = np.arange(0.0, 6.0 * case.voxel * max(case.density.shape), case.voxel / 16.0)
    rho = bake_suite.trilinear(case.density, (origin + steps[:, None] * direction) / case.voxel)
    inside = np.nonzero(rho >= 0.5 * case.density.max())[0]
    return steps[inside[0]] if len(inside) else None


def probe(case, path, view, pixels, samples):
    origins, directions, _ = bake_suite.views(case)
    per = case.pixels ** 2
    for row, column in pixels:
        i = view * per + (case.pixels - 1 - row) * case.pixels + column
        o, d = origins[i], directions[i]
        t0 = first_half_density(case, o, d)
        if t0 is None:
            print(f"view {case.views[view]} pixel ({row}, {column}): the ray never reaches half the density")
            continue
        starts = np.array([o + (t0 + s * case.voxel) * d for s in DEPTHS])
        along = np.repeat(d[None], len(DEPTHS), 0)
        baked = firncore.render_baked(path, case.optics, starts, along)[:, 1]
        mean, error = firncore.monte_carlo_radiance(path, case.optics, starts, along, suns=case.suns(),
                                                    sky=case.skies(), occluders=case.occluders, samples=samples,
                                                    seed=5)
        print(f"view {case.views[view]} pixel ({row}, {column}): half density at voxel "
              f"{np.round((o + t0 * d) / case.voxel, 2)} (channel G)")
        for s, b, m, e in zip(DEPTHS, baked, mean[:, 1], error[:, 1]):
            print(f"  depth {s:+5.2f} voxel: baked {b:.4f}, Monte Carlo {m:.4f} +- {e:.4f}, ratio {b / m:.3f}")


def classes(case, seeds):
    """Mean |relative error| and mean signed error per class (rim: the ray never reaches half the density) and
    per view, over `seeds` bakes against the suite's cached reference."""
    origins, directions, tau = bake_suite.views(case)
    seen = tau >= 1.0
    rim = np.array([first_half_density(case, o, d) is None for o, d in zip(origins, directions)])[seen]
    view = (np.arange(len(tau)) // case.pixels ** 2)[seen]
    with tempfile.TemporaryDirectory() as folder:
        cache = bake_suite.CACHE
        runs = [bake_suite.run_case(case, folder, cache, seed=s)["relative"] for s in range(seeds)]
    relative = np.array(runs)[:, :, 1]  # seeds x seen rays, channel G
    for name, mask in (("rim", rim), ("core", ~rim)):
        per_view = ", ".join(f"{case.views[v]} {100 * relative[:, mask & (view == v)].mean():+.0f} %"
                             for v in range(len(case.views)) if (mask & (view == v)).any())
        print(f"{name}: {mask.sum()} rays, mean |error| {100 * np.abs(relative[:, mask]).mean():.1f} %, "
              f"mean error {100 * relative[:, mask].mean():+.1f} %; per view {per_view}")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("case")
    parser.add_argument("--view", type=int, default=0, help="index into the case's views")
    parser.add_argument("--pixels", nargs="*", default=[], help="row,column of --maps")
    parser.add_argument("--samples", type=int, default=4096)
    parser.add_argument("--classes", action="store_true", help="rim against core rays over the case's views")
    parser.add_argument("--seeds", type=int, default=1)
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    if args.classes:
        classes(case, args.seeds)
    if args.pixels:
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, case.name + ".vdb")
            bake_suite.write_density(path, case.density, case.voxel)
            firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders, seed=0)
            probe(case, path, args.view, [tuple(int(x) for x in p.split(",")) for p in args.pixels], args.samples)


if __name__ == "__main__":
    main()
