"""Where spray_dense's rim error lies (docs/benchmarks.md, spray-rims): which voxels' light the rim pixels see, and
whether their baked values or the baked render of them is wrong.

Bakes the case (FINAL, seeds 0..N-1) against the suite's cached reference and splits its pixels as
bench/suite_regions.py does (lit or shadowed where the camera ray reaches optical depth 1; core: the ray's optical
depth through the snow 20 or more, rim: under 20). For each region:
- **whose light**: the share of the pixel's extinction-weighted transmittance (the weight the render gives the source
  grids' values along the ray, each sample's trilinear hat split over its 8 voxels) that falls on air voxels across
  a face of a traced voxel that gathers face sources (they carry that face's source), on other air voxels (the mean
  of their neighbours' carried values) and on snow voxels by their optical depth sigma_t h;
- **the baked render** against the reference (mean |error|, bias of the sum);
- **the mixed render** with the renderer scattering (its own path tracing, as Cycles does where firn_scatter is 1) in
  the bake's traced voxels of sigma_t h under each --thin depth and the air within their 3^3 block, the baked emission
  elsewhere (firncore.render_scattering_where_thin, shares on the density's voxels): 2 is the form users get (the
  bake's firn_scatter), 10 the lumps' thinner half; 20.5 every traced voxel (spray_dense's are all traced, its full
  voxels 20: the core's Monte Carlo throughout, and at a few hundred paths as noisy as 16 % per block); paths that
  leave a scattered voxel see the baked values of the voxels they meet;
- with --overlap the baked grids with every other-air voxel beside snow holding its snow neighbours' own values
  (overlap_oracle: whether that air's neighbour mean is the wrong value);
- the rims split by whether most of a pixel's light lies where the mixed form scatters (snow of sigma_t h under 2 and
  the air in its 3^3 block) or not, with the per block rms of the seeds' noise and of the bias (as
  bench/suite_regions.py), and per view;
- with --quality REFERENCE that bake instead (1024 paths per traced voxel: the traced sources nearer converged);
- with --segments K (seed 0's bake): where along each ray the error arises: each seen ray started again where the
  snow's optical depth along it reaches each of --cuts (the baked render and the core's Monte Carlo of K paths from
  there), the pixel's light split into the segments between the cuts, e^-tau_a L(tau_a) - e^-tau_b L(tau_b), and
  each segment's baked-minus-true light over the pixel's true light (these add up to the pixel's relative error).

    PYTHONPATH=build/python /usr/bin/python3 bench/spray_rims_probe.py [--case spray_dense] [--seeds 1]
        [--thin 2,10] [--samples 512] [--quality FINAL] [--overlap] [--segments 1024 --cuts 0.3,1,3] [--save F]
"""

import argparse
import os
import tempfile

import numpy as np

import pyopenvdb

import bake_suite
import firncore
from suite_regions import regions

CLASSES = ("air f", "air o", "tau<2", "2-10", ">=10")


def voxel_classes(case):
    """Per density voxel: air across a face of snow of sigma_t h over 2 (0: it carries that traced voxel's face
    source, faceCarried), other air (1: the mean of its carried neighbours), then snow by its optical depth sigma_t h:
    2 under 2 (the voxels the mixed form scatters; no face sources), 3 from 2 to 10, 4 over 10 (spray_dense's full
    voxels are 20; its lumps are mostly partly filled)."""
    depth = case.density * case.sigma_t / case.rho * case.voxel
    thick = np.pad(depth > 2.0, 1)
    beside = np.zeros(depth.shape, bool)
    for axis in range(3):
        for step in (-1, 1):
            beside |= np.roll(thick, step, axis=axis)[1:-1, 1:-1, 1:-1]
    return np.where(case.density > 0.0, np.digitize(depth, [2.0, 10.0]) + 2, np.where(beside, 0, 1))


def whose_light(case, origins, directions, seen, classes, count=len(CLASSES)):
    """Per seen ray, the shares (`count` classes, CLASSES' by default) of its weight sigma_t T ds on each voxel class
    (the rest: the ray leaves)."""
    n = np.array(case.density.shape)
    per_density = case.sigma_t / case.rho
    ds = 0.125 * case.voxel
    steps = np.arange(0.0, 2.0, ds)
    out = np.zeros((len(origins), count))
    for i in np.nonzero(seen)[0]:
        p = (origins[i] + steps[:, None] * directions[i]) / case.voxel
        f = np.floor(p).astype(int)
        t = p - f
        weights, kinds, rho = [], [], np.zeros(len(p))
        for corner in range(8):
            o = np.array([(corner >> a) & 1 for a in range(3)])
            c = f + o
            ok = np.all((c >= 0) & (c < n), axis=1)
            w = np.where(ok, np.prod(np.where(o, t, 1.0 - t), axis=1), 0.0)
            cc = np.clip(c, 0, n - 1)
            rho += w * np.where(ok, case.density[cc[:, 0], cc[:, 1], cc[:, 2]], 0.0)
            weights.append(w)
            kinds.append(np.where(ok, classes[cc[:, 0], cc[:, 1], cc[:, 2]], 0))
        sigma = rho * per_density
        before = np.exp(-(np.cumsum(sigma) - sigma) * ds)
        along = before * -np.expm1(-sigma * ds)  # exact over each step: sigma ds reaches 2.5 here
        for w, k in zip(weights, kinds):
            np.add.at(out[i], k, along * w)
    return out


def overlap_oracle(path, case, classes, out_path):
    """The baked file with every other-air voxel (class 1) beside snow holding its snow neighbours' own grid values,
    weighted by the overlap of the two voxels' trilinear hats (16 : 4 : 1 for a face, edge, corner neighbour) times
    the neighbour's density: the source of the scatterers the render's emission there comes from."""
    grids, metadata = pyopenvdb.readAll(path)
    n = np.array(case.density.shape)
    offsets = [np.array(o) for o in np.ndindex(3, 3, 3) if o != (1, 1, 1)]
    rho = np.pad(case.density, 1)
    targets = np.argwhere((classes == 1))
    for g in grids:
        if not g.name.startswith("firn_source"):
            continue
        values = np.zeros(tuple(n + 2) + (3,), np.float32)  # the density's box and one voxel around, index + 1
        g.copyToArray(values, ijk=(-1, -1, -1))
        new = values.copy()
        for c in targets:
            num, den = np.zeros(3), 0.0
            for o in offsets:
                at = tuple(c + o)  # padded index of c + o - 1
                if rho[at] > 0.0:
                    w = 4.0 ** (3 - np.count_nonzero(o - 1)) * rho[at]
                    num += w * values[at]
                    den += w
            if den > 0.0:
                new[tuple(c + 1)] = num / den
        g.copyFromArray(new, ijk=(-1, -1, -1), tolerance=(0.0, 0.0, 0.0))
    pyopenvdb.write(out_path, grids=grids, metadata=metadata)


def scattered_region(case):
    """1 where the mixed form scatters (firn_scatter at the density's voxels, every voxel traced as in spray_dense):
    snow of sigma_t h under 2 and the air in its 3^3 block; 0 elsewhere."""
    depth = case.density * case.sigma_t / case.rho * case.voxel
    thin = (case.density > 0.0) & (depth < 2.0)
    padded = np.pad(thin, 1)
    near = np.zeros(thin.shape, bool)
    for o in np.ndindex(3, 3, 3):
        near |= padded[o[0]:o[0] + thin.shape[0], o[1]:o[1] + thin.shape[1], o[2]:o[2] + thin.shape[2]]
    return (thin | (near & (case.density <= 0.0))).astype(int)


def shares_in(case, origins, directions, seen, region):
    """Per ray, the share of its light's weight (whose_light) on the region's voxels."""
    weights = whose_light(case, origins, directions, seen, region)
    return weights[:, 1] / np.maximum(weights.sum(1), 1e-30)


def cut_points(case, origins, directions, seen, cuts):
    """Per seen ray, where the snow's optical depth along it reaches each cut (NaN where it never does)."""
    per_density = case.sigma_t / case.rho
    ds = 0.0625 * case.voxel
    steps = np.arange(0.0, 2.0, ds)
    out = np.full((len(cuts), len(origins), 3), np.nan)
    for i in np.nonzero(seen)[0]:
        p = origins[i] + steps[:, None] * directions[i]
        tau = np.concatenate([[0.0], np.cumsum(bake_suite.trilinear(case.density, p / case.voxel)) * per_density * ds])
        for k, cut in enumerate(cuts):
            j = np.searchsorted(tau, cut)
            if j < len(tau):  # linear within the step
                s = steps[j - 1] + ds * (cut - tau[j - 1]) / max(tau[j] - tau[j - 1], 1e-30)
                out[k, i] = origins[i] + s * directions[i]
    return out


def segments(case, path, origins, directions, seen, groups, reference, cuts, samples):
    """Each group's light per segment of optical depth along its rays, baked against Monte Carlo (printed)."""
    starts = cut_points(case, origins, directions, seen, cuts)
    rays = np.nonzero(seen)[0]
    true_from, baked_from = [reference], [firncore.render_baked(path, case.optics, origins, directions,
                                                                occluders=case.occluders)]
    for k in range(len(cuts)):
        ok = rays[np.all(np.isfinite(starts[k, rays]), axis=1)]
        t, b = np.zeros_like(reference), np.zeros_like(reference)
        if len(ok):
            b[ok] = firncore.render_baked(path, case.optics, starts[k, ok], directions[ok], occluders=case.occluders)
            t[ok], _ = firncore.monte_carlo_radiance(path, case.optics, starts[k, ok], directions[ok],
                                                     suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                                                     samples=samples, seed=23 + k)
        true_from.append(t)
        baked_from.append(b)
    attenuation = [1.0] + [np.exp(-c) for c in cuts]
    pieces = []  # per segment: (true, baked) light of each pixel
    for k in range(len(cuts) + 1):
        def light(f):
            here = attenuation[k] * f[k]
            return here - (attenuation[k + 1] * f[k + 1] if k < len(cuts) else 0.0)
        pieces.append((light(true_from), light(baked_from)))
    edges = ["0"] + [f"{c:g}" for c in cuts] + ["end"]
    names = [f"tau {edges[k]}-{edges[k + 1]}" for k in range(len(cuts) + 1)]
    print(f"\nwhere along the rays (seed 0; Monte Carlo {samples} paths from each cut): per segment of optical depth, "
          "its share of the true light, then its (baked - true) / the pixel's true light: mean signed, mean |.|, %")
    print(f"  {'region':<14} {'px':>4}" + "".join(f"  {n:>24}" for n in names) + "      sum (signed)")
    for label, where in groups:
        total = reference[where]
        line = f"  {label:<14} {where.sum():4d}"
        signed_sum = 0.0
        for t, b in pieces:
            share = t[where].sum() / total.sum()
            term = (b[where] - t[where]) / np.maximum(total, 1e-30)
            signed_sum += 100 * term.mean()
            line += f"  {share:5.2f} {100 * term.mean():+7.1f} {100 * np.abs(term).mean():6.1f}    "
        print(line + f"  {signed_sum:+6.1f}", flush=True)


def figures(render, reference):
    relative = render / np.maximum(reference, 1e-30) - 1.0
    return 100 * np.abs(relative).mean(), 100 * (render.sum() / reference.sum() - 1.0)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="spray_dense")
    parser.add_argument("--seeds", type=int, default=1)
    parser.add_argument("--thin", default="2,10", help="sigma_t h under which traced voxels scatter")
    parser.add_argument("--samples", type=int, default=512, help="paths per block of the mixed renders")
    parser.add_argument("--quality", default="FINAL")
    parser.add_argument("--segments", type=int, default=0, help="paths per ray of the cut rays' Monte Carlo (0: none)")
    parser.add_argument("--cuts", default="0.3,1,3", help="optical depths where the cut rays start")
    parser.add_argument("--overlap", action="store_true",
                        help="also render the grids with other air beside snow holding its snow's values (overlap)")
    parser.add_argument("--save", default="", help="an npz of the per-pixel renders, reference, shares and regions")
    parser.add_argument("--cache", default=bake_suite.CACHE)
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    origins, directions, tau = bake_suite.views(case)
    seen, lit, core = regions(case, origins, directions, tau)
    classes = voxel_classes(case)
    shares = whose_light(case, origins, directions, seen, classes)
    groups = [("all", seen), ("lit core", seen & lit & core), ("lit rim", seen & lit & ~core),
              ("shadowed core", seen & ~lit & core), ("shadowed rim", seen & ~lit & ~core)]
    thins = [float(x) for x in args.thin.split(",") if x]
    forms = {"baked": []}
    if args.overlap:
        forms["other air from its snow"] = []
    forms.update({f"mixed, scatter under {d:g}": [] for d in thins})
    noise = {name: [] for name in forms}  # the mixed render's and the reference's standard errors together
    with tempfile.TemporaryDirectory() as folder:
        for seed in range(args.seeds):
            path = os.path.join(folder, case.name + ".vdb")
            run = bake_suite.baked_case(case, path, args.cache, args.quality, seed)
            reference = run.mean
            forms["baked"].append(firncore.render_baked(path, case.optics, origins, directions,
                                                        occluders=case.occluders))
            if args.overlap:
                oracle = os.path.join(folder, "overlap.vdb")
                overlap_oracle(path, case, classes, oracle)
                forms["other air from its snow"].append(firncore.render_baked(oracle, case.optics, origins, directions,
                                                                              occluders=case.occluders))
            if seed == 0 and args.segments:
                segments(case, path, origins, directions, seen, groups, reference,
                         [float(x) for x in args.cuts.split(",")], args.segments)
            for d in thins:
                scattered = len(firncore.scatter_voxels(path, case.optics, occluders=case.occluders, thin_depth=d,
                                                        traced_only=True))
                render, error = firncore.render_scattering_where_thin(
                    path, case.optics, origins, directions, suns=case.suns(), sky=case.skies(),
                    occluders=case.occluders, samples=args.samples, seed=1000 + seed, thin_depth=d,
                    traced_only=True, scatter_scale=1)
                forms[f"mixed, scatter under {d:g}"].append(render)
                noise[f"mixed, scatter under {d:g}"].append(np.hypot(error, run.error))
                print(f"seed {seed}: thin depth {d:g}: {scattered} voxels scattered (snow and air), "
                      f"{run.stats['traced_voxels']} traced", flush=True)
    if args.save:
        np.savez(args.save, reference=reference, seen=seen, lit=lit, core=core, shares=shares,
                 **{name.replace(" ", "_").replace(",", ""): np.array(r) for name, r in forms.items()})
    print(f"\n{case.name}, {args.quality}, seeds 0-{args.seeds - 1}, mixed renders {args.samples} paths per block")
    print("whose light (share of the ray's sigma_t T over " + ", ".join(CLASSES) + " voxels), then per form: "
          "one seed's mean |error| / bias of the sum, %; for the mixed renders in brackets the mean |error| their "
          "own and the reference's noise alone would give (sqrt(2/pi) of their standard errors combined)")
    header = f"  {'region':<14} {'px':>4}  " + " ".join(f"{c:>5}" for c in CLASSES)
    print(header + "".join(f"  {name:>22}" for name in forms))
    for label, where in groups:
        s = shares[where]
        line = f"  {label:<14} {where.sum():4d}  " + " ".join(f"{x:5.2f}" for x in s.mean(0))
        for name, renders in forms.items():
            per_seed = [figures(r[where], reference[where]) for r in renders]
            e, b = np.mean(per_seed, axis=0)
            line += f"  {e:6.1f} / {b:+6.1f}"
            line += (f" ({100 * np.sqrt(2 / np.pi) * np.mean([n[where] / reference[where] for n in noise[name]]):4.1f})"
                     if noise[name] else " " * 7)
        print(line, flush=True)
    # The rims split by whether most of their light lies where the mixed form scatters (snow of sigma_t h under 2
    # and the air in its 3^3 block), then per view.
    views = np.repeat(np.arange(len(case.views)), case.pixels ** 2)
    thin = shares_in(case, origins, directions, seen, scattered_region(case)) >= 0.5
    print("\nby where most of a pixel's light lies (thin: snow of sigma_t h under 2 and its 3^3 air, what the mixed "
          "form scatters): one seed's mean |error|, per block rms of the seeds' noise and of the bias, bias of the sum, %")
    parts = [("lit rim, thin", lit & ~core & thin), ("lit rim, thick", lit & ~core & ~thin),
             ("shadowed rim, thin", ~lit & ~core & thin), ("shadowed rim, thick", ~lit & ~core & ~thin),
             ("core", core)]
    for label, part in parts:
        where = seen & part
        line = f"  {label:<20} {where.sum():4d} px"
        for renders in forms.values():
            relative = np.array(renders)[:, where] / reference[where] - 1.0
            variance = relative.var(0, ddof=1) if len(renders) > 1 else np.zeros(relative.shape[1:])
            bias_squared = relative.mean(0) ** 2 - variance / len(renders)
            line += (f"   {100 * np.abs(relative).mean():5.1f} {100 * np.sqrt(variance.mean()):5.1f} "
                     f"{100 * np.sqrt(max(bias_squared.mean(), 0.0)):5.1f} "
                     f"{100 * (np.array(renders)[:, where].sum() / reference[where].sum() / len(renders) - 1):+5.1f}")
        print(line)
    print("per view, the same parts: mean signed error per block (seeds' mean), %")
    for name, renders in forms.items():
        with np.errstate(divide="ignore", invalid="ignore"):  # the unseen pixels' reference is 0
            mean_relative = (np.array(renders) / reference - 1.0).mean(0)
        for v, view in enumerate(case.views):
            line = f"  {name:<24} {str(view):<9}"
            for label, part in parts:
                where = seen & part & (views == v)
                line += f"  {label} {where.sum():2d} " + (f"{100 * mean_relative[where].mean():+6.1f}" if where.any()
                                                          else "     -")
            print(line)

if __name__ == "__main__":
    main()
