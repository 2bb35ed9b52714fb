"""The bake against the core's brute-force Monte Carlo on small, thin and thick snow shapes (docs/bake.md, Accuracy).

Each case is a density grid (balls, slabs, a sharp box, a bumpy layer with a plate, a cloud of thrown lumps), one
optics, a sun and/or a sky, and orthographic views around the object (towards the sun, across the terminator,
against the sun, from above and below). Every pixel is one block: one camera ray through its centre, all three
colour channels, rendered two ways against `firncore.monte_carlo_radiance` (all orders, sharing none of the bake's
approximations): the mixed form, the headline (`firncore.render_scattering_where_thin`: as Cycles renders the
add-on's default material, Scatter Thin Snow, scattering in the bake's traced thin voxels and drawing the baked
source elsewhere; a Monte Carlo render of --mixed paths per block, whose own noise the "render noise" column gives),
and the baked form (`firncore.render_baked`, the emission-absorption integral Cycles draws with Scatter Thin Snow
off; --baked-only for it alone, as tests/ and bench/against_sun.py score). Pixels whose ray passes through less
than optical depth 1 of snow are left out (the renderer's own transparency, not the bake, decides those). Reported
per case: mean and worst |relative error| over the blocks, bias (sum of rendered radiance over sum of reference
radiance, minus 1), the reference's median relative standard error per block (its noise is part of the errors),
bake time and reference time. The reference is cached by case under the output folder, so changing the bake reruns
only the bake.

    PYTHONPATH=build/python python3 bench/bake_suite.py [--cases a,b] [--cache DIR] [--markdown] [--fresh] [--maps]
        [--mixed PATHS | --baked-only]
"""

import argparse
import hashlib
import math
import os
import tempfile
import time
from dataclasses import dataclass, field

import numpy as np
import pyopenvdb

import firncore

SUN_ELEVATION = math.radians(30.0)
CACHE = os.path.join(tempfile.gettempdir(), "firn_bake_suite")  # the references, by case
MIXED_PATHS = 32768  # the mixed render's paths per block: its noise under 0.5 point of every case's mean (mixed_noise.py)


@dataclass
class Case:
    name: str
    what: str
    density: np.ndarray  # kg/m^3, voxel (i, j, k) centred at (i, j, k) * voxel
    voxel: float  # m
    sigma_t: float  # 1/m at density `rho`
    rho: float
    omega: tuple
    g: float
    sun: float = 1.0  # W/m^2, from azimuth 0 and SUN_ELEVATION
    sky: float = 0.05  # W/m^2/sr
    views: list = field(default_factory=list)  # (azimuth deg, elevation deg)
    pixels: int = 8
    samples: int = 1024
    occluders: list = field(default_factory=list)

    @property
    def optics(self):
        return firncore.VolumeOptics(self.sigma_t / self.rho, self.omega, self.g)

    def suns(self):
        if self.sun <= 0.0:
            return []
        d = (math.cos(SUN_ELEVATION), 0.0, math.sin(SUN_ELEVATION))
        return [firncore.SunLight(d, (self.sun,) * 3, 0.0093)]

    def skies(self):
        return firncore.Sky((self.sky,) * 3) if self.sky > 0.0 else None

    def key(self):
        h = hashlib.sha1(self.density.tobytes())
        h.update(np.ascontiguousarray(views(self)[0]).tobytes())
        h.update(repr((self.voxel, self.sigma_t, self.rho, self.omega, self.g, self.sun, self.sky, self.views,
                       self.pixels, self.samples, [(v.tobytes(), t.tobytes(), a) for v, t, a in self.occluders])).encode())
        return h.hexdigest()[:16]


def view_map(case, values):
    """One view's per-block values as text, laid out as the camera sees them (top row up), rounded to 0.01."""
    return np.array2string(np.round(values.reshape(case.pixels, case.pixels)[::-1], 2), max_line_width=200)


def print_view_maps(case, values, seen=None):
    """Every view's per-block values (all views' blocks in order), each laid out by view_map under its name; given
    `seen` (a mask over all blocks), `values` holds the seen blocks' alone, as scored's "relative" does (others: nan)."""
    if seen is not None:
        full = np.full(len(seen), np.nan)
        full[seen] = values
        values = full
    per = case.pixels * case.pixels
    for v, view in enumerate(case.views):
        print(f"    view {view}:")
        print(view_map(case, values[v * per:(v + 1) * per]))


def grid(n):
    return np.meshgrid(*[np.arange(m, dtype=float) for m in n], indexing="ij")


def coverage(inside, shape, voxel, sub=4):
    """Fraction of each voxel inside the shape (sub^3 points per voxel): partly filled voxels, as a rasterizer makes."""
    out = np.zeros(shape)
    offsets = (np.arange(sub) + 0.5) / sub - 0.5
    X, Y, Z = grid(shape)
    for a in offsets:
        for b in offsets:
            for c in offsets:
                out += inside((X + a) * voxel, (Y + b) * voxel, (Z + c) * voxel)
    return out / sub ** 3


def ball(radius, voxel, pad=3):
    n = int(math.ceil(2 * radius / voxel)) + 2 * pad
    centre = (n - 1) / 2 * voxel
    X, Y, Z = grid((n, n, n))
    distance = np.sqrt((X * voxel - centre) ** 2 + (Y * voxel - centre) ** 2 + (Z * voxel - centre) ** 2) - radius
    return np.clip(0.5 - distance / voxel, 0.0, 1.0)  # one-voxel antialiased surface


def box(size, voxel, pad=2):
    n = [int(round(s / voxel)) + 2 * pad for s in size]
    fill = np.zeros(n)
    fill[pad:-pad, pad:-pad, pad:-pad] = 1.0  # sharp edges
    return fill


def slab(width, layers, pad=2):
    fill = np.zeros((width + 2 * pad, width + 2 * pad, layers + 2 * pad))
    fill[pad:-pad, pad:-pad, pad:-pad] = 1.0
    return fill


def slab_top(fill, layers, h, pad=2):
    """The point (m) half a voxel under the middle of slab(width, layers, pad)'s top: its last layer's centre."""
    return np.array([(fill.shape[0] - 1) / 2 * h, (fill.shape[1] - 1) / 2 * h, (pad + layers - 0.5) * h])


BUMPS = (14.0, 11.0)  # voxels: the bumpy layer's wavelengths along x and y


def bumpy_top(x, y, depth, amplitude):
    """The bumpy layer's top (voxels) over (x, y) (voxels)."""
    return depth + amplitude * np.sin(2 * np.pi * x / BUMPS[0]) * np.cos(2 * np.pi * y / BUMPS[1])


def bumpy(side, depth, amplitude):
    X, Y, Z = grid((side, side, depth + amplitude + 3))
    top = bumpy_top(X, Y, depth, amplitude)
    fill = np.clip(top - Z + 0.5, 0.0, 1.0)
    fill[:, :, 0] = 0.0  # the ground lies under the lowest layer
    return fill


def spray(voxel, lumps=24, seed=3):
    """Thrown snow: lumps of 0.5-1.5 cm radius scattered through a 14 cm cloud, rasterized with coverage."""
    rng = np.random.default_rng(seed)
    n = int(math.ceil(0.18 / voxel))
    centres = rng.uniform(0.03, 0.15, size=(lumps, 3))
    radii = rng.uniform(0.005, 0.015, size=lumps)

    def inside(x, y, z):
        hit = np.zeros(x.shape, dtype=bool)
        for c, r in zip(centres, radii):
            hit |= (x - c[0]) ** 2 + (y - c[1]) ** 2 + (z - c[2]) ** 2 < r * r
        return hit

    return coverage(inside, (n, n, n), voxel)


def plate(x0, x1, y0, y1, z, albedo):
    vertices = np.array([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]], dtype=float)
    return vertices, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32), albedo


ROUND = [(0, 0), (90, 0), (180, 0), (0, 60)]  # towards the sun, terminator, against the sun, from above


def case(name):
    """The suite's case of that name (ValueError naming the cases if none)."""
    found = [c for c in cases() if c.name == name]
    if not found:
        raise ValueError(f"no suite case {name!r}; the cases: {', '.join(c.name for c in cases())}")
    return found[0]


def cases():
    out = []
    add = out.append
    # The ball: small, moderately thick, somewhat absorbing, sun plus a dim sky.
    add(Case("ball_issue", "ball r 5 cm, 1 cm voxels (tau 10), omega 0.98, g 0.85", ball(0.05, 0.01) * 100, 0.01,
             1000.0, 100.0, (0.98,) * 3, 0.85, views=ROUND, samples=65536))
    add(Case("ball_thin", "ball r 3 cm, tau 1 per voxel, 3 tmfp across, omega 0.999, g 0.5", ball(0.03, 0.01) * 100,
             0.01, 100.0, 100.0, (0.999,) * 3, 0.5, views=ROUND, samples=16384))
    add(Case("ball_thin_forward", "ball r 3 cm, tau 1 per voxel, under 1 tmfp across, omega 0.999, g 0.85",
             ball(0.03, 0.01) * 100, 0.01, 100.0, 100.0, (0.999,) * 3, 0.85, views=ROUND, samples=16384))
    add(Case("ball_half_tau", "ball r 8 cm, tau 0.5 per voxel, omega 0.99, g 0.3", ball(0.08, 0.01) * 100, 0.01,
             50.0, 100.0, (0.99,) * 3, 0.3, views=ROUND, samples=16384))
    add(Case("ball_grey", "ball r 5 cm, tau 5 per voxel, omega 0.9, g 0.6 (absorbing)", ball(0.05, 0.01) * 100, 0.01,
             500.0, 100.0, (0.9,) * 3, 0.6, views=ROUND, samples=16384))
    add(Case("ball_rgb", "ball r 6 cm, tau 3, omega 0.95 / 0.99 / 0.999, g 0.7", ball(0.06, 0.01) * 100, 0.01,
             300.0, 100.0, (0.95, 0.99, 0.999), 0.7, views=ROUND, samples=16384))
    add(Case("ball_snow", "ball r 8 cm, tau 20 per voxel, omega 0.9999, g 0.85 (snow)", ball(0.08, 0.01) * 300, 0.01,
             2000.0, 300.0, (0.9999,) * 3, 0.85, views=ROUND, samples=32768))
    add(Case("ball_clean", "ball r 4 cm, 5 mm voxels, tau 30, omega 1-1e-7, g 0.85", ball(0.04, 0.005) * 300, 0.005,
             6000.0, 300.0, (1.0 - 1e-7,) * 3, 0.85, views=ROUND, samples=32768))
    add(Case("ball_forward", "ball r 5 cm, tau 4, omega 0.999, g 0.9", ball(0.05, 0.01) * 100, 0.01, 400.0, 100.0,
             (0.999,) * 3, 0.9, views=ROUND, samples=65536))
    add(Case("ball_sky", "ball r 5 cm under sky only, tau 5, omega 0.99, g 0.7", ball(0.05, 0.01) * 100, 0.01, 500.0,
             100.0, (0.99,) * 3, 0.7, sun=0.0, sky=1.0, views=[(0, 0), (0, 60), (0, -60)], samples=16384))
    # The brief's corners the cases above leave: isotropic scattering (g 0), and voxels 60 optical depths thick.
    add(Case("ball_iso", "ball r 5 cm, tau 6 per voxel, omega 0.999, g 0 (isotropic)", ball(0.05, 0.01) * 100, 0.01,
             600.0, 100.0, (0.999,) * 3, 0.0, views=ROUND, samples=16384))
    add(Case("ball_deep", "ball r 5 cm, tau 60 per voxel, omega 0.9999, g 0.85", ball(0.05, 0.01) * 300, 0.01,
             6000.0, 300.0, (0.9999,) * 3, 0.85, views=ROUND, samples=16384))
    add(Case("slab_thin", "slab 3 cm (3 voxels, tau 2 each), omega 0.99, g 0.6", slab(24, 3) * 100, 0.01, 200.0, 100.0,
             (0.99,) * 3, 0.6, views=[(0, 60), (90, 75), (0, -60), (180, -75)], samples=16384))
    add(Case("slab_thin_forward", "slab 3 cm (3 voxels, tau 1 each), omega 0.9999, g 0.87", slab(24, 3) * 100, 0.01,
             100.0, 100.0, (0.9999,) * 3, 0.87, views=[(0, 60), (90, 75), (0, -60), (180, -75), (180, -30)],
             samples=65536))
    add(Case("slab_thick", "slab 20 cm (20 voxels, tau 30 each), omega 0.9999, g 0.87", slab(24, 20) * 300, 0.01,
             3000.0, 300.0, (0.9999,) * 3, 0.87, views=[(0, 60), (180, 60), (90, 80)], samples=65536))
    add(Case("box_sharp", "box 12 x 10 x 6 cm, sharp edges, tau 8, omega 0.995, g 0.7", box((0.12, 0.10, 0.06), 0.01) * 200,
             0.01, 800.0, 200.0, (0.995,) * 3, 0.7, views=[(0, 30), (120, 30), (220, 30), (300, 45)], samples=16384))
    occluders = [plate(0.10, 0.20, 0.05, 0.25, 0.22, (0.2, 0.2, 0.2)), plate(-1.0, 2.0, -1.0, 2.0, 0.005, (0.6, 0.3, 0.2))]
    add(Case("bumpy_plate", "bumpy layer 6 cm +- 3 cm, plate shadow, reddish ground, tau 15, omega 0.999, g 0.7",
             bumpy(30, 6, 3) * 300, 0.01, 1500.0, 300.0, (0.999,) * 3, 0.7, views=[(0, 60), (180, 50)],
             pixels=10, occluders=occluders, samples=16384))
    add(Case("spray_lumps", "24 lumps r 0.5-1.5 cm on 1.5 cm voxels (partly filled), omega 0.9999, g 0.85",
             spray(0.015) * 100, 0.015, 400.0, 100.0, (0.9999,) * 3, 0.85, views=ROUND, samples=16384))
    add(Case("spray_dense", "the lumps on 1 cm voxels, denser (tau up to 20 per voxel), omega 0.999, g 0.85",
             spray(0.01) * 300, 0.01, 2000.0, 300.0, (0.999,) * 3, 0.85, views=ROUND, samples=65536))
    return out


def write_density(path, density, voxel):
    g = pyopenvdb.FloatGrid()
    g.name = "density"
    g.transform = pyopenvdb.createLinearTransform(voxelSize=voxel)
    g.copyFromArray(density.astype(np.float32), tolerance=0.0)
    pyopenvdb.write(path, grids=[g])


def trilinear(density, p):
    """Density at index-space points p (N, 3), zero outside."""
    f = np.floor(p).astype(int)
    t = p - f
    out = np.zeros(len(p))
    n = np.array(density.shape)
    for corner in range(8):
        o = np.array([(corner >> a) & 1 for a in range(3)])
        c = f + o
        ok = np.all((c >= 0) & (c < n), axis=1)
        w = np.prod(np.where(o, t, 1.0 - t), axis=1)
        out[ok] += w[ok] * density[c[ok, 0], c[ok, 1], c[ok, 2]]
    return out


def plate_hit(case, origin, direction):
    """Distance to the first occluder (the cases' occluders are horizontal rectangles), inf if none."""
    nearest = math.inf
    for vertices, _, _ in case.occluders:
        if abs(direction[2]) < 1e-12:
            continue
        t = (vertices[0, 2] - origin[2]) / direction[2]
        x, y = origin[:2] + t * direction[:2]
        lo, hi = vertices.min(0), vertices.max(0)
        if t > 0.0 and lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1]:
            nearest = min(nearest, t)
    return nearest


def views(case):
    """Orthographic camera rays around the object: origins, directions, per-ray optical depth."""
    n = np.array(case.density.shape)
    centre = (n - 1) / 2 * case.voxel
    nonzero = np.argwhere(case.density > 0)
    radius = 0.55 * np.max((nonzero.max(0) - nonzero.min(0) + 1) * case.voxel)
    origins, directions = [], []
    for azimuth, elevation in case.views:
        a, e = math.radians(azimuth), math.radians(elevation)
        back = np.array([math.cos(a) * math.cos(e), math.sin(a) * math.cos(e), math.sin(e)])  # towards the camera
        up = np.array([0.0, 0.0, 1.0]) if abs(back[2]) < 0.99 else np.array([1.0, 0.0, 0.0])
        right = np.cross(up, back)
        right /= np.linalg.norm(right)
        up = np.cross(back, right)
        s = ((np.arange(case.pixels) + 0.5) / case.pixels * 2.0 - 1.0) * radius
        for v in s:
            for u in s:
                origins.append(centre + 3.0 * radius * back + u * right + v * up)
                directions.append(-back)
    origins, directions = np.array(origins), np.array(directions)
    steps = np.linspace(0.0, 6.0 * radius, int(6.0 * radius / (0.25 * case.voxel)))
    tau = np.array([trilinear(case.density, (o + steps[steps < plate_hit(case, o, d), None] * d) / case.voxel).sum()
                    for o, d in zip(origins, directions)]) * (steps[1] - steps[0]) * case.sigma_t / case.rho
    return origins, directions, tau


def depth_one_points(case, origins, directions, seen):
    """Where each seen ray reaches optical depth 1 of snow (NaN for the others)."""
    steps = np.linspace(0.0, 2.0, 4000)
    hit = np.full((len(origins), 3), np.nan)
    for i in np.nonzero(seen)[0]:
        p = origins[i] + steps[:, None] * directions[i]
        tau = np.cumsum(trilinear(case.density, p / case.voxel)) * (steps[1] - steps[0]) * case.sigma_t / case.rho
        hit[i] = p[min(np.searchsorted(tau, 1.0), len(p) - 1)]  # a grazing ray views() found at depth 1 on coarser steps
    return hit


def cached_monte_carlo(file, case, path, origins, directions, samples, seed):
    """The core's Monte Carlo of `case` along the rays (mean, error, seconds), kept in `file` (None: not kept) and read
    back from it when there (seconds NaN from files kept before they held it); written whole (temp file + rename)."""
    if file and os.path.exists(file):
        data = np.load(file)
        return data["mean"], data["error"], float(data["seconds"]) if "seconds" in data else float("nan")
    start = time.perf_counter()
    mean, error = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                                sky=case.skies(), occluders=case.occluders, samples=samples, seed=seed)
    seconds = time.perf_counter() - start
    if file:
        os.makedirs(os.path.dirname(file), exist_ok=True)
        np.savez(file + ".tmp.npz", mean=mean, error=error, seconds=seconds)
        os.replace(file + ".tmp.npz", file)
    return mean, error, seconds


def reference(case, path, origins, directions, cache):
    file = os.path.join(cache, f"{case.name}_{case.key()}.npz") if cache else None
    return cached_monte_carlo(file, case, path, origins, directions, case.samples, seed=11)


class Baked:
    """A case baked into `path`: its views' rays (origins, directions), their optical depth tau, the reference's mean,
    error and seconds, the bake's stats and seconds."""


def baked_case(case, path, cache, quality="FINAL", seed=0, sky_samples=0):
    out = Baked()
    write_density(path, case.density, case.voxel)
    out.origins, out.directions, out.tau = views(case)
    out.mean, out.error, out.reference_seconds = reference(case, path, out.origins, out.directions, cache)
    start = time.perf_counter()
    out.stats = firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                              quality=quality, seed=seed, sky_samples=sky_samples)
    out.bake_seconds = time.perf_counter() - start
    return out


def scored(case, render, mean, seen):
    """The suite's figures of one render of a case against its reference `mean` over the seen blocks."""
    per = case.pixels ** 2
    view_bias = [render[v * per:(v + 1) * per][seen[v * per:(v + 1) * per]].sum() /
                 max(mean[v * per:(v + 1) * per][seen[v * per:(v + 1) * per]].sum(), 1e-30) - 1.0 for v in range(len(case.views))]
    m, b = mean[seen], render[seen]
    relative = b / np.maximum(m, 1e-30) - 1.0
    return {"mean": float(np.abs(relative).mean()), "worst": float(np.abs(relative).max()),
            "worst_signed": float(relative.flat[np.abs(relative).argmax()]), "bias": float(b.sum() / m.sum() - 1.0),
            "relative": relative, "view_bias": view_bias}


def mixed_render(case, path, origins, directions, samples, seed, baked):
    """(render, its standard error) of the baked file at `path` as Cycles renders the material that scatters the bake's
    thin traced snow itself (firn_scatter; render_scattering_where_thin, rule B, unlimited bounces); where the renderer
    scatters nowhere, `baked` (the baked form's render) itself, without noise."""
    if not len(firncore.scatter_voxels(path, case.optics, occluders=case.occluders)):
        return baked, np.zeros_like(baked)
    return firncore.render_scattering_where_thin(path, case.optics, origins, directions, suns=case.suns(),
                                                 sky=case.skies(), occluders=case.occluders, samples=samples,
                                                 seed=seed, traced_only=True)


def run_case(case, folder, cache, quality="FINAL", seed=0, sky_samples=0, mixed=0):
    """One bake's row; with `mixed` paths per block also its "mixed" row: the bake rendered as Cycles renders the
    baked material that scatters the bake's thin traced snow itself (firn_scatter; render_scattering_where_thin,
    rule B, unlimited bounces, the render seeded by the bake's seed), the form users get (docs/benchmarks.md,
    thin-cycles)."""
    path = os.path.join(folder, case.name + ".vdb")
    run = baked_case(case, path, cache, quality, seed, sky_samples)
    origins, directions, tau, mean, error = run.origins, run.directions, run.tau, run.mean, run.error
    reference_seconds, stats, bake_seconds = run.reference_seconds, run.stats, run.bake_seconds
    baked = firncore.render_baked(path, case.optics, origins, directions, occluders=case.occluders)
    seen = tau >= 1.0
    out = {
        "case": case.name, "what": case.what, "blocks": int(seen.sum()) * 3,
        "noise": float(np.median(error[seen] / np.maximum(mean[seen], 1e-30))),
        "bake_s": bake_seconds, "reference_s": reference_seconds, "traced": stats["traced_voxels"], "traced_paths": stats["traced_paths"],
        "light_traced": stats["light_traced_voxels"], "photons": stats["photons"],
        "trace_cpu_s": stats["cpu_seconds"]["trace"], "views": case.views, **scored(case, baked, mean, seen),
    }
    if mixed:
        start = time.perf_counter()
        render, render_error = mixed_render(case, path, origins, directions, mixed, 1000 + seed, baked)
        out["mixed"] = {**out, "case": case.name + " (mixed)", **scored(case, render, mean, seen),
                        "render_noise": float(np.median(render_error[seen] / np.maximum(render[seen], 1e-30))),
                        "render_s": time.perf_counter() - start}
    return out


def over_seeds(runs):
    """One row from the runs of several bake seeds: mean error, bias, view biases and times averaged, the worst
    block the worst of any; "spread": the per-block spread of the baked render across seeds (relative standard
    deviation), the bake's own noise."""
    r = dict(runs[0])
    for key in ("mean", "bias", "bake_s", "trace_cpu_s", "render_s", "render_noise"):
        if key in r:
            r[key] = float(np.mean([x[key] for x in runs]))
    r["view_bias"] = list(np.mean([x["view_bias"] for x in runs], axis=0))
    worst = max(runs, key=lambda x: x["worst"])
    r["worst"], r["worst_signed"] = worst["worst"], worst["worst_signed"]
    ratios = np.array([x["relative"] for x in runs]) + 1.0
    r["spread"] = float(np.mean(ratios.std(0, ddof=1) / np.maximum(ratios.mean(0), 1e-30))) if len(runs) > 1 else 0.0
    return r


def worst_view(r):
    v = int(np.argmax(np.abs(r["view_bias"])))
    azimuth, elevation = r["views"][v]
    return f"{100 * r['view_bias'][v]:+.0f} % ({azimuth}°, {elevation}°)"


def table(rows, markdown):
    seeds = any(r.get("spread") for r in rows)  # several bake seeds: their spread too
    rendered = "render_noise" in rows[0]  # mixed rows: the render's own noise and seconds too
    head = ("case", "blocks", "mean", "worst", "bias", "worst view bias", "ref noise") + \
        (("render noise",) if rendered else ()) + (("bake spread",) if seeds else ()) + ("bake s", "ref s") + \
        (("render s",) if rendered else ())
    if markdown:
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for r in rows:
            noise = f"{100 * r['render_noise']:.1f} % | " if rendered else ""
            spread = f"{100 * r['spread']:.1f} % | " if seeds else ""
            render = f" {r['render_s']:.1f} |" if rendered else ""
            lines.append(f"| {r['case']} | {r['blocks']} | {100 * r['mean']:.1f} % | {100 * r['worst_signed']:+.0f} % | "
                         f"{100 * r['bias']:+.1f} % | {worst_view(r)} | {100 * r['noise']:.1f} % | {noise}{spread}"
                         f"{r['bake_s']:.2f} | {r['reference_s']:.0f} |{render}")
        return "\n".join(lines)
    lines = [f"{'case':<14} {'blocks':>6} {'mean':>7} {'worst':>7} {'bias':>7} {'worst view bias':>22} {'noise':>6} " +
             (f"{'render':>6} " if rendered else "") + f"{'bake s':>7} {'ref s':>7}" + (f" {'render s':>8}" if rendered else "")]
    for r in rows:
        lines.append(f"{r['case']:<14} {r['blocks']:>6} {100 * r['mean']:>6.1f}% {100 * r['worst_signed']:>+6.0f}% "
                     f"{100 * r['bias']:>+6.1f}% {worst_view(r):>22} {100 * r['noise']:>5.1f}% " +
                     (f"{100 * r['render_noise']:>5.1f}% " if rendered else "") +
                     f"{r['bake_s']:>7.2f} {r['reference_s']:>7.1f}" + (f" {r['render_s']:>8.1f}" if rendered else ""))
    return "\n".join(lines)


def summary(rows, what):
    """The suite's one line for a table: the sum of its means (the suite's figure of merit), the largest, the worst
    block."""
    return (f"{what}: sum of the {len(rows)} means {sum(100 * r['mean'] for r in rows):.2f}, largest mean "
            f"{100 * max(r['mean'] for r in rows):.1f} %, worst block {100 * max(r['worst'] for r in rows):.0f} %")


def traced_how(row):
    """How the traced voxels were traced: paths gathered per voxel, or photons from the lights (light tracing)."""
    if row["light_traced"]:
        return f"{row['light_traced']} light traced, {row['photons']:,} photons"
    return f"{row['traced_paths']} paths each"


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="", help="comma-separated case names (default: all)")
    parser.add_argument("--cache", default=CACHE,
                        help="folder caching the Monte Carlo reference per case")
    parser.add_argument("--fresh", action="store_true", help="recompute the reference")
    parser.add_argument("--markdown", action="store_true")
    parser.add_argument("--quality", default="FINAL")
    parser.add_argument("--maps", action="store_true", help="print each view's per-block relative errors")
    parser.add_argument("--sky-samples", type=int, default=0,
                        help="sky rays per surface voxel (0: the quality's; at most 64): whether the sky's share is converged")
    parser.add_argument("--seeds", type=int, default=1,
                        help="bake each case with seeds 0..N-1 and report the means (traced voxels' noise: one seed's "
                             "mean error moves by up to 2 points)")
    parser.add_argument("--mixed", type=int, default=MIXED_PATHS,
                        help="paths per block of the mixed render, as Cycles renders firn_scatter (the headline)")
    parser.add_argument("--baked-only", action="store_true", help="the baked form alone (no mixed render)")
    args = parser.parse_args()
    if args.baked_only:
        args.mixed = 0
    chosen = [c for c in cases() if not args.cases or c.name in args.cases.split(",")]
    cache = None if args.fresh else args.cache
    if cache:
        os.makedirs(cache, exist_ok=True)
    print(f"firncore {firncore.__version__}, {firncore.hardware_threads()} threads, {args.quality} quality" +
          (f", {args.sky_samples} sky rays" if args.sky_samples else ""), flush=True)
    rows, mixed_rows = [], []
    with tempfile.TemporaryDirectory() as folder:
        for case in chosen:
            runs = [run_case(case, folder, cache, args.quality, seed, args.sky_samples, args.mixed)
                    for seed in range(args.seeds)]
            rows.append(over_seeds(runs))
            if args.mixed:
                mixed_rows.append(over_seeds([x["mixed"] for x in runs]))
                m = mixed_rows[-1]
                print(f"  {m['case']}: mean {100 * m['mean']:.1f} %, worst {100 * m['worst_signed']:+.0f} %, bias "
                      f"{100 * m['bias']:+.1f} %" + (f", spread {100 * m['spread']:.1f} %" if args.seeds > 1 else "") +
                      "; per view: " + ", ".join(f"{v} {100 * b:+.0f} %" for v, b in zip(case.views, m["view_bias"])),
                      flush=True)
            r = rows[-1]
            seeds = ", ".join(f"{100 * x['mean']:.1f}" for x in runs)
            print(f"  {r['case']}: {r['what']}: mean {100 * r['mean']:.1f} %, worst {100 * r['worst_signed']:+.0f} %, "
                  f"bias {100 * r['bias']:+.1f} %; " +
                  (f"over {args.seeds} seeds (means {seeds} %, spread {100 * r['spread']:.1f} %); "
                   if args.seeds > 1 else "") +
                  f"{r['traced']} traced voxels ({traced_how(r)}), trace {r['trace_cpu_s']:.2f} processor s; per view: " +
                  ", ".join(f"{v} {100 * b:+.0f} %" for v, b in zip(case.views, r["view_bias"])), flush=True)
            if args.maps:
                _, _, tau = views(case)
                print_view_maps(case, r["relative"][:, 1], tau >= 1.0)
    print()
    if mixed_rows:
        print(f"mixed form, the headline ({args.mixed} paths per block; render s: its wall seconds):")
        print(table(mixed_rows, args.markdown))
        print()
        print("baked form (Scatter Thin Snow off):")
    print(table(rows, args.markdown))
    print()
    if mixed_rows:
        print(summary(mixed_rows, f"mixed ({args.mixed} paths per block)"))
    print(summary(rows, "baked"))


if __name__ == "__main__":
    main()
