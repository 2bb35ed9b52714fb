"""Whether spray_dense's shadowed thick blocks seen against the sun are too bright in their voxels' own baked source
or in the trilinear blend between them and their neighbours (docs/benchmarks.md, spray-shade).

Per seed: bakes the case (FINAL), takes the shadowed thick blocks (cores and thick rims, spray_thick_probe's regions)
of view (180, 0), and along their camera rays, from optical depth 0.3 to 3 (where spray-thick's segments put the
excess), the voxels whose trilinear hat the rays' weight sigma_t T ds falls on. For each such voxel centre x and
the direction w towards the camera, its baked source S_b(w) (the contract's two lobes from the six grids' values at
x) against a Monte Carlo estimate of the same source,
    S(x, w) = omega [ int HG(t . w) (L(x, t) + L_sky T(x, -t)) dt + E_sun T_sun(x) HG(sun's travel . w) ],
t drawn from HG about w, L(x, t) the light travelling t at x (firncore.monte_carlo_radiance looking along -t: the
snow's scattered light), the sky and the sun's uncollided light added with the trilinear density's transmittance.
Printed two ways: (a) along the rays, at the points where their optical depth reaches 0.3, 0.6, 1, 1.5, 2, 3, the
blend the renderer reads and the hat's corners of each voxel class alone (their trilinear weights renormalised)
against Monte Carlo at the same points, and the peaked lobe's share; (b) at the centres of the voxels holding
--share of the rays' weight (voxel_weights), per voxel class (spray_rims_probe.voxel_classes), the baked / Monte
Carlo of their weighted sums (saved to /tmp/spray_shade_seed<seed>.npz for bench/spray_shade_scaled.py).

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/spray_shade_probe.py [--seeds 0,1] [--directions 256]
        [--samples 8] [--share 0.9] [--no-rays | --no-voxels]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from spray_rims_probe import CLASSES, cut_points, voxel_classes
from spray_thick_probe import case_regions

GRIDS = ("firn_source", "firn_source_x", "firn_source_y", "firn_source_z", "firn_source_peak", "firn_source_peak_l1")


def lobes(values, w, part="both"):
    """The contract's source S(w) (docs/vdb-contract.md) from the six grids' values (dict name -> (N, 3)); w (3,);
    part: "both", "broad" or "peak" (that lobe alone)."""
    l0, l1 = values["firn_source"], np.stack([values[g] for g in GRIDS[1:4]], axis=2)  # l1[n, channel, axis]
    out = np.zeros_like(l0)
    norm = np.linalg.norm(l1, axis=2)
    k = np.where((l0 > 0) & (norm > 0), np.minimum(norm / np.maximum(3 * l0, 1e-30), 0.95), 0.0)
    cos = np.where(norm > 0, (l1 @ w) / np.maximum(norm, 1e-30), 0.0)
    if part != "peak":
        out += l0 * (1 - k ** 2) / (1 + k ** 2 - 2 * k * cos) ** 1.5
    if part == "broad":
        return out
    p0, p1 = values["firn_source_peak"], values["firn_source_peak_l1"]
    mean = p0.mean(1)
    pn = np.linalg.norm(p1, axis=1)
    kp = np.where((mean > 0) & (pn > 0), np.minimum(pn / np.maximum(3 * mean, 1e-30), 0.95), 0.0)
    cp = np.where(pn > 0, (p1 @ w) / np.maximum(pn, 1e-30), 0.0)
    out += p0 * ((1 - kp ** 2) / (1 + kp ** 2 - 2 * kp * cp) ** 1.5)[:, None]
    return out


def hg_sample(axis, g, n, rng):
    """n unit directions t with t . axis distributed as Henyey-Greenstein g."""
    u = rng.random(n)
    s = (1 - g * g) / (1 - g + 2 * g * u)
    cos = (1 + g * g - s * s) / (2 * g)
    phi = 2 * np.pi * rng.random(n)
    a = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = np.cross(axis, a)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    sin = np.sqrt(np.maximum(1 - cos * cos, 0))
    return cos[:, None] * axis + sin[:, None] * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2)


def transmittance(case, points, direction):
    """The snow's uncollided transmittance from points (N, 3, m) along `direction` (3,) out of the grid."""
    per_density = case.sigma_t / case.rho
    ds = 0.0625 * case.voxel
    steps = np.arange(0.5, 2.0 / ds) * ds
    out = np.empty(len(points))
    for i, x in enumerate(points):
        p = (x + steps[:, None] * direction) / case.voxel
        out[i] = np.exp(-bake_suite.trilinear(case.density, p).sum() * per_density * ds)
    return out


def voxel_weights(case, origins, directions, rays, lo=0.3, hi=3.0):
    """Per density voxel, the rays' weight sigma_t T ds on its trilinear hat where the ray's optical depth lies in
    [lo, hi], summed over `rays` (each ray's weight normalised by its own sum over all its depths)."""
    n = np.array(case.density.shape)
    per_density = case.sigma_t / case.rho
    ds = 0.0625 * case.voxel
    steps = np.arange(0.0, 2.0, ds)
    weight = np.zeros(case.density.shape)
    for i in rays:
        p = (origins[i] + steps[:, None] * directions[i]) / case.voxel
        sigma = bake_suite.trilinear(case.density, p) * per_density
        tau = np.concatenate([[0.0], np.cumsum(sigma * ds)])[:-1]
        w = sigma * np.exp(-tau) * ds
        w = np.where((tau >= lo) & (tau < hi), w, 0.0) / max(w.sum(), 1e-30)
        f = np.floor(p).astype(int)
        t = p - f
        for corner in range(8):
            o = np.array([(corner >> a) & 1 for a in range(3)])
            c = f + o
            ok = np.all((c >= 0) & (c < n), axis=1) & (w > 0)
            hat = np.prod(np.where(o, t, 1.0 - t), axis=1)
            np.add.at(weight, (c[ok, 0], c[ok, 1], c[ok, 2]), (hat * w)[ok])
    return weight


def monte_carlo_source(case, path, x, w, directions, samples, seed):
    """S(x, w) (3,) and its standard error: see the module's docstring."""
    rng = np.random.default_rng(seed)
    t = hg_sample(w, case.g, directions, rng)
    L, e = firncore.monte_carlo_radiance(path, case.optics, np.repeat(x[None], directions, 0), -t,
                                         suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                                         samples=samples, seed=seed)
    sky = case.sky * np.array([transmittance(case, x[None], -d)[0] for d in t])
    per = L + sky[:, None]
    sun = case.suns()[0]
    towards_sun = np.array(sun.direction)
    cos = float(np.dot(-towards_sun, w))
    hg = (1 - case.g ** 2) / (4 * np.pi * (1 + case.g ** 2 - 2 * case.g * cos) ** 1.5)
    direct = np.array(sun.irradiance) * transmittance(case, x[None], towards_sun)[0] * hg
    omega = np.array(case.omega)
    return omega * (per.mean(0) + direct), omega * per.std(0) / np.sqrt(directions), omega * direct


def grid_values(path, points):
    """The six grids' trilinear values at world points (N, 3), as the renderer reads them."""
    return {g: firncore.sample_color_grid(path, g, points.astype(np.float32)).astype(np.float64) for g in GRIDS}


def corner_values(path, case, points, keep):
    """The six grids blended over only the hat corners of each point whose voxel class is in `keep` (their
    trilinear weights renormalised), and the share of the hat's weight those corners hold."""
    classes = voxel_classes(case)
    p = points / case.voxel
    f = np.floor(p).astype(int)
    t = p - f
    out = {g: np.zeros((len(points), 3)) for g in GRIDS}
    total = np.zeros(len(points))
    for corner in range(8):
        o = np.array([(corner >> a) & 1 for a in range(3)])
        c = f + o
        hat = np.prod(np.where(o, t, 1.0 - t), axis=1)
        ok = np.isin(classes[c[:, 0], c[:, 1], c[:, 2]], keep) & (hat > 0)
        if not ok.any():
            continue
        values = grid_values(path, (c[ok] * case.voxel).astype(np.float64))
        for g in GRIDS:
            out[g][ok] += hat[ok, None] * values[g]
        total[ok] += hat[ok]
    for g in GRIDS:
        out[g] /= np.maximum(total, 1e-30)[:, None]
    return out, total


def along_rays(case, path, origins, directions, rays, w, args, seed):
    """At the points of the rays where their optical depth reaches each cut: the blend the renderer reads, the
    thick voxels' own values alone (their corners of the hat), the air's alone, against Monte Carlo."""
    cuts = [0.3, 0.6, 1.0, 1.5, 2.0, 3.0]
    seen = np.zeros(len(origins), bool)
    seen[rays] = True
    points = cut_points(case, origins, directions, seen, cuts)[:, rays]  # per cut, per ray of `rays`
    print(f"\nseed {seed}: along the {len(rays)} rays, at optical depth: the blend the render reads, the hat's "
          "thick corners alone (sigma_t h > 2), its air corners alone, its thin snow corners alone, each / Monte "
          "Carlo (green, sums over the rays); the hat's weight on thick, air (facing a thick face), other air, thin")
    rows = []
    for k, cut in enumerate(cuts):
        ok = np.all(np.isfinite(points[k]), axis=1)
        x = points[k, ok]
        mc = np.array([monte_carlo_source(case, path, p, w, args.directions, args.samples, 7919 * seed + 97 * k + n)
                       for n, p in enumerate(x)])
        truth, err, direct = mc[:, 0, 1], mc[:, 1, 1], mc[:, 2, 1]
        values = grid_values(path, x)
        blend = lobes(values, w)[:, 1]
        peak = lobes(values, w, "peak")[:, 1]
        parts, peaks, shares = {}, {}, {}
        for name, keep in (("thick", [3, 4]), ("air f", [0]), ("air o", [1]), ("thin", [2])):
            v, share = corner_values(path, case, x, keep)
            parts[name] = np.where(share > 0, lobes(v, w)[:, 1], np.nan)
            peaks[name] = np.where(share > 0, lobes(v, w, "peak")[:, 1], np.nan)
            shares[name] = share.mean()
        def ratio(v):
            m = np.isfinite(v)
            return f"{v[m].sum() / truth[m].sum():5.2f} ({m.sum():2d})" if m.any() else "   -      "
        print(f"  tau {cut:3.1f}: blend {ratio(blend)}  thick {ratio(parts['thick'])}  air f {ratio(parts['air f'])}"
              f"  air o {ratio(parts['air o'])}  thin {ratio(parts['thin'])}   hat: " +
              " ".join(f"{n} {s:.2f}" for n, s in shares.items()) +
              f"   (MC noise {100 * np.sqrt((err ** 2).sum()) / truth.sum():.1f} %)", flush=True)
        print(f"           the sun's single scattering: {direct.sum() / truth.sum():.2f} of the truth; peaked lobe / it "
              f"{peak.sum() / max(direct.sum(), 1e-30):5.2f} (the peaked lobe / the truth: blend {peak.sum() / truth.sum():.2f}, " +
              ", ".join(f"{n} {np.nansum(peaks[n]) / truth[np.isfinite(peaks[n])].sum():.2f}" for n in peaks if np.isfinite(peaks[n]).any()) +
              f"); broad lobe / the rest {(blend - peak).sum() / max((truth - direct).sum(), 1e-30):5.2f}",
              flush=True)
        rows.append((x, truth, err, blend, parts))
    return rows


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", default="0,1")
    parser.add_argument("--directions", type=int, default=256)
    parser.add_argument("--samples", type=int, default=8, help="paths per direction")
    parser.add_argument("--share", type=float, default=0.9, help="the voxels holding this share of the weight")
    parser.add_argument("--no-rays", action="store_true", help="only the voxel centres")
    parser.add_argument("--no-voxels", action="store_true", help="only the points along the rays")
    parser.add_argument("--cache", default=bake_suite.CACHE)
    args = parser.parse_args()
    case, origins, directions, tau, seen, lit, core, thin, views = case_regions()
    against = seen & ~lit & (core | ~thin) & (views == 2)
    rays = np.nonzero(against)[0]
    w = -directions[rays[0]]  # towards the camera (an orthographic view: one direction)
    classes = voxel_classes(case)
    weight = voxel_weights(case, origins, directions, rays)
    order = np.argsort(-weight.ravel())
    take = order[:np.searchsorted(np.cumsum(weight.ravel()[order]), args.share * weight.sum()) + 1]
    voxels = np.array(np.unravel_index(take, case.density.shape)).T
    centres = voxels * case.voxel
    print(f"{case.name}, view (180, 0): {len(rays)} shadowed thick blocks; the {len(voxels)} voxels holding "
          f"{args.share:.0%} of their rays' weight from optical depth 0.3 to 3; Monte Carlo {args.directions} "
          f"directions x {args.samples} paths per voxel")
    for seed in (int(s) for s in args.seeds.split(",")):
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, case.name + ".vdb")
            bake_suite.baked_case(case, path, args.cache, "FINAL", seed)
            if not args.no_rays:
                along_rays(case, path, origins, directions, rays, w, args, seed)
            if args.no_voxels:
                continue
            baked = lobes(grid_values(path, centres), w)
            mc, err = np.zeros_like(baked), np.zeros_like(baked)
            for k, x in enumerate(centres):
                mc[k], err[k], _ = monte_carlo_source(case, path, x, w, args.directions, args.samples, 100 * seed + k)
            wk = weight.ravel()[take]
            print(f"\nseed {seed}: per class (its share of the taken weight): the weighted sums' baked / Monte Carlo,"
                  " green; the per-voxel ratio's weighted median; voxels")
            k_of = classes.ravel()[take]
            for k, name in enumerate(CLASSES):
                m = k_of == k
                if not m.any():
                    continue
                r = baked[m, 1] / np.maximum(mc[m, 1], 1e-30)
                o = np.argsort(r)
                med = r[o][np.searchsorted(np.cumsum(wk[m][o]), 0.5 * wk[m].sum())]
                print(f"  {name:<6} {wk[m].sum() / wk.sum():5.2f}  {(wk[m] * baked[m, 1]).sum() / (wk[m] * mc[m, 1]).sum():5.2f}"
                      f"  {med:5.2f}  {m.sum():3d}   (MC noise {100 * np.sqrt((wk[m] ** 2 * err[m, 1] ** 2).sum()) / (wk[m] * mc[m, 1]).sum():.1f} %)")
            print(f"  all    1.00  {(wk * baked[:, 1]).sum() / (wk * mc[:, 1]).sum():5.2f}")
            rel = baked[:, 1] / np.maximum(mc[:, 1], 1e-30)
            print("  the heaviest voxels: voxel, class, weight share, sigma_t h, baked, MC (+- se), ratio")
            depth = case.density * case.sigma_t / case.rho * case.voxel
            for j in np.argsort(-wk)[:12]:
                v = tuple(voxels[j])
                print(f"    {str(v):<14} {CLASSES[k_of[j]]:<6} {wk[j] / wk.sum():.3f}  {depth[v]:5.1f}  "
                      f"{baked[j, 1]:.4f}  {mc[j, 1]:.4f} +- {err[j, 1]:.4f}  {rel[j]:.2f}")
            np.savez(f"/tmp/spray_shade_seed{seed}.npz", voxels=voxels, weight=wk, baked=baked, mc=mc, err=err,
                     classes=k_of)


if __name__ == "__main__":
    main()
