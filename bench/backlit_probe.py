"""Where a thick ball seen against the sun misses its light (branch backlit, docs/benchmarks.md "backlit").

bench/bake_suite.py's case (ball_issue by default), seed 0, its cached Monte Carlo reference:
  regions: per view, the blocks grouped by the cosine mu0 between the sun and the normal at the ray's optical
           depth 1 point (the ball's centre to it) and by whether that normal faces the camera (face: mu_v >= 0.5)
           or not (limb): reference and baked radiance summed (green channel), what is missing.
  top rows: the view against the sun (180 deg, 0 deg), its two top rows' blocks: reference, baked, the baked
           render's peaked lobe's part (the grids' firn_source_peak* cleared), and the sun's exact single
           scattering along the ray (the trilinear density, midpoint rule on 0.5 mm steps).
  cut: the core's Monte Carlo of those blocks (sun only, 8192 paths) with the ball's voxels below a height
           removed, and the bake of what is left: how deep under the surface their light travels, and whether
           the bake holds it when the top layers stand alone (light traced whole, Method 3).
  --finer: ball_issue's ball (sun only, view against the sun) on 1, 0.5 and 0.25 cm voxels: the same top rows.
  --flat: a thick flat slab (top layer half filled) under a grazing sun, seen 30 deg off the sun's travel at the
           ball's top rows' cosines (mu0, mu_v): what a flat surface returns there.

    PYTHONPATH=build/python /usr/bin/python3 bench/backlit_probe.py [--case ball_issue] [--cache DIR] [--finer] [--flat]
"""

import argparse
import math
import os
import tempfile

import numpy as np
import pyopenvdb

import bake_suite as S
import firncore

TOP_ROWS = (58, 59, 60, 61, 49, 50, 51, 52, 53, 54)  # view pixels (row-major from the bottom) of the top two rows


def sun_towards():
    return np.array([math.cos(S.SUN_ELEVATION), 0.0, math.sin(S.SUN_ELEVATION)])


def single_scattering(case, origin, direction, h=0.0005):
    """The sun's single scattering along a camera ray (W/m^2/sr per W/m^2 of sun), trilinear density."""
    k, albedo, g = case.sigma_t / case.rho, case.omega[1], case.g
    s = np.arange(h / 2, 0.4, h)
    rho = S.trilinear(case.density, (origin + s[:, None] * direction) / case.voxel)
    camera = np.exp(-k * (np.cumsum(rho) - rho / 2) * h)
    mu = float(np.dot(direction, sun_towards()))  # cosine between the sun's travel and the way to the camera
    phase = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * mu) ** 1.5)
    total = 0.0
    for i in np.nonzero((rho > 0) & (camera > 1e-4))[0]:
        p = origin + s[i] * direction
        sun = math.exp(-k * S.trilinear(case.density, (p + s[:, None] * sun_towards()) / case.voxel).sum() * h)
        total += k * rho[i] * albedo * phase * camera[i] * sun * h
    return total


def finer():
    """ball_issue's ball against the sun on finer voxels: its top rows' light (sun only)."""
    for voxel in (0.01, 0.005, 0.0025):
        case = S.Case("finer", "", S.ball(0.05, voxel) * 100, voxel, 1000.0, 100.0, (0.98,) * 3, 0.85, views=[(180, 0)])
        origins, directions, tau = S.views(case)
        rows = [i for i in TOP_ROWS if tau[i] >= 1]
        path = os.path.join(tempfile.mkdtemp(), "finer.vdb")
        S.write_density(path, case.density, voxel)
        m, _ = firncore.monte_carlo_radiance(path, case.optics, origins[rows], directions[rows], suns=case.suns(),
                                             samples=4096, seed=3)
        stats = firncore.bake(path, case.optics, suns=case.suns(), quality="FINAL", seed=0)
        b = firncore.render_baked(path, case.optics, origins[rows], directions[rows])
        print(f"  voxel {100 * voxel} cm, {stats['traced_voxels']} traced; ray optical depth "
              + " ".join(f"{t:.0f}" for t in tau[rows]))
        print("    reference " + " ".join(f"{x:.4f}" for x in m[:, 1]))
        print("    baked     " + " ".join(f"{x:.4f}" for x in b[:, 1]))


def flat():
    """A thick flat slab, its top layer half filled, under a grazing sun, seen forwards at the top rows' cosines."""
    voxel, width, depth = 0.01, 40, 12
    density = np.zeros((width, width, depth + 4))
    density[:, :, 2:2 + depth], density[:, :, 2 + depth] = 100.0, 50.0
    optics = firncore.VolumeOptics(10.0, (0.98,) * 3, 0.85)
    path = os.path.join(tempfile.mkdtemp(), "flat.vdb")
    S.write_density(path, density, voxel)
    top = np.array([(width - 1) / 2 * voxel, (width - 1) / 2 * voxel, (2 + depth) * voxel])
    for mu0, muv in ((0.04, 0.46), (0.16, 0.32), (0.3, 0.3)):
        sun = np.array([math.sqrt(1 - mu0 * mu0), 0.0, mu0])
        camera = np.array([-math.sqrt(1 - muv * muv), 0.0, muv])
        suns = [firncore.SunLight(tuple(sun), (1.0,) * 3, 0.0093)]
        origins = top + np.array([[0.0, y, 0.0] for y in np.linspace(-0.05, 0.05, 6)]) + 0.3 * camera
        directions = np.tile(-camera, (len(origins), 1))
        m, e = firncore.monte_carlo_radiance(path, optics, origins, directions, suns=suns, samples=8192, seed=3)
        firncore.bake(path, optics, suns=suns, quality="FINAL", seed=0)
        b = firncore.render_baked(path, optics, origins, directions)
        angle = math.degrees(math.acos(np.dot(-sun, camera)))
        print(f"  mu0 {mu0}, mu_v {muv} (sun's travel to camera {angle:.0f} deg): reference {m[:, 1].mean():.4f} "
              f"+- {e[:, 1].mean() / math.sqrt(len(origins)):.4f}, baked {b[:, 1].mean():.4f}")


def write_without_peaks(path, out):
    """A baked file with the peaked lobes' grids (firn_source_peak*) cleared, its file metadata kept (the grids'
    half-voxel shift, firn_half_voxel_shift, is there: without it the render reads them half a voxel off)."""
    grids, metadata = pyopenvdb.readAll(path)
    for grid in grids:
        if grid.name.startswith("firn_source_peak"):
            grid.clear()
    pyopenvdb.write(out, grids=list(grids), metadata=metadata)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_issue")
    parser.add_argument("--cache", default=S.CACHE)
    parser.add_argument("--finer", action="store_true")
    parser.add_argument("--flat", action="store_true")
    args = parser.parse_args()
    if args.finer or args.flat:
        return finer() if args.finer else flat()
    case = [c for c in S.cases() if c.name == args.case][0]
    folder = tempfile.mkdtemp()
    path = os.path.join(folder, "snow.vdb")
    S.write_density(path, case.density, case.voxel)
    origins, directions, tau = S.views(case)
    mean, _, _ = S.reference(case, path, origins, directions, args.cache)
    firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), quality="FINAL", seed=0)
    baked = firncore.render_baked(path, case.optics, origins, directions)
    seen = tau >= 1.0
    hit = S.depth_one_points(case, origins, directions, seen)
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    normal = (hit - centre) / np.linalg.norm(hit - centre, axis=1)[:, None]
    mu0, muv = normal @ sun_towards(), -(normal * directions).sum(1)
    per = case.pixels ** 2
    print(f"{case.name}: regions (green channel; mu0 sun to normal, limb: normal-to-camera cosine < 0.5)")
    for v, view in enumerate(case.views):
        s = slice(v * per, (v + 1) * per)
        m, b, sn = mean[s, 1], baked[s, 1], seen[s]
        print(f"  view {view}: reference {m[sn].sum():.3f}, baked {b[sn].sum():.3f} ({b[sn].sum() / m[sn].sum() - 1:+.0%})")
        for lo, hi in [(-1.0, -0.3), (-0.3, 0.0), (0.0, 0.3), (0.3, 0.6), (0.6, 1.01)]:
            for vlo, vhi, what in [(0.0, 0.5, "limb"), (0.5, 1.01, "face")]:
                k = sn & (mu0[s] >= lo) & (mu0[s] < hi) & (muv[s] >= vlo) & (muv[s] < vhi)
                if k.sum():
                    print(f"    mu0 [{lo:+.1f}, {hi:+.1f}) {what}: {k.sum():2d} blocks, reference {m[k].sum():.3f}, "
                          f"baked {b[k].sum():.3f} ({b[k].sum() / m[k].sum() - 1:+.0%}), missing {m[k].sum() - b[k].sum():+.3f}")
    against = [i for i, view in enumerate(case.views) if tuple(view) == (180, 0)][0]
    rows = [against * per + i for i in TOP_ROWS if seen[against * per + i]]
    broad_path = os.path.join(folder, "broad.vdb")
    write_without_peaks(path, broad_path)
    broad = firncore.render_baked(broad_path, case.optics, origins, directions)
    print(f"\n  view (180, 0)'s top two rows: block, reference, baked, its peaked lobe's part, exact single scattering, mu0, mu_v")
    for j in rows:
        print(f"    {j - against * per:2d}  {mean[j, 1]:.4f}  {baked[j, 1]:.4f}  {baked[j, 1] - broad[j, 1]:+.4f}  "
              f"{single_scattering(case, origins[j], directions[j]):.4f}  {mu0[j]:+.2f}  {muv[j]:.2f}")
    print("\n  the same blocks, sun only, the ball cut below voxel layer z (Monte Carlo 8192 paths; bake FINAL seed 0):")
    for cut in (None, 8, 10, 11, 12):
        density = case.density.copy()
        if cut is not None:
            density[:, :, :cut] = 0.0
        cut_path = os.path.join(folder, f"cut{cut}.vdb")
        S.write_density(cut_path, density, case.voxel)
        m, e = firncore.monte_carlo_radiance(cut_path, case.optics, origins[rows], directions[rows], suns=case.suns(),
                                             samples=8192, seed=3)
        stats = firncore.bake(cut_path, case.optics, suns=case.suns(), quality="FINAL", seed=0)
        b = firncore.render_baked(cut_path, case.optics, origins[rows], directions[rows])
        print(f"    z < {cut}: {stats['traced_voxels']} traced ({stats['light_traced_voxels']} light traced), "
              f"reference noise {np.median(e[:, 1] / np.maximum(m[:, 1], 1e-30)):.1%}")
        print("      reference " + " ".join(f"{x:.4f}" for x in m[:, 1]))
        print("      baked     " + " ".join(f"{x:.4f}" for x in b[:, 1]))


if __name__ == "__main__":
    main()
