"""Lamps at a ball's terminator: the bake against the core's Monte Carlo under a point, a spot and an area lamp, and
under the sun from the same direction (docs/benchmarks.md, ramp-lamps).

The suite's balls (bench/bake_suite.py: ball_issue's and ball_grey's snow), no sky, one light each time: the sun from
azimuth 0 and elevation 30 degrees, or a lamp in that direction 15 cm from the ball's centre (3 radii: the lit cap
ends 70.5 degrees from the lamp), a point, a spot (50 degree cone, blend 0.3, on the ball's centre) or a 40 x 40 cm
rectangle facing the ball (the patches to about 110 degrees past its centre's terminator see part of it). Each lamp
gives 1 W/m^2 at the point of the ball nearest it, as the sun does. The suite's views (towards the light, across the
terminator, against the light, from above), one block per pixel; per light: mean and worst |relative error|, bias,
per view bias, and the ratio of sums by where each block's ray reaches optical depth 1: the cosine between the
surface's outward normal there and the way to the lamp's centre (lit, grazing 0-0.2, past the terminator -0.5-0,
dark). The references are cached under --cache by case, light and samples.

    PYTHONPATH=build/python python3 bench/lamp_terminator.py [--cases ball_grey,ball_issue] [--lights sun,point,...]

--voxel 0.005 bakes the same ball (the same snow per metre) on finer voxels, --samples sets the reference's paths per
block (their own cached references): a near lamp's light varying across a voxel is a question of the voxel's size
(docs/benchmarks.md, grey-lamps2).

--round 24 takes 24 views spread over the sphere instead of the suite's four: its bias is the light leaving the
ball in all directions, the bake's against the truth's.

--sweep: the terminator crossing patches (the ramp's jump at mu0 = 0): the sun alone rotated in 0.5 degree steps
about the y axis (elevation 18-42), the baked source (broad l0 + peaked, green, W/m^2/sr) of the outer voxels
(centres beyond R - h) in the sun's plane whose normals lie 80-100 degrees from the sun at elevation 30, printed
against mu0 = cos(normal, sun).
"""

import argparse
import dataclasses
import hashlib
import math
import os
import tempfile
import time

import numpy as np

import firncore
from bake_suite import SUN_ELEVATION, ball, case as suite_case, depth_one_points, views, write_density

DISTANCE = 0.15  # m, lamp to the ball's centre
SPOT_ANGLE_DEG, SPOT_BLEND = 50.0, 0.3  # the spot's cone (degrees) and blend
AREA_SIZE = (0.4, 0.4)  # m, the rectangle's sides
TOWARDS = np.array([math.cos(SUN_ELEVATION), 0.0, math.sin(SUN_ELEVATION)])  # unit, from the ball to the light
BANDS = [("lit", 0.2, 2.0), ("grazing", 0.0, 0.2), ("past", -0.5, 0.0), ("dark", -2.0, -0.5)]
SAMPLES = {"ball_grey": 16384, "ball_issue": 4096}  # paths per pixel: ball_issue's 16384 take 4.5 minutes a light


def centre_of(case):
    return (np.array(case.density.shape) - 1) / 2 * case.voxel


def on_voxels(case, voxel):
    """`case`'s ball (radius 5 cm, the same snow per metre) on voxels of `voxel` m."""
    return dataclasses.replace(case, density=ball(0.05, voxel) * case.rho, voxel=voxel)


def round_views(n):
    """n view directions (azimuth, elevation; degrees) spread evenly over the sphere (a Fibonacci lattice): the sum of
    the blocks over them is the light leaving the ball, in every direction at once."""
    views = []
    for k in range(n):
        z = 1.0 - (k + 0.5) / n * 2.0
        views.append((round(k * 137.50776 % 360.0, 2), round(math.degrees(math.asin(z)), 2)))
    return views


def lamp(kind, case):
    """The lamp `kind` for `case`, scaled to 1 W/m^2 (grey) at the ball's point nearest it; None for the sun."""
    if kind == "sun":
        return None
    c = centre_of(case)
    position = tuple(c + DISTANCE * TOWARDS)
    axis = tuple(-TOWARDS)
    if kind not in ("point", "spot", "area"):
        raise ValueError(f"no light {kind!r}: sun, point, spot, area")

    def made(e):
        if kind == "point":
            return firncore.Lamp("POINT", position, (e,) * 3)
        if kind == "spot":
            return firncore.Lamp("SPOT", position, (e,) * 3, axis=axis, spot_angle=math.radians(SPOT_ANGLE_DEG),
                                 spot_blend=SPOT_BLEND)
        return firncore.Lamp("RECTANGLE", position, (e,) * 3, axis=axis, tangent=(0.0, 1.0, 0.0), size=AREA_SIZE)

    radius = 0.05  # the suite's balls
    nearest = tuple(c + radius * TOWARDS)
    unit = made(1.0).irradiance(nearest, tuple(TOWARDS), samples=20000, seed=1)[1]
    return made(1.0 / unit)


def reference(case, kind, path, origins, directions, samples, cache):
    """The core's Monte Carlo under light `kind`, cached in folder `cache` (None: not cached)."""
    lamps = f"{DISTANCE} {SPOT_ANGLE_DEG} {SPOT_BLEND} {AREA_SIZE}"  # a changed lamp is not read from an old file
    key = hashlib.sha1(f"{case.key()} {kind} {lamps} {samples} v2".encode()).hexdigest()[:16]
    file = os.path.join(cache, f"{case.name}_{kind}_{key}.npz") if cache else None
    if file and os.path.exists(file):
        data = np.load(file)
        return data["mean"], data["error"]
    light = lamp(kind, case)
    mean, error = firncore.monte_carlo_radiance(path, case.optics, origins, directions,
                                                suns=case.suns() if light is None else [],
                                                lamps=[] if light is None else [light], samples=samples, seed=11)
    if file:
        np.savez(file + ".tmp.npz", mean=mean, error=error)
        os.replace(file + ".tmp.npz", file)
    return mean, error


def local_cosine(case, kind, points):
    """Cosine between the ball's outward normal at each point and the way to the light (its centre for a lamp)."""
    c = centre_of(case)
    normal = points - c
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    if kind == "sun":
        way = np.broadcast_to(TOWARDS, points.shape)
    else:
        way = c + DISTANCE * TOWARDS - points
        way = way / np.linalg.norm(way, axis=1, keepdims=True)
    return np.sum(normal * way, axis=1)


def measure(case, kind, folder, cache, samples=None):
    """The bake of `case` (its sky set to none) under light `kind` against the Monte Carlo (`samples` paths per block;
    None: SAMPLES'): the row main prints, with per view "views" and per view and band "bands" (ratio - 1, blocks)."""
    path = os.path.join(folder, case.name + ".vdb")
    write_density(path, case.density, case.voxel)
    case.sky = 0.0
    origins, directions, tau = views(case)
    mean, error = reference(case, kind, path, origins, directions, samples or SAMPLES.get(case.name, 4096), cache)
    light = lamp(kind, case)
    start = time.perf_counter()
    firncore.bake(path, case.optics, suns=case.suns() if light is None else [], lamps=[] if light is None else [light],
                  quality="FINAL", seed=0)
    seconds = time.perf_counter() - start
    baked = firncore.render_baked(path, case.optics, origins, directions)
    seen = tau >= 1.0
    points = depth_one_points(case, origins, directions, seen)
    cosine = local_cosine(case, kind, np.nan_to_num(points))
    per = case.pixels ** 2
    m, b = mean[seen], baked[seen]
    relative = b[m > 0] / m[m > 0] - 1.0  # blocks no path reached (a point lamp's far side) left out
    row = {"mean": np.abs(relative).mean(), "worst": relative.flat[np.abs(relative).argmax()],
           "bias": b.sum() / m.sum() - 1.0, "noise": np.median(error[seen] / np.maximum(m, 1e-30)), "bake_s": seconds}
    row["views"] = []
    for v in range(len(case.views)):
        part = slice(v * per, (v + 1) * per)
        row["views"].append(baked[part][seen[part]].sum() / mean[part][seen[part]].sum() - 1.0)
    row["bands"] = []
    for v in range(len(case.views)):
        part = np.zeros(len(seen), dtype=bool)
        part[v * per:(v + 1) * per] = True
        cells = []
        for _, lo, hi in BANDS:
            sel = part & seen & (cosine >= lo) & (cosine < hi)
            ref = mean[sel].sum()
            cells.append((baked[sel].sum() / ref - 1.0, int(sel.sum())) if sel.any() and ref > 0 else (math.nan, 0))
        row["bands"].append(cells)
    return row


def sweep(name, folder):
    import pyopenvdb
    case = suite_case(name)
    centre = centre_of(case)
    path = os.path.join(folder, name + ".vdb")
    j = case.density.shape[1] // 2  # the y = centre plane (the balls' even sizes: the nearer of the two)
    voxels = []
    for i, k in zip(*np.nonzero(case.density[:, j, :] > 0.0)):
        n = np.array([i, j, k]) * case.voxel - centre
        outer = np.linalg.norm(n) > 0.05 - case.voxel  # the balls' radius 5 cm: the outer layer
        n /= np.linalg.norm(n)
        if outer and abs(math.degrees(math.acos(np.dot(n, TOWARDS))) - 90.0) < 10.0:
            voxels.append(((i, j, k), n))
    rows = []
    for elevation in np.arange(18.0, 42.01, 0.5):
        write_density(path, case.density, case.voxel)
        e = math.radians(elevation)
        sun = np.array([math.cos(e), 0.0, math.sin(e)])
        firncore.bake(path, case.optics, suns=[firncore.SunLight(tuple(sun), (1.0,) * 3, 0.0093)], quality="FINAL",
                      seed=0)
        grids = {g.name: g for g in pyopenvdb.readAll(path)[0]}

        def read(g, c):
            return np.array(grids[g].getConstAccessor().getValue(tuple(int(x) for x in c)))

        rows.append([(float(np.dot(n, sun)), float(read("firn_source", c)[1] + read("firn_source_peak", c)[1]))
                     for c, n in voxels])
    print(f"{name}: the sun alone, elevation 18-42 degrees in 0.5 steps; per surface voxel (i, j, k): mu0, source")
    for v, (c, _) in enumerate(voxels):
        print(f"  {c}: " + " ".join(f"{mu:+.3f}:{src:.4f}" for mu, src in (r[v] for r in rows) if abs(mu) < 0.12))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="ball_grey,ball_issue")
    parser.add_argument("--lights", default="sun,point,spot,area")
    parser.add_argument("--voxel", type=float, help="m: the ball on these voxels instead of the case's")
    parser.add_argument("--samples", type=int, help="the reference's paths per block instead of SAMPLES'")
    parser.add_argument("--round", type=int, help="this many views spread over the sphere instead of the case's")
    parser.add_argument("--sweep", action="store_true", help="the terminator sweep instead (the first case)")
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_lamp_terminator"))
    args = parser.parse_args()
    os.makedirs(args.cache, exist_ok=True)
    with tempfile.TemporaryDirectory() as folder:
        if args.sweep:
            return sweep(args.cases.split(",")[0], folder)
        for name in args.cases.split(","):
            case = suite_case(name)
            if args.voxel:
                case = on_voxels(case, args.voxel)
            if args.round:
                case = dataclasses.replace(case, views=round_views(args.round))
            what = case.what + (" at 1 cm" if args.voxel else "")
            print(f"{name}: {what}; voxel {case.voxel * 100:g} cm; no sky; views {case.views}")
            print(f"  {'light':<6} {'mean':>6} {'worst':>6} {'bias':>6} {'noise':>6}   per view bias")
            rows = {}
            for kind in args.lights.split(","):
                r = rows[kind] = measure(case, kind, folder, args.cache, args.samples)
                print(f"  {kind:<6} {100 * r['mean']:5.1f}% {100 * r['worst']:+5.0f}% {100 * r['bias']:+5.1f}% "
                      f"{100 * r['noise']:5.1f}%   " + "  ".join(f"{100 * x:+4.0f}%" for x in r["views"]), flush=True)
            print("  by the local cosine to the light (baked / Monte Carlo - 1 of the sums, blocks): "
                  + ", ".join(f"{n} [{lo}, {hi})" for n, lo, hi in BANDS))
            for kind, r in rows.items():
                for v, cells in enumerate(r["bands"]):
                    print(f"  {kind:<6} view {str(case.views[v]):<9} " +
                          "  ".join(f"{b:<7} {'-':>11}" if n == 0 else f"{b:<7} {100 * x:+5.0f}% ({n:3d})"
                                    for (b, _, _), (x, n) in zip(BANDS, cells)))
            print(flush=True)


if __name__ == "__main__":
    main()
