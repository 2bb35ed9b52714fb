"""Whether spray_dense's thick lump voxels (sigma_t h 2-10) are too bright for a camera against the sun in their
estimate or in what that one value stands for (docs/benchmarks.md, spray-core 2026-12-02).

A traced voxel of forward scattering snow thicker than 2 optical depths is gathered where cameras see it
(gatheredWhereSeen, visible_points.h): its points are drawn with density hat(x) sigma_t(x) sum_j exp(-tau_j(x)), tau_j
the optical depth from x to the snow's bounds along the j-th of sourceDirections (the cube's 26 and 13 about the
sun's beam), and its lobes are fitted to their moments: one value for every camera. A camera looking from w sees the
voxel's hat only through hat(x) sigma_t(x) exp(-tau_w(x)). Per voxel, towards the camera w of view (180, 0):
    baked   the contract's lobes from the six grids at the voxel's centre (what the renderer reads there),
    all     Monte Carlo S(x, w) averaged over points drawn as the bake draws them (its target),
    seen    Monte Carlo S(x, w) averaged over points drawn as the camera from w sees the hat (what it should show),
    centre  Monte Carlo S(x, w) at the centre (spray-shade's comparison),
S(x, w) as spray_shade_probe.monte_carlo_source (the scattered light by firncore.monte_carlo_radiance, the sky's and
the sun's uncollided light by the trilinear density's transmittance). baked / all is the estimate's error (its
paths' noise and the moments' fit), all / seen what one value for every camera costs this one.

--classes picks other voxel classes (the air across thick faces, whose value stands for the ramp before the face:
seen is its target too); --baked-only prints only each seed's baked values (S(x, w) does not depend on the bake's
seed). --check-rays N instead integrates exp(-tau) S dtau along the rays at N points each (the Monte Carlo S, the
baked grids' blend as the renderer reads it, the voxels' own lobes blended linearly) against the reference and the
baked render (--directions 0: the blends only).

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/spray_seen_probe.py [--seeds 0] [--classes 3]
        [--points 48] [--directions 32] [--samples 4] [--share 0.6] [--baked-only] [--check-rays N]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from spray_rims_probe import CLASSES, voxel_classes
from spray_shade_probe import grid_values, hg_sample, lobes, voxel_weights
from spray_thick_probe import case_regions, lumps

STEP = 0.25  # voxels, the columns' marching step


def source_directions(case):
    """sourceDirections(beam travel) (monte_carlo.cpp): the cube's 26, the beam's axis and rings of 6 at 10 and 25
    degrees about it."""
    out = [np.array(o, float) - 1 for o in np.ndindex(3, 3, 3) if o != (1, 1, 1)]
    out = [o / np.linalg.norm(o) for o in out]
    axis = -np.array(case.suns()[0].direction)
    a = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = np.cross(axis, a)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    out.append(axis)
    for degrees in (10.0, 25.0):
        c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
        out += [c * axis + s * (np.cos(np.pi * i / 3) * e1 + np.sin(np.pi * i / 3) * e2) for i in range(6)]
    return np.array(out)


def sigma_t(case, p):
    """1/m at index-space points p (N, 3)."""
    return bake_suite.trilinear(case.density, p) * case.sigma_t / case.rho


def depth_out(case, p, d, cap=10.0):
    """Optical depth from index-space points p (N, 3) along unit d (3,) or (N, 3) to the grid's bounds, up to cap."""
    n = int(np.ceil(np.linalg.norm(case.density.shape) / STEP))
    tau = np.zeros(len(p))
    for i in range(n):
        tau += sigma_t(case, p + (i + 0.5) * STEP * d) * STEP * case.voxel
    return np.minimum(tau, cap)


def transmittance(case, points, d):
    """exp(-tau) from world points (N, 3) along d to the grid's bounds."""
    return np.exp(-depth_out(case, points / case.voxel, d, cap=50.0))


def drawn_points(case, voxel, w, candidates, points, rng):
    """Index-space points of `voxel`'s hat drawn as the bake draws them (all) and as a camera from w sees them
    (seen): uniform candidates over the hat's box, resampled by their weights."""
    x = voxel + rng.uniform(-1, 1, (candidates, 3))
    base = np.prod(1 - np.abs(x - voxel), axis=1) * sigma_t(case, x)
    seen_from = np.array([np.exp(-depth_out(case, x, d)) for d in source_directions(case)])
    out = {}
    for name, weight in (("all", base * seen_from.sum(0)), ("seen", base * np.exp(-depth_out(case, x, w)))):
        p = weight / weight.sum()
        out[name] = x[rng.choice(len(x), points, p=p)]
    return out


def monte_carlo_sources(case, path, x, w, directions, samples, seed):
    """S(x, w) per world point x (N, 3) and its standard error (green), as spray_shade_probe.monte_carlo_source."""
    rng = np.random.default_rng(seed)
    t = np.concatenate([hg_sample(w, case.g, directions, rng) for _ in x])
    at = np.repeat(x, directions, 0)
    L, _ = firncore.monte_carlo_radiance(path, case.optics, at, -t, suns=case.suns(), sky=case.skies(),
                                         occluders=case.occluders, samples=samples, seed=seed)
    sky = case.sky * np.exp(-depth_out(case, at / case.voxel, -t, cap=50.0))
    per = (L[:, 1] + sky).reshape(len(x), directions)
    towards_sun = np.array(case.suns()[0].direction)
    cos = float(np.dot(-towards_sun, w))
    hg = (1 - case.g ** 2) / (4 * np.pi * (1 + case.g ** 2 - 2 * case.g * cos) ** 1.5)
    direct = case.suns()[0].irradiance[1] * transmittance(case, x, towards_sun) * hg
    omega = case.omega[1]
    return omega * (per.mean(1) + direct), omega * per.std(1) / np.sqrt(directions)


def corners(case, path, x, w):
    """Per world point x (N, 3) and each of its 8 hat corners: the corner voxel (8, N, 3), its hat weight (8, N) and
    its own lobes towards w (8, N)."""
    p = x / case.voxel
    f = np.floor(p).astype(int)
    t = p - f
    offsets = [np.array([(corner >> a) & 1 for a in range(3)]) for corner in range(8)]
    hats = np.array([np.prod(np.where(o, t, 1.0 - t), axis=1) for o in offsets])
    own = np.array([lobes(grid_values(path, ((f + o) * case.voxel).astype(np.float64)), w)[:, 1] for o in offsets])
    return np.array([f + o for o in offsets]), hats, own


def corner_blend(case, path, x, w):
    """Per world point x (N, 3): the grids' blend as the renderer reads it (the six grids' trilinear values, then
    the lobes towards w: k from the blended moments) and the blend of the corners' own sources towards w (each
    voxel's lobes evaluated, then weighted by the trilinear hat: linear in the voxels' values)."""
    _, hats, own = corners(case, path, x, w)
    return lobes(grid_values(path, x), w)[:, 1], (hats * own).sum(0)


def check_rays(case, path, cache, origins, directions, rays, w, per_ray, args):
    """Along the rays, int exp(-tau) S dtau by quadrature (tau drawn from the ray's truncated exponential) of the
    Monte Carlo S(x, w), of the baked blend as the renderer reads it, and of the corners' sources blended linearly,
    against the suite's reference and the baked render: whether S is the light the reference sees, and whether
    the excess is in the voxels' values or in the blend of their lobes' moments."""
    mean, error, _ = bake_suite.reference(case, path, origins, directions, cache)
    render = firncore.render_baked(path, case.optics, origins[rays], directions[rays], occluders=case.occluders)[:, 1]
    ds = 0.0625 * case.voxel
    rng = np.random.default_rng(5)
    sums = np.zeros((4, len(rays)))
    classes, by_class = voxel_classes(case), np.zeros((len(CLASSES), 2))
    for n, i in enumerate(rays):
        s = np.arange(0.0, 6.0 * case.voxel * max(case.density.shape), ds)
        p = origins[i] + s[:, None] * directions[i]
        tau = np.concatenate([[0.0], np.cumsum(sigma_t(case, p / case.voxel) * ds)])[:-1]
        total = tau[-1]
        u = (np.arange(per_ray) + rng.random(per_ray)) / per_ray
        drawn = -np.log(1 - u * (1 - np.exp(-total)))
        x = p[np.searchsorted(tau, drawn).clip(0, len(p) - 1)]
        read, linear = corner_blend(case, path, x, w)
        S = monte_carlo_sources(case, path, x, w, args.directions, args.samples, int(i))[0] if args.directions else read
        sums[:, n] = (1 - np.exp(-total)) * np.array([S.mean(), read.mean(), linear.mean(), 0.0])
        if args.directions:  # per voxel class, its values against S at these rays' own points, hat-weighted
            voxel, hats, own = corners(case, path, x, w)
            k = classes[tuple(voxel.reshape(-1, 3).clip(0, np.array(case.density.shape) - 1).T)].reshape(hats.shape)
            q = (1 - np.exp(-total)) / per_ray * hats
            for c in range(len(CLASSES)):
                by_class[c] += [(q * own)[k == c].sum(), (q * S[None, :])[k == c].sum()]
    m = mean[rays, 1]
    print(f"the {len(rays)} rays, {per_ray} points each (reference noise {np.sqrt((error[rays, 1] ** 2).sum()) / m.sum():.3f}): "
          f"quadrature of Monte Carlo S / reference {sums[0].sum() / m.sum():.3f}; baked render / reference "
          f"{render.sum() / m.sum():.3f}; quadrature of the baked blend as read / reference {sums[1].sum() / m.sum():.3f}, "
          f"of the corners' sources blended linearly {sums[2].sum() / m.sum():.3f}")
    if args.directions:
        print("  per class, its values / S at these rays' points (hat-weighted; the class's share of the linear blend): " +
              "  ".join(f"{CLASSES[c]} {a / b:.2f} ({a / by_class[:, 0].sum():.2f})" for c, (a, b) in enumerate(by_class) if b > 0))
    print("  per ray, MC S, read, linear / reference: " + "  ".join(
        f"{a / r:.2f} {b / r:.2f} {c / r:.2f}" for a, b, c, r in zip(sums[0], sums[1], sums[2], m)), flush=True)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", default="0")
    parser.add_argument("--points", type=int, default=48, help="points per voxel and distribution")
    parser.add_argument("--candidates", type=int, default=2048)
    parser.add_argument("--directions", type=int, default=32)
    parser.add_argument("--samples", type=int, default=4, help="paths per direction")
    parser.add_argument("--share", type=float, default=0.6)
    parser.add_argument("--classes", default="3", help="voxel classes (spray_rims_probe.CLASSES' indices: 0 air "
                        "across a thick face, 1 other air, 2 snow of sigma_t h < 2, 3 2-10, 4 over 10)")
    parser.add_argument("--baked-only", action="store_true",
                        help="per seed only the voxels' baked source towards w and its peaked lobe's share")
    parser.add_argument("--quality", default="FINAL")
    parser.add_argument("--lit-cores", type=int, default=-1, help="the lit cores of this view (0: (0, 0), 3: "
                        "(0, 60)) instead of the shadowed thick blocks of (180, 0)")
    parser.add_argument("--check-rays", type=int, default=0, help="only S's quadrature along the rays, this many "
                        "points per ray, against the reference")
    parser.add_argument("--cache", default=bake_suite.CACHE)
    args = parser.parse_args()
    case, origins, directions, tau, seen, lit, core, thin, views = case_regions()
    rays = np.nonzero(seen & lit & core & (views == args.lit_cores) if args.lit_cores >= 0 else
                      seen & ~lit & (core | ~thin) & (views == 2))[0]
    w = -directions[rays[0]]
    classes = voxel_classes(case)
    weight = voxel_weights(case, origins, directions, rays)
    order = np.argsort(-weight.ravel())
    take = order[:np.searchsorted(np.cumsum(weight.ravel()[order]), args.share * weight.sum()) + 1]
    voxels = np.array(np.unravel_index(take, case.density.shape)).T
    kept = np.isin(classes[tuple(voxels.T)], [int(c) for c in args.classes.split(",")])
    voxels, wk = voxels[kept], weight.ravel()[take][kept]
    label = lumps(case.density > 0)
    depth = case.density * case.sigma_t / case.rho * case.voxel
    sun_side = np.array(case.suns()[0].direction)
    print(f"{case.name}, view {case.views[views[rays[0]]]}, {len(rays)} rays, w {np.round(w, 3)}: the {len(voxels)} voxels of classes {args.classes} among those "
          f"holding {args.share:.0%} of the rays' weight (tau 0.3-3); Monte Carlo {args.points} "
          f"points x {args.directions} directions x {args.samples} paths per distribution")
    for seed in (int(s) for s in args.seeds.split(",")):
        rng = np.random.default_rng(seed + 11)
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, case.name + ".vdb")
            run = bake_suite.baked_case(case, path, args.cache, args.quality, seed)
            if args.check_rays:
                check_rays(case, path, args.cache, origins, directions, rays, w, args.check_rays, args)
                continue
            values = grid_values(path, voxels * case.voxel)
            baked = lobes(values, w)[:, 1]
            if args.baked_only:
                peak = lobes(values, w, "peak")[:, 1]
                print(f"seed {seed} ({args.quality}, {run.stats['traced_paths']} paths): baked " + " ".join(f"{b:.4f}" for b in baked) + "\n        peak share " +
                      " ".join(f"{p / max(b, 1e-30):.2f}" for p, b in zip(peak, baked)), flush=True)
                continue
            rows = []
            for k, v in enumerate(voxels):
                pts = drawn_points(case, v.astype(float), w, args.candidates, args.points, rng)
                got = {}
                for n, name in enumerate(("all", "seen")):
                    s, e = monte_carlo_sources(case, path, pts[name] * case.voxel, w, args.directions, args.samples,
                                               1000 * seed + 10 * k + n)
                    got[name] = (s.mean(), np.sqrt((s.var() + (e ** 2).mean()) / len(s)))
                    # where the points lie: their mean offset from the centre along the sun's direction, voxels
                    got[name + " sun"] = float(((pts[name] - v) @ sun_side).mean())
                c, ce = monte_carlo_sources(case, path, (v * case.voxel)[None].astype(float), w, 8 * args.directions,
                                            args.samples, 1000 * seed + 10 * k + 7)
                rows.append((baked[k], got["all"][0], got["all"][1], got["seen"][0], got["seen"][1], c[0], ce[0],
                             got["all sun"], got["seen sun"]))
                lump = label[tuple(v)]
                print(f"  {str(tuple(v)):<13} {CLASSES[classes[tuple(v)]]:<6} lump {lump:2d} ({(label == lump).sum():3d} voxels) sigma_t h "
                      f"{depth[tuple(v)]:4.1f} weight {wk[k] / wk.sum():.3f}: baked {baked[k]:.4f}  all "
                      f"{got['all'][0]:.4f}+-{got['all'][1]:.4f}  seen {got['seen'][0]:.4f}+-{got['seen'][1]:.4f}  "
                      f"centre {c[0]:.4f}+-{ce[0]:.4f}  baked/all {baked[k] / got['all'][0]:.2f}  all/seen "
                      f"{got['all'][0] / got['seen'][0]:.2f}  baked/seen {baked[k] / got['seen'][0]:.2f}  "
                      f"(towards the sun: all {got['all sun']:+.2f}, seen {got['seen sun']:+.2f} voxels)", flush=True)
            r = np.array(rows)
            ws = wk / wk.sum()
            def ratio(a, b):
                return (ws * r[:, a]).sum() / (ws * r[:, b]).sum()
            print(f"seed {seed}, weighted sums: baked/all {ratio(0, 1):.3f}  all/seen {ratio(1, 3):.3f}  baked/seen "
                  f"{ratio(0, 3):.3f}  baked/centre {ratio(0, 5):.3f}  seen/centre {ratio(3, 5):.3f}  (MC noise: all "
                  f"{np.sqrt((ws ** 2 * r[:, 2] ** 2).sum()) / (ws * r[:, 1]).sum():.3f}, seen "
                  f"{np.sqrt((ws ** 2 * r[:, 4] ** 2).sum()) / (ws * r[:, 3]).sum():.3f})", flush=True)


if __name__ == "__main__":
    main()
