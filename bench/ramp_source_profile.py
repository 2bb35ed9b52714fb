"""The source function along one camera ray of a suite case in optical-depth bins finer than a voxel: the truth's
(the core's Monte Carlo) against the baked render's (docs/benchmarks.md, edge-fall).

Radiance is estimated from origins placed on the ray at optical depths tau_k (trilinear density, as the reference's
and the render's) of the snow along it; the mean source over a bin [a, b] (weighted by exp(-(tau - a)), the light
of the bin that reaches a) is

    S_ab = (I(a) - exp(-(b - a)) I(b)) / (1 - exp(-(b - a)))

(the radiance transfer along the ray, exact for both: the Monte Carlo's paths start at the origin in the same
medium; the render integrates its grids from the origin). The last bin is I at its start (the snow beyond is
opaque where tau reaches several). Per bin: where its start lies (index space), the density there over the
snow's, the truth's S (green) with its standard error, the bake's S (FINAL, seed 0), bake / truth. The ray is the
suite's block ray of VIEW,ROW,COL shifted along the image's axis by --shift voxels (bench/edge_blocks.py --scan).

    PYTHONPATH=build/python:bench python3 bench/ramp_source_profile.py --case slab_thick --block 2,3,7 \
        [--shifts 0,0.25,0.5] [--axis u] [--paths 16384] [--taus 0,0.1,0.25,0.5,1,2,4]

With --exits E1,E2,... (a slab or box case) the flat top's exit instead: one ray per elevation (degrees above the top, from
--azimuth) aimed at the middle of the top's half-density plane, the truth against the baked render: whether the
voxels' lobes hold the flat surface's exit at grazing, where the camera ray becomes opaque in the ramp's outer part;
--side: horizontal rays onto the middle of the -x side instead, at angles E from its plane. With --by-exit CASES the
cases' blocks (FINAL, seed 0, the suite's cached references) by the exit cosine where their rays reach depth 1.
--omega, --g, --sun replace the case's optics and sun for the profiles and exits (the Milne fall of an absorbing
surface under the sky alone). With
--side-air CASE (a box or slab) the oracle side_air_copied (--corners: the corners' air too) on the suite's figures,
the blocks it moves by over 3 points, and on --block's scans (";" apart).
"""

import argparse
import dataclasses
import math
import os
import tempfile

import numpy as np

import pyopenvdb

import bake_suite
import firncore
from edge_blocks import image_axis
from plate_side_probe import copy_source_values


def points_at_depths(case, origin, direction, taus):
    """The points (m) where the ray's optical depth of snow reaches each of taus (NaN past its end)."""
    steps = np.linspace(0.0, 2.0, 40000)
    p = origin + steps[:, None] * direction
    density = bake_suite.trilinear(case.density, p / case.voxel)
    tau = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(steps))]) * case.sigma_t / case.rho
    out = np.full((len(taus), 3), np.nan)
    for k, t in enumerate(taus):
        i = np.searchsorted(tau, t)
        if t == 0.0:
            i = max(int(np.argmax(density > 0.0)) - 1, 0)  # the last point before the snow
        if i < len(steps):
            out[k] = p[i]
    return out


def flat_exits(case, elevations, azimuth, paths, side=False):
    """The truth's and the bake's radiance of rays from `elevations` at `azimuth` onto the middle of a slab's top;
    with `side`, horizontal rays onto the middle of its -x side, `elevations` then the angles (degrees) from the side's
    plane about the vertical, from +y (azimuth 90 + angle)."""
    full = np.argwhere(case.density >= case.rho)
    middle = (full.min(0) + full.max(0)) / 2
    if side:
        target = np.array([full[:, 0].min() - 0.5, middle[1], middle[2]]) * case.voxel
        a = np.radians(90.0 + np.array(elevations))
        back = np.stack([np.cos(a), np.sin(a), np.zeros(len(a))], 1)
    else:
        target = np.array([middle[0], middle[1], full[:, 2].max() + 0.5]) * case.voxel
        a = math.radians(azimuth)
        back = np.array([[math.cos(a) * math.cos(math.radians(e)), math.sin(a) * math.cos(math.radians(e)),
                          math.sin(math.radians(e))] for e in elevations])
    origins = target + 0.5 * back  # 50 cm back: clear of a 24 cm slab
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        mc, error = firncore.monte_carlo_radiance(path, case.optics, origins, -back, suns=case.suns(),
                                                  sky=case.skies(), occluders=case.occluders, samples=paths, seed=5)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                      quality="FINAL", seed=0)
        baked = firncore.render_baked(path, case.optics, origins, -back, occluders=case.occluders)
    print(f"{case.name}: the flat {'-x side' if side else 'top'}'s exit from azimuth "
          f"{'90 + angle' if side else azimuth}, {paths} paths (green)")
    for e, m, s, b in zip(elevations, mc[:, 1], error[:, 1], baked[:, 1]):
        print(f"  {'angle' if side else 'elevation'} {e:5.1f}  truth {m:.4f} ({100 * s / m:.1f} %)  baked {b:.4f}  {100 * (b / m - 1):+6.1f} %")


def by_exit_cosine(names, cache):
    """Each case's seen blocks (FINAL, seed 0, the suite's cached references) by the exit cosine mu = the view's
    direction towards the camera dotted with the snow's outward normal (minus the trilinear density's gradient) where
    the block's ray reaches optical depth 1: pixels, mean |error|, mean error, pixels over 10 % (green)."""
    bands = ((-1.0, 0.0), (0.0, 0.15), (0.15, 0.3), (0.3, 0.6), (0.6, 1.01))
    print("case              exit cosine    pixels  mean |err|  mean err  over 10 %")
    for name in names:
        case = bake_suite.case(name)
        origins, directions, tau = bake_suite.views(case)
        seen = tau >= 1.0
        with tempfile.TemporaryDirectory() as folder:
            run = bake_suite.run_case(case, folder, cache, seed=0)
        error = run["relative"][:, 1]
        hits = bake_suite.depth_one_points(case, origins[seen], directions[seen], np.ones(seen.sum(), bool)) / case.voxel
        gradient = np.stack([(bake_suite.trilinear(case.density, hits + e) -
                              bake_suite.trilinear(case.density, hits - e)) for e in 0.25 * np.eye(3)], 1)
        normal = -gradient / np.maximum(np.linalg.norm(gradient, axis=1), 1e-30)[:, None]
        mu = np.einsum("ij,ij->i", -directions[seen], normal)
        for lo, hi in bands:
            at = (mu >= lo) & (mu < hi)
            if at.any():
                print(f"{name:<17} {lo:+5.2f}-{min(hi, 1.0):4.2f}   {at.sum():6d}  {100 * np.abs(error[at]).mean():8.1f} %"
                      f"  {100 * error[at].mean():+7.1f} %  {(np.abs(error[at]) > 0.1).sum():6d}")


def side_air_copied(path, density, rho, out, corners):
    """The baked file at path written to out with the air voxels beyond each side face (+-x, +-y) of a box or slab, in
    its top and bottom voxel layers (with `corners` also the air one layer above and below them, beyond two faces),
    holding the values of the air beyond that side in its middle layer (an oracle: the side's own light where
    facingAverage mixes in the edge voxel's one lobe, its lit top's or face's)."""
    grids, metadata = pyopenvdb.readAll(path)
    full = np.argwhere(density >= rho)
    low, high = [int(x) for x in full.min(0)], [int(x) for x in full.max(0)]
    middle = (low[2] + high[2]) // 2
    targets = []
    for axis in (0, 1):
        for side, step in ((low[axis], -1), (high[axis], 1)):
            for u in range(low[1 - axis], high[1 - axis] + 1):
                c = [0, 0]
                c[axis], c[1 - axis] = side + step, u
                for z in (low[2] - 1, low[2], high[2], high[2] + 1) if corners else (low[2], high[2]):
                    targets.append(((c[0], c[1], middle), (c[0], c[1], z)))
    copy_source_values(grids, metadata, targets, out)


def side_air_oracle(name, cache, scans, corners):
    """The case's suite figures (FINAL, seed 0, the cached reference) baked and with side_air_copied, and each scan
    (VIEW,ROW,COL: its ray shifted along u by -0.5..0.75 voxel, the Monte Carlo of 4096 paths) rendered both ways."""
    case = bake_suite.case(name)
    origins, directions, tau = bake_suite.views(case)
    seen = tau >= 1.0
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        mean, _, _ = bake_suite.reference(case, path, origins, directions, cache)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                      quality="FINAL", seed=0)
        copied = os.path.join(folder, "copied.vdb")
        side_air_copied(path, case.density, case.rho, copied, corners)
        relative = []
        for label, file in (("baked", path), ("side air", copied)):
            r = bake_suite.scored(case, firncore.render_baked(file, case.optics, origins, directions)[:, 1],
                                  mean[:, 1], seen)
            relative.append(np.full(len(seen), np.nan))
            relative[-1][seen] = r["relative"]
            print(f"{name} {label:<9} mean {100 * r['mean']:.2f} %  worst {100 * r['worst_signed']:+.0f} %  bias "
                  f"{100 * r['bias']:+.2f} %  views " + " ".join(f"{100 * v:+.1f}" for v in r["view_bias"]) +
                  f"  over 10 %: {(np.abs(r['relative']) > 0.1).sum()}")
        per = case.pixels ** 2
        for i in np.nonzero(np.abs(relative[1] - relative[0]) > 0.03)[0]:
            print(f"    {str(case.views[i // per]):<10} row {i % per // case.pixels} col {i % case.pixels}  "
                  f"{100 * relative[0][i]:+6.1f} -> {100 * relative[1][i]:+6.1f} %")
        for block in scans:
            view, row, column = (int(x) for x in block.split(","))
            i = view * case.pixels ** 2 + row * case.pixels + column
            shifts = np.array([-0.5, -0.25, 0.0, 0.25, 0.5, 0.75])
            o = origins[i] + shifts[:, None] * case.voxel * image_axis(case, view, "u")
            d = np.tile(directions[i], (len(shifts), 1))
            mc, _ = firncore.monte_carlo_radiance(path, case.optics, o, d, suns=case.suns(), sky=case.skies(),
                                                  samples=4096, seed=7)
            a = firncore.render_baked(path, case.optics, o, d)[:, 1] / mc[:, 1] - 1
            b = firncore.render_baked(copied, case.optics, o, d)[:, 1] / mc[:, 1] - 1
            print(f"  scan {block}: shift " + "  ".join(f"{s:+.2f} {100 * x:+.0f} -> {100 * y:+.0f} %"
                                                        for s, x, y in zip(shifts, a, b)))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="slab_thick")
    parser.add_argument("--block", default="2,3,7", help="VIEW,ROW,COL of the suite's blocks (row 0 at the bottom)")
    parser.add_argument("--shifts", default="0", help="voxels along --axis (+: the image's axis direction)")
    parser.add_argument("--axis", default="u", choices=("u", "v"))
    parser.add_argument("--paths", type=int, default=16384)
    parser.add_argument("--taus", default="0,0.1,0.25,0.5,1,2,4")
    parser.add_argument("--exits", default="", help="elevations (degrees) of rays onto a slab's flat top")
    parser.add_argument("--azimuth", type=float, default=90.0)
    parser.add_argument("--side-air", default="", help="a box or slab case: side_air_oracle with --block's scans")
    parser.add_argument("--corners", action="store_true", help="--side-air: the corners' air too")
    parser.add_argument("--omega", type=float, help="the case's albedo replaced (all channels)")
    parser.add_argument("--g", type=float, help="the case's anisotropy replaced")
    parser.add_argument("--sun", type=float, help="the case's sun irradiance replaced (0: the sky alone)")
    parser.add_argument("--by-exit", default="", help="cases: their blocks' errors by exit cosine")
    parser.add_argument("--cache", default=bake_suite.CACHE)
    parser.add_argument("--side", action="store_true", help="--exits onto the -x side (angles from its plane)")
    args = parser.parse_args()
    if args.side_air:
        side_air_oracle(args.side_air, args.cache, args.block.split(";"), args.corners)
        return
    if args.by_exit:
        by_exit_cosine(args.by_exit.split(","), args.cache)
        return
    case = bake_suite.case(args.case)
    case = dataclasses.replace(case, **{k: v for k, v in (("omega", args.omega and (args.omega,) * 3), ("g", args.g),
                                                          ("sun", args.sun)) if v is not None})
    if args.exits:
        flat_exits(case, [float(x) for x in args.exits.split(",")], args.azimuth, args.paths, args.side)
        return
    view, row, column = (int(x) for x in args.block.split(","))
    origins, directions, _ = bake_suite.views(case)
    block = view * case.pixels ** 2 + row * case.pixels + column
    along = image_axis(case, view, args.axis)
    taus = np.array([float(x) for x in args.taus.split(",")])
    shifts = [float(x) for x in args.shifts.split(",")]
    d = directions[block]
    starts = []
    for s in shifts:
        starts.append(points_at_depths(case, origins[block] + s * case.voxel * along, d, taus))
    starts = np.concatenate(starts)
    ok = ~np.isnan(starts[:, 0])
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        dirs = np.tile(d, (ok.sum(), 1))
        mc, error = firncore.monte_carlo_radiance(path, case.optics, starts[ok], dirs, suns=case.suns(),
                                                  sky=case.skies(), occluders=case.occluders, samples=args.paths,
                                                  seed=5)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                      quality="FINAL", seed=0)
        baked = firncore.render_baked(path, case.optics, starts[ok], dirs, occluders=case.occluders)
    I = np.full(len(starts), np.nan)
    E = np.full(len(starts), np.nan)
    B = np.full(len(starts), np.nan)
    I[ok], E[ok], B[ok] = mc[:, 1], error[:, 1], baked[:, 1]
    n = len(taus)
    print(f"{case.name} view {case.views[view]} row {row} col {column}, direction {np.round(d, 3)}, "
          f"{args.paths} paths; source per optical-depth bin (green)")
    for k, s in enumerate(shifts):
        print(f"shift {s:+.2f} voxel along {args.axis}: whole ray truth {I[k * n]:.4f} ({100 * E[k * n] / I[k * n]:.1f} %)"
              f"  baked {B[k * n]:.4f}  {100 * (B[k * n] / I[k * n] - 1):+.1f} %")
        print("   bin tau        start (index)          fill   truth S (se)        baked S   baked/truth")
        for j in range(n):
            i = k * n + j
            if np.isnan(I[i]):
                continue
            a = taus[j]
            if j + 1 < n and not np.isnan(I[i + 1]):
                T = math.exp(-(taus[j + 1] - a))
                St = (I[i] - T * I[i + 1]) / (1 - T)
                se = math.hypot(E[i], T * E[i + 1]) / (1 - T)
                Sb = (B[i] - T * B[i + 1]) / (1 - T)
                label = f"{a:4.2f}-{taus[j + 1]:<4.2f}"
            else:
                St, se, Sb, label = I[i], E[i], B[i], f"{a:4.2f}-    "
            p = starts[i] / case.voxel
            fill = bake_suite.trilinear(case.density, p[None])[0] / case.rho
            print(f"  {label}  ({p[0]:6.2f} {p[1]:6.2f} {p[2]:6.2f})  {fill:4.2f}   {St:.4f} ({se:.4f})   "
                  f"{Sb:.4f}   {Sb / St:5.2f}")


if __name__ == "__main__":
    main()
