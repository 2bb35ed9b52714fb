"""How much each extension of the grids' broad lobe would remove of three measured shape errors (docs only).

The true angular distributions, by numpy Monte Carlo (optical-depth units, local estimates towards a fixed set
of directions at every collision, as bench/bake_halfspace.py's half_space):
  (a) a half-space's exit radiance under a high sun (omega 0.9999, g 0.85: ball_snow's snow), mu0 1 and 0.87;
  (b) the source function in a plane-parallel layer of optical thickness 3 (slab_thin_forward: omega 0.9999,
      g 0.87, sun 30 deg from the layer), its multiple scattering (the peaked lobe holds the single scattering
      exactly: omega HG(g) about the beam);
  (c) a half-space's exit radiance under a grazing sun (mu0 0.05-0.44, ball_snow's limb).
Each candidate form (CANDIDATES) is fitted by least squares in relative error, with the flux kept (surfaces:
the exitance, as exitLobe keeps it; the layer: the mean and first moment, as the grids keep them, and freely).
Run (docs/benchmarks.md "lobe-form": 32000 photons on 16 cores, 126 s):
  /usr/bin/python3 bench/lobe_form.py --simulate /tmp/mc.npz --photons 32000; ... --fit /tmp/mc.npz
"""
import argparse
import math
import os

import numpy as np

from bake_halfspace import henyey_greenstein, scatter


def sphere_grid(n_mu, n_phi, upper_only):
    """Directions (midpoint rule in mu and azimuth) and their solid angles."""
    lo = 0.0 if upper_only else -1.0
    edges = np.linspace(lo, 1.0, n_mu + 1)
    mu = 0.5 * (edges[1:] + edges[:-1])
    phi = (np.arange(n_phi) + 0.5) * 2.0 * math.pi / n_phi
    M, P = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1.0 - M * M)
    dirs = np.stack([s * np.cos(P), s * np.sin(P), M], axis=-1).reshape(-1, 3)
    dw = np.full(len(dirs), (edges[1] - edges[0]) * 2.0 * math.pi / n_phi)
    return dirs, dw


def half_space_exits(omega, g, mu0, views, photons, seed):
    """pi L / (mu0 E) towards each unit view (normal +z, sun travelling towards +x): single, multiple."""
    rng = np.random.default_rng(seed)
    s0 = math.sqrt(1.0 - mu0 * mu0)
    d = np.tile([s0, 0.0, -mu0], (photons, 1))
    z = -np.log(rng.random(photons)) * mu0
    w = np.ones(photons)
    mu = views[:, 2]
    single, multiple, first = np.zeros(len(views)), np.zeros(len(views)), True
    while len(w):
        est = (w[:, None] * omega * henyey_greenstein(g, d @ views.T)
               * np.exp(-z[:, None] / mu[None, :]) / mu[None, :]).sum(0)
        if first:
            single += est
        else:
            multiple += est
        first = False
        w = w * omega
        d = scatter(d, g, rng)
        z = z - d[:, 2] * -np.log(rng.random(len(w)))
        low = w < 1e-3
        survive = ~low | (rng.random(len(w)) < 0.1)
        w = np.where(low, 10.0 * w, w)
        keep = (z >= 0.0) & survive
        d, z, w = d[keep], z[keep], w[keep]
    return math.pi * single / photons, math.pi * multiple / photons


def layer_source(omega, g, tau, sun_elevation, views, photons, seed, bins=3):
    """The multiply scattered source function per unit extinction, in each of `bins` depth slices of a layer
    of optical thickness tau (z from 0 at the bottom to tau), lit from above by a unit beam travelling down at
    sun_elevation from the layer's plane, towards +x (the suite's sun is at -x: mirrored views): a collision
    estimator, omega HG(d . view) per collision after the first, divided by the slice's optical thickness and the
    beam's flux through the layer."""
    rng = np.random.default_rng(seed)
    mu0 = math.sin(sun_elevation)
    d = np.tile([math.cos(sun_elevation), 0.0, -mu0], (photons, 1))
    z = tau - (-np.log(rng.random(photons))) * mu0
    w = np.ones(photons)
    out = np.zeros((bins, len(views)))
    alive = z >= 0.0
    d, z, w = d[alive], z[alive], w[alive]
    d = scatter(d, g, rng)  # the first collision is the single scattering: left to the peaked lobe
    w = w * omega
    while len(w):
        z = z + d[:, 2] * -np.log(rng.random(len(w)))  # z up from the layer's bottom
        inside = (z >= 0.0) & (z <= tau)
        d, z, w = d[inside], z[inside], w[inside]
        b = np.minimum((z / tau * bins).astype(int), bins - 1)
        val = w[:, None] * omega * henyey_greenstein(g, d @ views.T)
        for i in range(bins):
            out[i] += val[b == i].sum(0)
        w = w * omega
        d = scatter(d, g, rng)
        low = w < 1e-3
        survive = ~low | (rng.random(len(w)) < 0.1)
        w = np.where(low, 10.0 * w, w)
        d, z, w = d[survive], z[survive], w[survive]
    return out / photons / (tau / bins)  # per unit extinction, the beam's flux E mu0 = 1 per unit area


def nelder_mead(f, x0, step=0.2, iterations=3000):
    """Minimises f from x0 (no scipy on this machine); restarted once from its result."""
    for _ in range(2):
        n = len(x0)
        simplex = [np.array(x0, float)] + [np.array(x0, float) + step * np.eye(n)[i] for i in range(n)]
        values = [f(x) for x in simplex]
        for _ in range(iterations):
            order = np.argsort(values)
            simplex, values = [simplex[i] for i in order], [values[i] for i in order]
            centre = np.mean(simplex[:-1], axis=0)
            reflected = centre + (centre - simplex[-1])
            fr = f(reflected)
            if fr < values[0]:
                expanded = centre + 2.0 * (centre - simplex[-1])
                fe = f(expanded)
                simplex[-1], values[-1] = (expanded, fe) if fe < fr else (reflected, fr)
            elif fr < values[-2]:
                simplex[-1], values[-1] = reflected, fr
            else:
                contracted = centre + 0.5 * (simplex[-1] - centre)
                fc = f(contracted)
                if fc < values[-1]:
                    simplex[-1], values[-1] = contracted, fc
                else:
                    simplex = [simplex[0] + 0.5 * (x - simplex[0]) for x in simplex]
                    values = [f(x) for x in simplex]
        x0 = simplex[int(np.argmin(values))]
    return x0


def axis(theta, phi):
    return np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])


def lobe(k, cos, power=1.5):
    """4 pi HG(k) for power 1.5 (the grids' lobe, mean 1); other powers unnormalised."""
    k = np.clip(k, -0.95, 0.95)
    return (1.0 - k * k) / (1.0 + k * k - 2.0 * k * cos) ** power


def quadrupole_basis(v):
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    return np.stack([x * y, y * z, x * z, x * x - y * y, 3.0 * z * z - 1.0])


# Each candidate: (name, parameter count, shape(params, views) -> unscaled radiance). Shapes before the scale;
# the scale is fixed by the flux (surfaces) or is a free parameter held by the moments' penalty (the layer).
def hg_shape(p, v):
    return lobe(p[0], v @ axis(p[1], p[2]))


def p2_shape(p, v):
    cos = v @ axis(p[1], p[2])
    return np.maximum(0.0, lobe(p[0], cos) + p[3] * 0.5 * (3.0 * cos * cos - 1.0))


def quad_shape(p, v):
    return np.maximum(0.0, lobe(p[0], v @ axis(p[1], p[2])) + p[3:8] @ quadrupole_basis(v))


def two_lobe_shape(p, v):
    return lobe(p[0], v @ axis(p[1], p[2])) + p[3] * p[3] * lobe(p[4], v @ axis(p[5], p[6]))


def power_shape(p, v):
    return lobe(p[0], v @ axis(p[1], p[2]), 1.5 + p[3])


def linear_p2_shape(p, v):
    cos = v @ axis(p[1], p[2])
    return np.maximum(0.0, 1.0 + p[0] * cos + p[3] * 0.5 * (3.0 * cos * cos - 1.0))


def sh2_shape(p, v):
    return np.maximum(0.0, 1.0 + p[0] * (v @ axis(p[1], p[2])) + p[3:8] @ quadrupole_basis(v))


CANDIDATES = [
    ("HG (the grids' broad lobe)", [0.3, 0.3, 0.0], hg_shape),
    ("(1) HG + q P2(cos), axial mu^2 about l1", [0.3, 0.3, 0.0, 0.0], p2_shape),
    ("(1) HG + quadrupole (5)", [0.3, 0.3, 0.0, 0, 0, 0, 0, 0], quad_shape),
    ("(2) two broad HG lobes", [[0.3, 0.3, 0.0, 0.7, 0.3, 1.5, 0.0], [0.3, 0.3, 0.0, 0.7, 0.3, 1.5, math.pi],
                                [0.3, 0.3, 0.0, 0.7, -0.3, 0.2, 0.0]], two_lobe_shape),
    ("(3) (1 + k^2 - 2k cos)^-p, k of either sign", [0.3, 0.3, 0.0, 0.0], power_shape),
    ("(1') no HG: max(0, l0 + l1.w + q P2), axial", [[0.9, 0.3, 0.0, 0.0], [0.5, 0.3, 0.0, -0.3]], linear_p2_shape),
    ("(1') no HG: max(0, l0 + l1.w + quadrupole)",
     [[0.9, 0.3, 0.0, 0, 0, 0, 0, 0], [0.5, 0.3, 0.0, 0, 0, 0, 0, -0.1]], sh2_shape),
]


def fit_surface(target, views, dw, peak_axis=None, peak_k=0.85):
    """Each candidate fitted to target(views) over the hemisphere: relative error weighted by mu dw, the
    exitance kept; a peaked HG lobe (k = g about the sun's travel: the bake's SunPeak) beside it where given."""
    weight = views[:, 2] * dw
    flux = (target * weight).sum()
    scale = np.repeat(target.reshape(SURFACE_VIEWS).mean(1), SURFACE_VIEWS[1])  # the ring's level: a cell's
    # own noisy value as the denominator would pull the fit towards the cells that came out low
    peak = lobe(peak_k, views @ peak_axis) if peak_axis is not None else None
    out, best = [], None
    for name, starts, shape in CANDIDATES:
        def model(p):
            broad = shape(p[:-1] if peak is not None else p, views)
            f = broad + (p[-1] ** 2 * peak if peak is not None else 0.0)
            return f * flux / max((f * weight).sum(), 1e-30)
        def cost(p):
            return (weight * ((model(p) - target) / scale) ** 2).sum() / weight.sum()
        tail = [0.3] if peak is not None else []
        fits = [nelder_mead(cost, list(x0) + tail) for x0 in as_starts(starts)]
        # also from the HG fit with the extension switched off: never worse than HG (nested forms)
        if out and shape not in (linear_p2_shape, sh2_shape):
            fits.append(nelder_mead(cost, nested_start(best, starts, len(tail))))
        p = min(fits, key=cost)
        best = best if out else p
        out.append((name, model(p)))
    return out


def nested_start(hg_fit, starts, tail):
    """The HG fit's parameters with a candidate's extension switched off (a second lobe of weight 0.05^2)."""
    extension = list(as_starts(starts)[0][3:])
    if len(extension) == 4 and extension[0] == 0.7:
        extension[0] = 0.05
    return list(hg_fit[:3]) + extension + list(hg_fit[len(hg_fit) - tail:])


def as_starts(starts):
    return starts if isinstance(starts[0], list) else [starts]


def fit_layer(target, views, dw, penalty, peak):
    """Each candidate fitted to target over the sphere, relative error weighted by dw, its mean and first
    moment held to the target's, beside a peaked lobe about the beam (k = g, its mean free: the bake's
    peaked lobe holds the single scattering and what keeps the beam's direction), by a penalty (times the squared
    relative difference: 10^4 holds them, 0 is a free fit as tracedSourceByDirection's)."""
    mean = (target * dw).sum()
    moment = (target[:, None] * views * dw[:, None]).sum(0)
    out, best = [], None
    for name, starts, shape in CANDIDATES:
        def model(p):
            return p[-2] ** 2 * shape(p[:-2], views) + p[-1] ** 2 * peak
        def cost(p):
            f = model(p)
            fit = (dw * (f / target - 1.0) ** 2).sum() / dw.sum()
            m1 = (f[:, None] * views * dw[:, None]).sum(0)
            return fit + penalty * ((((f * dw).sum() - mean) / mean) ** 2 + (np.linalg.norm(m1 - moment) / mean) ** 2)
        fits = []
        for x0 in as_starts(starts):
            start = list(x0)
            start[1], start[2] = math.acos(moment[2] / np.linalg.norm(moment)), math.atan2(moment[1], moment[0])
            fits.append(nelder_mead(cost, start + [0.5 * math.sqrt(mean), 0.5 * math.sqrt(mean)]))
        if out and shape not in (linear_p2_shape, sh2_shape):
            fits.append(nelder_mead(cost, nested_start(best, starts, 2)))
        p = min(fits, key=cost)
        best = best if out else p
        out.append((name, model(p)))
    return out


def ring_means(x):
    return x.reshape(SURFACE_VIEWS).mean(1)


def rms(model, target, weight):
    return math.sqrt((weight * (model / target - 1.0) ** 2).sum() / weight.sum())


def mirrored(x, shape):
    """Averaged with its mirror image in the sun's plane (azimuth phi and -phi: the same by symmetry)."""
    x = x.reshape(shape)
    return (0.5 * (x + x[:, ::-1])).reshape(-1)


def fit_all(path, layer_photons=400000):
    data = np.load(path)
    views, dw = sphere_grid(*SURFACE_VIEWS, upper_only=True)
    n_mu, n_phi = SURFACE_VIEWS
    ring = lambda x, i: x.reshape(n_mu, n_phi)[i].mean()
    for mu0 in (1.0, 0.87):
        target = mirrored(data[f"a_{mu0}"].mean(0).sum(0), SURFACE_VIEWS)
        sun = np.array([math.sqrt(1 - mu0 * mu0), 0.0, -mu0])
        print(f"(a) half-space, omega 0.9999 g 0.85, mu0 {mu0}: "
              f"the top ring (mu {1 - 0.5 / n_mu:.3f}) {ring(target, -1):.3f}")
        for name, model in fit_surface(target, views, dw, sun):
            rings = rms(ring_means(model), ring_means(target), ring_means(views[:, 2] * dw))
            print(f"  {name:48s} rms {100 * rms(model, target, views[:, 2] * dw):5.1f} % (rings {100 * rings:4.1f} %)  "
                  f"top ring {100 * (ring(model, -1) / ring(target, -1) - 1):+5.1f} %   "
                  f"mu 0.06 ring {100 * (ring(model, 0) / ring(target, 0) - 1):+5.1f} %")
    for mu0 in (0.05, 0.15, 0.3, 0.44):
        target = mirrored(data[f"c_{mu0}"].mean(0).sum(0), SURFACE_VIEWS)
        sun = np.array([math.sqrt(1 - mu0 * mu0), 0.0, -mu0])
        t = target.reshape(n_mu, n_phi)
        # mu 0.19, azimuth 11 / 169 deg
        fb = lambda x: (x[1, [0, -1]].mean() / x[1, [n_phi // 2 - 1, n_phi // 2]].mean())
        print(f"(c) half-space, grazing sun mu0 {mu0}: forward / backward at mu 0.19 {fb(t):.2f}")
        for name, model in fit_surface(target, views, dw, sun):
            m = model.reshape(n_mu, n_phi)
            print(f"  {name:48s} rms {100 * rms(model, target, views[:, 2] * dw):5.1f} %   "
                  f"forward {100 * (m[1, [0, -1]].mean() / t[1, [0, -1]].mean() - 1):+5.1f} %"
                  f"  backward {100 * (m[1, [7, 8]].mean() / t[1, [7, 8]].mean() - 1):+5.1f} %  f/b {fb(m):.2f}")
    lv, ldw = sphere_grid(*LAYER_VIEWS, upper_only=False)
    multiple = mirrored(layer_source(*LAYER, lv, layer_photons, 7, bins=3)[1], LAYER_VIEWS)  # the middle voxel
    beam = np.array([math.cos(LAYER[3]), 0.0, -math.sin(LAYER[3])])
    mu0 = math.sin(LAYER[3])  # the single scattering at mid-depth, per unit extinction, E mu0 = 1
    single = LAYER[0] * henyey_greenstein(LAYER[1], lv @ beam) * math.exp(-0.5 * LAYER[2] / mu0) / mu0
    total = single + multiple
    ring45 = np.abs(lv @ beam - math.cos(math.radians(45.0))) < 0.06
    print(f"(b) layer tau 3, omega 0.9999 g 0.87, sun 30 deg, middle third: the 45 deg ring's max / min "
          f"{total[ring45].max() / total[ring45].min():.2f} "
          f"(multiple alone {multiple[ring45].max() / multiple[ring45].min():.2f})")
    camera = np.argmax(lv @ np.array([0.26, 0.0, -0.97]))  # slab_thin_forward's (180, -75) camera, mirrored
    for penalty, how in ((1e4, "mean and first moment kept"), (0.0, "fitted freely")):
        print(f"  {how}:")
        for name, f in fit_layer(total, lv, ldw, penalty, lobe(LAYER[1], lv @ beam)):
            print(f"  {name:48s} rms {100 * rms(f, total, ldw):5.1f} %   45 deg ring rms "
                  f"{100 * rms(f[ring45], total[ring45], ldw[ring45]):5.1f} %   "
                  f"camera below {100 * (f[camera] / total[camera] - 1):+5.1f} %")


SURFACE_VIEWS = (8, 16)  # mu x azimuth cells over the outgoing hemisphere
LAYER_VIEWS = (16, 16)  # over the sphere
SNOW = (0.9999, 0.85)  # ball_snow's omega, g
LAYER = (0.9999, 0.87, 3.0, math.radians(30.0))  # slab_thin_forward: omega, g, optical thickness, sun elevation
CONFIGS = [("a", 1.0), ("a", 0.87), ("c", 0.05), ("c", 0.15), ("c", 0.30), ("c", 0.44)]  # (part, mu0); (b) in fit_all


def simulate(job):
    """One worker's share of one configuration: (config index, seed, photons) -> arrays."""
    index, seed, photons = job
    _, mu0 = CONFIGS[index]
    views, _ = sphere_grid(*SURFACE_VIEWS, upper_only=True)
    return index, np.stack(half_space_exits(*SNOW, mu0, views, photons, seed))


def run_monte_carlo(photons, workers, out):
    import multiprocessing

    per = photons // workers
    jobs = [(i, 1000 * i + s, per) for i in range(len(CONFIGS)) for s in range(workers)]
    sums = {}
    with multiprocessing.Pool(workers) as pool:
        for index, value in pool.imap_unordered(simulate, jobs):
            sums.setdefault(index, []).append(value)
    arrays = {f"{CONFIGS[i][0]}_{CONFIGS[i][1]}": np.stack(v) for i, v in sums.items()}
    np.savez(out, **arrays)


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--photons", type=int, default=20000, help="per configuration")
    parser.add_argument("--workers", type=int, default=os.cpu_count())
    parser.add_argument("--simulate", help="write the Monte Carlo's arrays (per worker) to this .npz")
    parser.add_argument("--fit", help="fit the candidate forms to this .npz")
    args = parser.parse_args()
    if args.simulate:
        run_monte_carlo(args.photons, args.workers, args.simulate)
    if args.fit:
        fit_all(args.fit)
