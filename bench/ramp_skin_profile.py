"""The sun's light across the density ramp of ball_issue's lit band seen from the side, by depth below the level set:
the core's Monte Carlo against the bake (docs/benchmarks.md, issue-skin; plateau-sun 2 found the truth brightest in
the ramp's outer part, the bake flat through it).

Rays along -y (the side view (90, 0)) through points (x, z) cm from the ball's centre, the sun from +x at 30 deg up
(mu0 0.14-0.5). Each ray is started at depths along it every quarter voxel, from 2 voxels outside the level set (the
sphere r: voxel value 0.5) to 1.5 inside; L(a), the radiance of the ray started at a, is the Monte Carlo's (cached in
--cache) and the baked render's. A stretch [a, b] sends the camera T(0, a) (L(a) - T(a, b) L(b)), T the trilinear
density's transmittance; its mean source function towards the camera is (L(a) - T(a, b) L(b)) / (1 - T(a, b)), taken
over the rays weighted by (1 - T(a, b)) T(0, a). Per depth (the stretch's middle, voxels below the level set along
its normal): what the camera gets (x 1000, the sun 1 W/m^2), the Monte Carlo's exact single scattering in it
(snow_block_split.py's), the bake's and its peaked lobes' part (grids firn_source_peak*), the mean source functions.
--orders: the Monte Carlo's mean source split by scattering order instead (needs the core built with the Monte Carlo
part of bench/rim_forward_hooks.diff: FIRN_MC_GATE counts a camera path's sun at collision orders lo..hi only).
--shares: instead, what share of the rays' baked render each class of voxels' values gives (each class's values scaled
by 1.5 in turn: the first air shell, the air beyond, the fringe voxels 0 < rho < full, the full voxels).
--plane: the same on a flat antialiased half-space (the ball's ramp, clip(0.5 - d / h)) whose normal is the band's
middle (x 1.5, z 0.5: mu0 0.31), rays along -y through points of its level set: the ball's curvature removed.

    PYTHONPATH=build/python python3 bench/ramp_skin_profile.py [--plane] [--orders] [--shares] [--samples 16384]
"""

import argparse
import math
import os
import re
import tempfile

import numpy as np

import pyopenvdb

import bake_suite
import firncore
from backlit_probe import write_without_peaks
from snow_block_split import single_scattering

COLUMNS = "0.5,0.5;1.0,0.5;1.5,0.5;2.0,0.5;2.5,0.5;0.5,1.5;1.0,1.5;1.5,1.5;2.0,1.5;2.5,1.5"  # (x, z) cm: the lit band
STARTS = np.arange(2.0, -1.51, -0.25)  # voxels along the ray past its meeting the level set (positive: outside)
DOWN = np.array([0.0, -1.0, 0.0])
ORDERS = [(1, 1), (2, 4), (5, 8), (9, 16), (17, 1 << 40)]
PLANE_NORMAL = np.array([0.3, math.sqrt(1.0 - 0.3 ** 2 - 0.1 ** 2), 0.1])  # the ball's at (1.5, 0.5) cm
PLANE_POINTS = [(0.0, 0.0), (0.3, 0.4), (-0.4, 0.2), (0.15, -0.35), (-0.2, -0.45)]  # voxels (x, z) off its middle


def ball_rays(case, radius, x_cm, z_cm):
    """The starts of the ray along -y through (x, z) cm from the ball's centre (m), and the depth (voxels below the
    sphere) of a point."""
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    x, z = x_cm / 100.0, z_cm / 100.0
    meets = centre[1] + np.sqrt(radius ** 2 - x ** 2 - z ** 2)
    starts = np.array([[centre[0] + x, meets + s * case.voxel, centre[2] + z] for s in STARTS])
    return starts, lambda p: (radius - np.linalg.norm(p - centre)) / case.voxel


def plane(normal=PLANE_NORMAL, voxels=40):
    """The half-space below the plane through the grid's middle of unit normal `normal` (voxel values, the ball's
    one-voxel ramp), and that middle (index space)."""
    middle = (voxels - 1) / 2
    X, Y, Z = bake_suite.grid((voxels,) * 3)
    above = (X - middle) * normal[0] + (Y - middle) * normal[1] + (Z - middle) * normal[2]
    fill = np.clip(0.5 - above, 0.0, 1.0)
    for axis in range(3):  # empty margins: the bake's topology dilates by 3 voxels
        index = [slice(None)] * 3
        index[axis] = np.r_[0:2, voxels - 2:voxels]
        fill[tuple(index)] = 0.0
    return fill, np.full(3, middle)


def plane_rays(case, middle, dx, dz):
    p = (middle + np.array([dx, 0.0, dz])) * case.voxel
    meets = p[1] - (p - middle * case.voxel) @ PLANE_NORMAL / PLANE_NORMAL[1]  # y on the level set
    starts = np.array([[p[0], meets + s * case.voxel, p[2]] for s in STARTS])
    return starts, lambda q: -(q - middle * case.voxel) @ PLANE_NORMAL / case.voxel


def transmittance(case, origin, a, b, step=0.0001):
    s = np.arange(a + step / 2, b, step)
    rho = bake_suite.trilinear(case.density, (origin + s[:, None] * DOWN) / case.voxel)
    return float(np.exp(-case.sigma_t / case.rho * rho.sum() * step))


def render_shares(case, path, origins, directions):
    """The share of the render along the rays that each class of voxels' baked values gives."""
    rho, full = case.density, case.density.max()
    centre = (np.array(rho.shape) - 1) / 2
    radius = np.linalg.norm(np.stack(np.meshgrid(*map(np.arange, rho.shape), indexing="ij"), -1) - centre, axis=-1)
    classes = {"air, first shell (rho 0, r < 6 voxels)": (rho == 0) & (radius < 6.0),
               "air beyond": (rho == 0) & (radius >= 6.0), "fringe (0 < rho < full)": (rho > 0) & (rho < full),
               "full": rho == full}
    whole = firncore.render_baked(path, case.optics, origins, directions)[:, 1].sum()
    with tempfile.TemporaryDirectory() as folder:
        scaled = os.path.join(folder, "scaled.vdb")
        for name, mask in classes.items():
            grids, metadata = pyopenvdb.readAll(path)
            for grid in (g for g in grids if g.name.startswith("firn_source")):
                accessor = grid.getAccessor()
                for voxel in zip(*(v.tolist() for v in np.nonzero(mask))):
                    value, on = accessor.probeValue(voxel)
                    if on:
                        accessor.setValueOn(voxel, tuple(1.5 * v for v in value))
            pyopenvdb.write(scaled, grids=list(grids), metadata=metadata)
            more = firncore.render_baked(scaled, case.optics, origins, directions)[:, 1].sum()
            print(f"  {name:40s} {100 * (more / whole - 1) / 0.5:5.1f} % of the render")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_issue")
    parser.add_argument("--plane", action="store_true")
    parser.add_argument("--orders", action="store_true")
    parser.add_argument("--shares", action="store_true")
    parser.add_argument("--samples", type=int, default=16384)
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_ramp_skin"))
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    case.sky = 0.0
    if args.plane:
        fill, middle = plane()
        case.density = fill * case.density.max()
        rays = [(f"plane_{dx:g}_{dz:g}", plane_rays(case, middle, dx, dz)) for dx, dz in PLANE_POINTS]
    else:
        radius = float(re.search(r"r (\d+) cm", case.what).group(1)) / 100.0
        columns = [tuple(float(v) for v in c.split(",")) for c in COLUMNS.split(";")]
        rays = [(f"{x:g}_{z:g}", ball_rays(case, radius, x, z)) for x, z in columns]
    os.makedirs(args.cache, exist_ok=True)
    folder = tempfile.mkdtemp()
    path, flat = os.path.join(folder, "snow.vdb"), os.path.join(folder, "flat.vdb")
    bake_suite.write_density(path, case.density, case.voxel)
    firncore.bake(path, case.optics, suns=case.suns(), quality="FINAL", seed=0)
    write_without_peaks(path, flat)
    if args.shares:
        origins = np.array([starts[0] for _, (starts, _) in rays])
        print(f"{case.name}: the baked render of the {len(rays)} rays along -y by the voxels whose values it reads")
        return render_shares(case, path, origins, np.repeat(DOWN[None], len(origins), 0))
    stretches = len(STARTS) - 1
    sent = {k: np.zeros(stretches) for k in ("mc", "once", "baked", "peak")}
    weight, depth = np.zeros(stretches), np.zeros(stretches)
    for name, (origins, depth_of) in rays:
        directions = np.repeat(DOWN[None], len(origins), 0)
        cached = os.path.join(args.cache, f"{case.name}_{name}_{args.samples}.npy")
        if not os.path.exists(cached):
            mc, _ = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                                  samples=args.samples, seed=37)
            np.save(cached, mc[:, 1])
        L = {"mc": np.load(cached), "baked": firncore.render_baked(path, case.optics, origins, directions)[:, 1]}
        L["peak"] = L["baked"] - firncore.render_baked(flat, case.optics, origins, directions)[:, 1]
        for lo, hi in ORDERS if args.orders else []:
            gated = cached.replace(".npy", f"_orders{lo}.npy")
            if not os.path.exists(gated):
                os.environ["FIRN_MC_GATE"] = f"{lo} {hi} 0 0 0 0 1e9 -2 2 0 0 1"
                mc, _ = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                                      samples=args.samples, seed=41)
                del os.environ["FIRN_MC_GATE"]
                np.save(gated, mc[:, 1])
            L[f"orders {lo}-{hi if hi < 1000 else ''}"] = np.load(gated)
        s = (STARTS[0] - STARTS) * case.voxel  # m from the first start
        for k in range(stretches):
            seen, T = transmittance(case, origins[0], 0.0, s[k]), transmittance(case, origins[0], s[k], s[k + 1])
            depth[k] += depth_of(origins[0] + 0.5 * (s[k] + s[k + 1]) * DOWN) / len(rays)
            weight[k] += seen * (1.0 - T)
            for key in L:
                sent.setdefault(key, np.zeros(stretches))[k] += seen * (L[key][k] - T * L[key][k + 1])
            sent["once"][k] += single_scattering(case, origins[0], DOWN, s[k], s[k + 1])
    print(f"{'a plane of the band normal' if args.plane else case.name}, the sun alone, {len(rays)} rays along -y, "
          f"{args.samples} paths; x 1000")
    print("depth (voxels)  camera gets: MC   once  baked   peak  (baked/MC - 1)   mean source: MC  baked  peak  weight")
    for k in np.flatnonzero(weight >= 0.004 * len(rays)):
        w = weight[k]
        print(f"{depth[k]:+6.2f}        {1000 * sent['mc'][k]:8.2f} {1000 * sent['once'][k]:6.2f} "
              f"{1000 * sent['baked'][k]:6.2f} {1000 * sent['peak'][k]:6.2f}  ({100 * (sent['baked'][k] / sent['mc'][k] - 1):+5.0f} %)"
              f"      {1000 * sent['mc'][k] / w:7.1f} {1000 * sent['baked'][k] / w:6.1f} {1000 * sent['peak'][k] / w:6.1f}"
              f"  {w:.3f}")
    if args.orders:
        keys = [key for key in sent if key.startswith("orders")]
        print("depth (voxels)  mean source by order: " + "  ".join(keys))
        for k in np.flatnonzero(weight >= 0.02 * len(rays)):
            print(f"{depth[k]:+6.2f}         " + "  ".join(f"{1000 * sent[key][k] / weight[k]:9.1f}" for key in keys))
        total = sum(sent[key].sum() for key in keys)
        print("the camera's share: " + "  ".join(f"{100 * sent[key].sum() / total:.1f} %" for key in keys))
    print(f"the stretch: MC {1000 * sent['mc'].sum():.1f}, baked {1000 * sent['baked'].sum():.1f} "
          f"({100 * (sent['baked'].sum() / sent['mc'].sum() - 1):+.1f} %)")


if __name__ == "__main__":
    main()
