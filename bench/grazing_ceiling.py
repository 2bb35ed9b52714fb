"""How much of the suite's error is the grazing exit, and what a limb-darkening term could take (docs/benchmarks.md,
limb-dark).

Each case's blocks (FINAL, --seed, the suite's cached references) get the exit cosine mu where their ray reaches
optical depth 1 (the view's direction towards the camera dotted with the snow's outward normal, minus the trilinear
density's gradient: bench/ramp_source_profile.py --by-exit). Two oracles on the baked render, the bench only:

- ceiling(mu_c): the blocks of mu < mu_c given the reference's value (their error 0): what any change that moves
  grazing exits alone can take at most;
- darker(mu_c): only those of them brighter than the reference, per channel: what any darkening of grazing exits
  can take at most;
- limb(a): the render with the broad lobe's light (the render without the peaked grids, backlit_probe's
  write_without_peaks) times D(mu) = 1 - a (1 - mu / MU_FULL) below MU_FULL, 1 above, on thick snow only (the
  case's sigma_t h >= 3 and under half its voxels traced by the bake: a half-space's limb darkening does not exist in
  thin snow, and a bake would write the term on its smooth surface patches only); --peaks also the peaked lobe's
  light. With --lit L the amplitude times the lit share min(mu0 / L, 1) (mu0 the sun's cosine to the normal at
  depth 1, 0 where snow or an occluder shades it: no darkening on shadowed or sky-lit snow). On a flat top the
  render of S(w) D(w . n) through the ramp is D(mu) times the baked one exactly (one normal along the ray); on a
  ball the normal at depth 1 stands for the few voxels the light comes from. a = 0.3 is the shape of slab_thick's
  truth over its bake at az 90 (edge-fall: 0.73, 0.76, 0.88, 0.97 at mu 0.05, 0.10, 0.17, 0.34, the baked exit
  flat there).
- --grid: limb(a) as a grid would render it (the design: a Vec3 grid a x lit share x the outward unit normal on the
  surface's band, carried two voxels into the air (--carry); the renderer reads it trilinearly, its length the
  amplitude, its direction the normal), D averaged along each ray over the light it shows; --grid-scale 2 that grid
  on voxels twice the density's; --l1-axis the amplitude alone from it and the broad lobe's own axis l1 as the
  normal (no grid for the direction); --forward the darkening times 1 - max(w . p1 / |p1|, 0), w towards the
  viewer: none along the peaked lobe's axis (the sun's forward travel out of a lit surface, where its limb is too
  dark already); --derived D from the transport in place of a and MU_FULL (limb-derive: derived_table, the
  half-space's exit over the broad lobe fitted to it by exit cosine, azimuth off the sun's travel and mu0, for the
  case's green omega and g; the grid's length the lit share alone), --darken-only that D at most 1; --own that D
  from the bake's own lobes (limb-own: own_table, the half-space's Monte Carlo over the peaked and broad lobes the
  bake writes for it, tools/sun_lobe_table's `limb` mode); --curve prints it beside the fitted form. The edge gates
  (limb-grid): --unsharp no term on the sharp edges' voxels (the core's onSharpEdge, sharp_voxels) nor the air beside
  them alone; --sharp-least a sharp voxel's lit share its least lit air face's; --face-cap the derived D at most 1
  where the exit cosine is over MU_FULL (no limb there).

Per case: the mean |error| (the suite's, all channels), each oracle's, the worst block and its mu; the sum of the
means. --blocks lists each case's five worst blocks (view, row, col, mu, error).

    PYTHONPATH=build/python:bench python3 bench/grazing_ceiling.py [--cases a,b] [--amplitudes 0.15,0.3,0.45] \
        [--lit 0.3] [--grid [--forward] [--carry 2] [--grid-scale 2] [--l1-axis] [--unsharp | --sharp-least] \
        [--derived [--own] [--darken-only | --face-cap]]] \
        [--curve] [--blocks] [--dump DIR]
"""

import argparse
import functools
import math
import os
import subprocess
import tempfile
from collections import namedtuple

import numpy as np
import pyopenvdb

import bake_suite as S
from backlit_probe import sun_towards, write_without_peaks
from bake_halfspace import henyey_greenstein
from lobe_form import axis as lobe_axis, lobe, nelder_mead, sphere_grid

MU_FULL = 0.35  # above this exit cosine the truth's exit over the bake's is flat on slab_thick (edge-fall)
DERIVED_MU = np.array([0.01, 0.03, 0.05, 0.08, 0.12, 0.17, 0.23, 0.3, 0.4, 0.5, 0.65, 0.8, 1.0])  # the table's nodes
DERIVED_AZIMUTH = np.radians(np.arange(0.0, 181.0, 15.0))  # the exit's tangent part off the sun's travel
DERIVED_MU0 = np.array([0.05, 0.1, 0.2, 0.3, 0.45, 0.6, 0.8, 1.0])
OWN_PHOTONS = 4000000  # per sun: a grazing bin (1.4e-4 of the projected solid angle) gets ~300 of them (+-6 %)
THICK = 3.0  # sigma_t h from which a case's surfaces are a half-space's (the limb darkening is a thick medium's)


def exit_cosines(case, origins, directions, seen):
    """mu and mu0 per block (NaN where not seen; mu0 NaN without a sun): -direction and the direction towards the
    sun dotted with the outward normal at the ray's optical depth 1 point (mu0 0 where snow or an occluder shades
    the point 1.5 voxels out along the normal from the sun)."""
    mu, mu0 = np.full(len(origins), np.nan), np.full(len(origins), np.nan)
    hits = S.depth_one_points(case, origins[seen], directions[seen], np.ones(seen.sum(), bool)) / case.voxel
    gradient = np.stack([S.trilinear(case.density, hits + e) - S.trilinear(case.density, hits - e)
                         for e in 0.25 * np.eye(3)], 1)
    normal = -gradient / np.maximum(np.linalg.norm(gradient, axis=1), 1e-30)[:, None]
    mu[seen] = np.einsum("ij,ij->i", -directions[seen], normal)
    if case.sun > 0.0:
        mu0[seen] = normal @ sun_towards() * sun_seen(case, hits * case.voxel + 1.5 * case.voxel * normal)
    return mu, mu0


def sun_seen(case, points):
    """1 where the sun reaches points (m) through under optical depth 1 of snow and past the occluders, else 0."""
    steps = np.linspace(0.0, 1.0, 2000)
    out = np.zeros(len(points))
    for i, p in enumerate(points):
        path = p + steps[:, None] * sun_towards()
        tau = S.trilinear(case.density, path / case.voxel).sum() * (steps[1] - steps[0]) * case.sigma_t / case.rho
        out[i] = float(tau < 1.0 and S.plate_hit(case, p, sun_towards()) == np.inf)
    return out


def darkening(mu, amplitude):
    """D(mu): 1 - a (1 - mu / MU_FULL) below MU_FULL (mu under 0, a ray through the ramp only, as at 0), 1 above."""
    return 1.0 - amplitude * np.clip(1.0 - np.nan_to_num(mu, nan=1.0) / MU_FULL, 0.0, 1.0)


def h_function(omega, mu, nodes=48):
    """Chandrasekhar's H function of isotropic scattering at albedo omega, at the cosines mu (Radiative Transfer
    1950, ch. V): 1 / H(mu) = sqrt(1 - omega) + omega / 2 int_0^1 x H(x) / (mu + x) dx, iterated on Gauss-Legendre
    nodes (H(1) = 2.9078 at omega 1)."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    x, w = 0.5 * (x + 1.0), 0.5 * w
    root = math.sqrt(max(1.0 - omega, 0.0))
    h = np.ones(nodes)
    for _ in range(2000):  # damped: undamped, it does not settle as omega nears 1
        h = 0.5 * h + 0.5 / (root + 0.5 * omega * (w * x * h / (x[:, None] + x[None, :])).sum(1))
    return 1.0 / (root + 0.5 * omega * (w * x * h / (np.asarray(mu)[..., None] + x)).sum(-1))


def half_space_exit(omega, g, mu0, views):
    """pi L / (mu0 E) of a half-space towards unit views (normal +z, the sun travelling towards +x): the exact single
    scattering, pi omega HG(g, cos) / (mu + mu0), plus the multiple scattering of the similar isotropic half-space
    (omega' = omega (1 - g) / (1 - omega g)), omega' (H(mu) H(mu0) - 1) / 4 (mu + mu0) (snow-optics.md)."""
    mu = views[:, 2]
    single = math.pi * omega * henyey_greenstein(g, views @ [math.sqrt(1.0 - mu0 * mu0), 0.0, -mu0]) / (mu + mu0)
    similar = omega * (1.0 - g) / (1.0 - omega * g)
    return single + similar * (h_function(similar, mu) * h_function(similar, mu0) - 1.0) / (4.0 * (mu + mu0))


def broad_lobe_fit(truth, views, dw):
    """The broad lobe fitted to a half-space's exit as the bake fits its lobes (docs/bake.md Method 5): one HG lobe
    about an axis in the sun's plane, the exitance kept, least squares in relative error weighted by mu dw. The
    peaked lobe is left out: fitted beside it (bench/limb_family_fit.py's family) at mu0 0.45-0.5 it turns into a
    second broad lobe (k 0.03-0.2 straight up) and the rest's quotient is noise; the forward gate stands for it."""
    weight = views[:, 2] * dw

    def shape(p, v):
        return lobe(0.95 * math.tanh(p[0]), v @ lobe_axis(p[1], 0.0))

    def scale(p):
        return (truth * weight).sum() / max((shape(p, views) * weight).sum(), 1e-30)

    def cost(p):
        return (weight * (scale(p) * shape(p, views) / truth - 1.0) ** 2).sum()

    best = nelder_mead(cost, [0.4, 1.0], iterations=400)
    return lambda v: scale(best) * shape(best, v)


Table = namedtuple("Table", "mu0 mu azimuth values")  # D on mu0 x mu x azimuth (radians off the sun's travel)


@functools.lru_cache(maxsize=None)
def derived_table(omega, g):
    """The limb darkening the broad lobe misses, D = the half-space's exit / the broad lobe fitted to it, on
    DERIVED_MU0 x DERIVED_MU x DERIVED_AZIMUTH: no free constant, the transport's angular law against the
    contract's form (D S1(w) renders the half-space's exit exactly)."""
    views, dw = sphere_grid(12, 36, upper_only=True)
    a, m = np.meshgrid(DERIVED_AZIMUTH, DERIVED_MU, indexing="ij")
    s = np.sqrt(1.0 - m * m)
    probes = np.stack([s * np.cos(a), s * np.sin(a), m], -1).reshape(-1, 3)
    table = np.zeros((len(DERIVED_MU0), len(DERIVED_MU), len(DERIVED_AZIMUTH)))
    for i, mu0 in enumerate(DERIVED_MU0):
        broad = broad_lobe_fit(half_space_exit(omega, g, mu0, views), views, dw)(probes)
        d = half_space_exit(omega, g, mu0, probes) / np.maximum(broad, 1e-30)
        table[i] = d.reshape(a.shape).T
    return Table(DERIVED_MU0, DERIVED_MU, DERIVED_AZIMUTH, table)


@functools.lru_cache(maxsize=None)
def own_table(omega, g, photons=OWN_PHOTONS):
    """The limb darkening the bake's own lobes miss (limb-own): D = (R / A - P) / B per outgoing bin (20 exit cosines x
    18 azimuths off the sun's travel) at DERIVED_MU0, R the half-space's reflection function from the core's Monte
    Carlo (sun_lobe_table.inc's), P and B the peaked lobe and the rest's broad lobe that sunPeak's split writes for a
    flat surface, as the grids render them: D B + P is the half-space's exit, no constant chosen. From
    tools/sun_lobe_table's `limb` mode, run once per snow and kept in the temp folder (limb-rule's folder: limb-own's
    tables rendered P with the anisotropy k / mean, not k, wrong wherever the split has a peak, mu0 < 0.6); at least 0
    (forwards at grazing the peaked lobe alone may outshine the half-space; the forward gate keeps the term off there)."""
    path = os.path.join(tempfile.gettempdir(), "limb-rule", f"limb_{g}_{omega}_{photons}.txt")  # limb-own's peak fixed
    if not os.path.exists(path):
        os.makedirs(os.path.dirname(path), exist_ok=True)
        tool = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "tools", "sun_lobe_table")
        with open(path + ".part", "w") as out:
            subprocess.run([tool, str(photons), "limb", str(g), str(omega)], stdout=out, check=True)
        os.replace(path + ".part", path)
    rows = np.loadtxt(path)
    mu0, mu, azimuth = (np.unique(rows[:, k]) for k in range(3))
    values = rows[:, 3].reshape(len(mu0), len(mu), len(azimuth))
    return Table(mu0, mu, np.radians(azimuth), np.maximum(values, 0.0))


def table_value(table, mu0, mu, azimuth):
    """A D table read multilinearly at (mu0, mu, azimuth) (each clamped to its nodes)."""
    corners = []
    for nodes, x in ((table.mu0, mu0), (table.mu, mu), (table.azimuth, azimuth)):
        x = np.clip(x, nodes[0], nodes[-1])
        i = np.clip(np.searchsorted(nodes, x) - 1, 0, len(nodes) - 2)
        corners.append((i, (x - nodes[i]) / (nodes[i + 1] - nodes[i])))
    (i, s), (j, t), (k, u) = corners
    out = 0.0
    for di, dj, dk in np.ndindex(2, 2, 2):
        w = (s if di else 1.0 - s) * (t if dj else 1.0 - t) * (u if dk else 1.0 - u)
        out = out + w * table.values[i + di, j + dj, k + dk]
    return out


def derived_darkening(table, normal, towards_viewer, darken_only):
    """D from the derived table at unit normals and view directions, the suite's sun (1 where the sun is below the
    normal's horizon: the table's lowest mu0 stands for it, and the lit share gates it to 0 there)."""
    mu = np.einsum("ij,ij->i", towards_viewer, normal)
    travel = -sun_towards()
    mu0 = normal @ sun_towards()
    out_t = towards_viewer - mu[:, None] * normal
    sun_t = travel[None, :] - (normal @ travel)[:, None] * normal
    cos = np.einsum("ij,ij->i", out_t, sun_t) / np.maximum(np.linalg.norm(out_t, axis=1) *
                                                          np.linalg.norm(sun_t, axis=1), 1e-30)
    d = table_value(table, mu0, mu, np.arccos(np.clip(cos, -1.0, 1.0)))
    if darken_only == "face":  # no brightening where the exit is no limb's (mu over MU_FULL)
        return np.where(mu >= MU_FULL, np.minimum(d, 1.0), d)
    return np.minimum(d, 1.0) if darken_only else d


def sharp_voxels(density):
    """The snow voxels on a sharp edge or corner, as the core's onSharpEdge (snow_topology.cpp) finds them: two air
    faces at right angles, each going on flat past the edge for 2 voxels (or 3 and 1)."""
    snow = density > 0.0
    padded = np.pad(snow, 4)
    steps = [np.eye(3, dtype=int)[f // 2] * (1 if f & 1 else -1) for f in range(6)]

    def shifted(step):  # the padded mask at voxel + step, on the unpadded grid
        return padded[tuple(slice(4 + d, 4 + d + n) for d, n in zip(step, snow.shape))]

    def air(f, offset=(0, 0, 0)):  # snow at voxel + offset with face f in air
        return shifted(offset) & ~shifted(np.add(offset, steps[f]))

    def flat_past(f, g, voxels):  # face f goes on flat for `voxels` voxels inwards from face g
        out = np.ones(snow.shape, bool)
        for k in range(1, voxels + 1):
            out &= air(f, -k * steps[g])
        return out

    sharp = np.zeros(snow.shape, bool)
    for f in range(6):
        for g in range(f + 1, 6):
            if f // 2 != g // 2:
                both = air(f) & air(g)
                sharp |= both & ((flat_past(f, g, 2) & flat_past(g, f, 2)) | (flat_past(f, g, 3) & flat_past(g, f, 1)) |
                                 (flat_past(f, g, 1) & flat_past(g, f, 3)))
    return sharp


def unsharpened(grid, density):
    """The grid without the sharp edges' voxels (no smooth surface there, no normal: vdb-contract's firn_limb) and the
    air voxels whose only snow neighbours across a face are sharp."""
    sharp = sharp_voxels(density)
    smooth = (density > 0.0) & ~sharp
    padded = np.pad(smooth, 1)
    beside_smooth = np.zeros(density.shape, bool)
    for a in range(3):
        for d in (0, 2):
            beside_smooth |= padded[tuple(slice(d if b == a else 1, (d if b == a else 1) + n)
                                          for b, n in enumerate(density.shape))]
    keep = smooth | ((density == 0.0) & beside_smooth)
    return np.where(keep[..., None], grid, 0.0)


def sharp_least_lit(grid, case, lit):
    """The grid with each sharp voxel's lit share that of its least lit air face (min over its air faces of
    min(mu0_f / lit, 1), mu0_f the sun's cosine to the face's normal, 0 where the sun does not reach the point 1.5
    voxels out of it): an edge between a lit and a shadowed face gets no term, one between two lit faces keeps it."""
    out = grid.copy()
    snow = case.density > 0.0
    padded = np.pad(snow, 1)
    for q in np.argwhere(sharp_voxels(case.density)):
        least = 1.0
        for f in range(6):
            n = np.eye(3)[f // 2] * (1 if f & 1 else -1)
            if padded[tuple(q + 1 + n.astype(int))]:
                continue  # snow across this face
            mu0 = n @ sun_towards() if case.sun > 0.0 else 0.0
            if mu0 > 0.0:
                mu0 *= sun_seen(case, ((q + 1.5 * n) * case.voxel)[None, :])[0]
            least = min(least, float(np.clip(mu0 / lit, 0.0, 1.0)))
        length = np.linalg.norm(grid[tuple(q)])
        if length > 0.0:
            out[tuple(q)] = grid[tuple(q)] / length * least
    return out


def limb_grid(case, amplitude, lit, carry=2):
    """The term as a grid would hold it, on the density's voxels: amplitude x lit share x the outward unit normal
    (minus the density's central-difference gradient) where that gradient is not 0 (the surface's band, a voxel
    either side of its ramp), carried `carry` voxels on into the air (each empty voxel the mean of its face neighbours
    holding one), 0 elsewhere; the lit share min(mu0 / lit, 1) with mu0 as exit_cosines'."""
    gradient = np.stack(np.gradient(case.density.astype(float)), -1)
    length = np.linalg.norm(gradient, axis=-1)
    band = length > 1e-6 * case.rho
    normal = -gradient[band] / length[band][:, None]
    centres = np.argwhere(band) * case.voxel
    share = np.ones(len(normal))
    if lit > 0.0:
        mu0 = normal @ sun_towards() * sun_seen(case, centres + 1.5 * case.voxel * normal) if case.sun > 0.0 else 0.0
        share = np.clip(mu0 / lit, 0.0, 1.0)
    grid = np.zeros(case.density.shape + (3,))
    grid[band] = (amplitude * share)[:, None] * normal
    for _ in range(carry):  # carried on into the air, as the source grids' values are (vdb-contract.md: two voxels)
        empty = ~np.any(grid != 0.0, axis=-1) & (case.density == 0.0)
        total, count = np.zeros(grid.shape), np.zeros(case.density.shape)
        for a in range(3):
            for shift in (-1, 1):
                neighbour = np.roll(grid, shift, axis=a)
                total += neighbour
                count += np.any(neighbour != 0.0, axis=-1)
        grid[empty] = total[empty] / np.maximum(count[empty], 1)[:, None]
    return grid


def coarsened(grid, scale):
    """The grid on voxels `scale` times larger (voxel J where density voxel scale J is): each the mean of the fine
    voxels within its trilinear hat, weighted by the hat."""
    if scale == 1:
        return grid
    hat = 1.0 - np.abs(np.arange(-scale + 1, scale)) / scale
    out = np.zeros(grid.shape)
    for axis in range(3):  # separable: the hat along each axis in turn
        padded = np.pad(grid if axis == 0 else out, [(scale - 1, scale - 1) if a == axis else (0, 0) for a in range(4)])
        out = sum(w * np.take(padded, np.arange(k, k + grid.shape[axis]), axis=axis) for k, w in enumerate(hat))
        out /= hat.sum()
    return out[::scale, ::scale, ::scale]


def broad_axis(path, shape):
    """The broad lobe's l1 (green) on the density's voxels, from the baked file (the source grids' voxels are the
    density's in the suite: source_scale 1)."""
    out = np.zeros(shape + (3,))
    for a, name in enumerate(("firn_source_x", "firn_source_y", "firn_source_z")):
        values = np.zeros(shape + (3,), np.float32)
        pyopenvdb.read(path, name).copyToArray(values, ijk=(0, 0, 0))
        out[..., a] = values[..., 1]
    return out


def peak_axis(path, shape):
    """The peaked lobe's p1 (one vector for all channels) on the density's voxels, from the baked file."""
    out = np.zeros(shape + (3,), np.float32)
    pyopenvdb.read(path, "firn_source_peak_l1").copyToArray(out, ijk=(0, 0, 0))
    return out.astype(float)


def grid_darkening(case, grid, origins, directions, seen, scale=1, axis=None, forward=None, derived=None,
                   darken_only=False, step=0.05):
    """Each seen ray's D averaged over the light it shows: sum of sigma_t e^-tau ds D(-direction, the trilinear
    grid) over sum of sigma_t e^-tau ds, to optical depth 12 (the source along the first optical depths taken as
    constant: a surface's exit radiance, as the contract holds it there)."""
    out = np.ones(len(origins))
    steps = np.arange(0.0, 2.0, step * case.voxel)
    for i in np.nonzero(seen)[0]:
        p = (origins[i] + steps[:, None] * directions[i]) / case.voxel
        sigma = S.trilinear(case.density, p) * case.sigma_t / case.rho
        tau = np.cumsum(sigma) * step * case.voxel
        k = (sigma > 0.0) & (tau < 12.0)
        v = np.stack([S.trilinear(grid[..., a], p[k] / scale) for a in range(3)], 1)
        a = np.linalg.norm(v, axis=1)
        if axis is not None:  # the amplitude alone from the grid, the direction the broad lobe's axis
            v = np.stack([S.trilinear(axis[..., c], p[k]) for c in range(3)], 1)
        mu = -(v @ directions[i]) / np.maximum(np.linalg.norm(v, axis=1), 1e-30)
        if derived is None:
            d = 1.0 - a * np.clip(1.0 - mu / MU_FULL, 0.0, 1.0)
        else:  # the grid's length the lit share alone, D from the transport's table
            normal = v / np.maximum(np.linalg.norm(v, axis=1), 1e-30)[:, None]
            d = 1.0 - a * (1.0 - derived_darkening(derived, normal, -directions[i][None, :], darken_only))
        if forward is not None:  # none along the peaked lobe's travel: there the lit limb is too dark already
            f = np.stack([S.trilinear(forward[..., c], p[k]) for c in range(3)], 1)
            along = (f @ -directions[i]) / np.maximum(np.linalg.norm(f, axis=1), 1e-30)
            d = 1.0 - (1.0 - d) * (1.0 - np.maximum(along, 0.0))
        w = sigma[k] * np.exp(-tau[k])
        out[i] = (w * d).sum() / max(w.sum(), 1e-30)
    return out


def print_curve(case, own, photons=OWN_PHOTONS, mu0=0.5, mus=(0.01, 0.03, 0.05, 0.1, 0.17, 0.25, 0.35, 0.5, 0.8),
                azimuths=(0, 30, 90, 150, 180)):
    """The derived D at mu0 (the suite's sun on a flat top) beside the fitted form, by exit cosine and azimuth."""
    table = own_table(case.omega[1], case.g, photons) if own else derived_table(case.omega[1], case.g)
    print(f"  {case.name} (omega {case.omega[1]}, g {case.g}), mu0 {mu0}: D by mu " + " ".join(f"{m:5.2f}" for m in mus))
    print("    fitted (a 0.3)     " + " ".join(f"{x:5.2f}" for x in darkening(np.array(mus), 0.3)))
    for a in azimuths:
        d = table_value(table, np.full(len(mus), mu0), np.array(mus), np.full(len(mus), math.radians(a)))
        print(f"    derived az {a:3d}     " + " ".join(f"{x:5.2f}" for x in d))


def mean_error(render, mean, seen):
    return float(np.abs(render[seen] / np.maximum(mean[seen], 1e-30) - 1.0).mean())


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--ceilings", default="0.15,0.3")
    parser.add_argument("--amplitudes", default="0.15,0.3,0.45")
    parser.add_argument("--peaks", action="store_true", help="darken the peaked lobe's light too")
    parser.add_argument("--lit", type=float, default=0.0,
                        help="the amplitude times min(mu0 / LIT, 1), 0 where the sun is below the surface's horizon")
    parser.add_argument("--grid", action="store_true",
                        help="limb(a) as a grid renders it: limb_grid's vectors read trilinearly along the ray")
    parser.add_argument("--l1-axis", action="store_true",
                        help="--grid's amplitude only, about the broad lobe's axis l1 in place of the normal")
    parser.add_argument("--forward", action="store_true",
                        help="--grid's darkening times 1 - max(w . p1 / |p1|, 0): none along the peaked lobe's axis")
    parser.add_argument("--derived", action="store_true",
                        help="--grid's D from the transport (derived_table: the half-space's exit over the broad lobe "
                             "fitted to it, by mu, azimuth off the sun's travel, mu0, the case's green omega and g) "
                             "in place of 1 - a clamp(1 - mu / MU_FULL); --amplitudes is then 1")
    parser.add_argument("--darken-only", action="store_true", help="--derived's D at most 1")
    parser.add_argument("--face-cap", action="store_true",
                        help="--derived's D at most 1 where the exit cosine is over MU_FULL (no limb there)")
    parser.add_argument("--own", action="store_true",
                        help="--derived's D over the bake's own lobes (own_table: tools/sun_lobe_table limb)")
    parser.add_argument("--own-photons", type=int, default=OWN_PHOTONS, help="--own's Monte Carlo photons per sun")
    parser.add_argument("--curve", action="store_true",
                        help="print each case's derived D beside the fitted 1 - 0.3 clamp(1 - mu / 0.35) at mu0 0.5")
    parser.add_argument("--carry", type=int, default=2, help="--grid's vectors carried this many voxels into the air")
    parser.add_argument("--unsharp", action="store_true",
                        help="--grid without the sharp edges' voxels (nor the air beside them alone)")
    parser.add_argument("--sharp-least", action="store_true",
                        help="--grid's sharp voxels lit by their least lit air face (sharp_least_lit)")
    parser.add_argument("--grid-scale", type=int, default=1, help="--grid's voxels this many density voxels wide")
    parser.add_argument("--blocks", action="store_true", help="each case's five worst blocks")
    parser.add_argument("--dump", help="a folder: per case NAME.npz of the blocks' reference, baked and limb-darkened "
                                       "radiances (and the broad lobe's alone), mu, mu0, seen and the depth-one "
                                       "points (limb-rule)")
    parser.add_argument("--cache", default=S.CACHE)
    args = parser.parse_args()
    ceilings = [float(x) for x in args.ceilings.split(",")]
    amplitudes = [1.0] if args.derived else [float(x) for x in args.amplitudes.split(",")]
    chosen = [c for c in S.cases() if not args.cases or c.name in args.cases.split(",")]
    if args.curve:
        for case in chosen:
            print_curve(case, args.own, args.own_photons)
        return
    print("case               mean  " + "".join(f" ceil<{c:4.2f}" for c in ceilings) +
          f" darker<{ceilings[-1]:4.2f}" + "".join(f"  limb {a:4.2f}" for a in amplitudes) +
          "   worst (mu)        blocks mu<0.3 (|err|)")
    totals = np.zeros(2 + len(ceilings) + len(amplitudes))
    with tempfile.TemporaryDirectory() as folder:
        for case in chosen:
            path = os.path.join(folder, case.name + ".vdb")
            run = S.baked_case(case, path, args.cache, "FINAL", args.seed)
            baked = S.firncore.render_baked(path, case.optics, run.origins, run.directions, occluders=case.occluders)
            write_without_peaks(path, path + ".broad.vdb")
            broad = S.firncore.render_baked(path + ".broad.vdb", case.optics, run.origins, run.directions,
                                            occluders=case.occluders)
            seen = run.tau >= 1.0
            mu, mu0 = exit_cosines(case, run.origins, run.directions, seen)
            lit = np.clip(np.nan_to_num(mu0) / args.lit, 0.0, 1.0) if args.lit > 0.0 else 1.0
            relative = baked / np.maximum(run.mean, 1e-30) - 1.0
            row = [mean_error(baked, run.mean, seen)]
            for c in ceilings:
                fixed = np.where((mu < c)[:, None], run.mean, baked)
                row.append(mean_error(fixed, run.mean, seen))
            bright = (mu < ceilings[-1])[:, None] & (baked > run.mean)
            row.append(mean_error(np.where(bright, run.mean, baked), run.mean, seen))
            thick = case.sigma_t * case.voxel >= THICK and run.stats["traced_voxels"] < 0.5 * (case.density > 0).sum()
            darkened = []
            for a in amplitudes:
                if not thick:
                    d = 1.0
                elif args.grid:
                    axis = broad_axis(path, case.density.shape) if args.l1_axis else None
                    forward = peak_axis(path, case.density.shape) if args.forward else None
                    grid = limb_grid(case, a, args.lit, args.carry)
                    if args.unsharp:
                        grid = unsharpened(grid, case.density)
                    if args.sharp_least:
                        grid = sharp_least_lit(grid, case, args.lit)
                    grid = coarsened(grid, args.grid_scale)
                    table = None
                    if args.derived:
                        table = (own_table(case.omega[1], case.g, args.own_photons) if args.own else
                                 derived_table(case.omega[1], case.g))
                    d = grid_darkening(case, grid, run.origins, run.directions, seen, args.grid_scale, axis,
                                       forward, table, "face" if args.face_cap else args.darken_only)[:, None]
                else:
                    d = (1.0 - lit * (1.0 - darkening(mu, a)))[:, None]
                darkened.append(baked * d if args.peaks else (baked - broad) + broad * d)
                row.append(mean_error(darkened[-1], run.mean, seen))
            totals += 100 * np.array(row)
            if args.dump:
                os.makedirs(args.dump, exist_ok=True)
                np.savez(os.path.join(args.dump, case.name + ".npz"), reference=run.mean, baked=baked, broad=broad,
                         darkened=np.array(darkened), mu=mu, mu0=mu0, seen=seen,
                         hit=S.depth_one_points(case, run.origins, run.directions, seen))
            k = np.unravel_index(np.argmax(np.where(seen[:, None], np.abs(relative), -1.0)), relative.shape)
            low = seen & (mu < 0.3)
            print(f"  {case.name:<16}" + "".join(f" {100 * x:8.2f}" for x in row) +
                  f"   {100 * relative[k]:+5.0f} % ({mu[k[0]]:+.2f})   {low.sum():3d} / {seen.sum():3d} "
                  f"({100 * np.abs(relative[low]).mean() if low.any() else 0.0:4.1f} %)", flush=True)
            if args.blocks:
                per = case.pixels ** 2
                worst = np.argsort(-np.where(seen, np.abs(relative).max(1), -1.0))[:5]
                for i in worst:
                    v, j = divmod(int(i), per)
                    c = np.abs(relative[i]).argmax()
                    print(f"      view {tuple(case.views[v])} row {j // case.pixels} col {j % case.pixels}: "
                          f"mu {mu[i]:+.2f}, error {100 * relative[i, c]:+5.1f} %, limb: " +
                          " ".join(f"{100 * (x[i, c] / run.mean[i, c] - 1):+5.1f}" for x in darkened) + " %")
    print("  sum of the means" + "".join(f" {x:8.2f}" for x in totals))


if __name__ == "__main__":
    main()
