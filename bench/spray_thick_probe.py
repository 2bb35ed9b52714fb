"""Which part of spray_dense's error the mixed form (Scatter Thin Snow, what users render) keeps, and what its worst
block is (docs/benchmarks.md, spray-thick).

Bakes the case (FINAL, seeds 0..N-1) and renders it baked and mixed (bake_suite.run_case's mixed render:
render_scattering_where_thin, `--mixed` paths per block, seeded 1000 + seed) against the suite's cached reference;
the per-seed renders can be saved (--save DIR) and read again (--load DIR) instead of baking. Its pixels split as
bench/spray_rims_probe.py does: lit or shadowed where the camera ray reaches optical depth 1, core (the ray's optical
depth 20 or more) or rim, and a rim thin (most of its light's weight on snow of sigma_t h under 2 and the air in its
3^3 block, what the mixed form scatters) or thick. Per region and form:
- points: the region's share of the case's mean |error| (its blocks' |error| summed over all seen blocks), one seed's,
  averaged over the seeds;
- bias-free: the same with each block's mean over the seeds taken out (what is left is the seeds' noise and the
  mixed render's; the difference is the points a per-block correction could take);
- the bias of the region's sum, the per block rms of the seeds' noise and of the bias, the mean signed error per view;
then the shadowed thick blocks (cores and thick rims) together, and the worst blocks over the seeds
with the lump their camera ray reaches depth 1 in (connected through faces, edges, corners: voxels, the sum of
(sigma_tr h)^3, the thickest voxel, extent). With --classes, seed 0's bake with each voxel class's source grids zeroed
(classes as spray_rims_probe.voxel_classes: air across a thick traced voxel's face, other air, snow by sigma_t h):
each class's light in those regions, as a share of the bake's and of the truth's. With --depths, seed 0's bake
rendered with the renderer scattering in the traced voxels under sigma_t h 2 (the mixed form), 10 and 20.5 (all of
them). With --facing, the regions' light weight on the thick voxels split by what lies across their face towards the
camera (air, thin snow, thick snow). With --segments K, seed 0's baked render split along the rays of those regions
by optical depth (spray_rims_probe.segments: each ray started again at 0.3, 1, 3, baked and K paths of Monte Carlo).

    PYTHONPATH=build/python /usr/bin/python3 bench/spray_thick_probe.py [--seeds 8] [--mixed 2048] [--save DIR |
        --load DIR] [--classes] [--depths] [--facing]
        [--segments 4096]
"""

import argparse
import os
import tempfile

import numpy as np
import pyopenvdb

import bake_suite
import firncore
from spray_rims_probe import CLASSES, scattered_region, segments, shares_in, voxel_classes, whose_light
from suite_regions import regions

CASE = "spray_dense"


def case_regions():
    """spray_dense's views and its blocks' regions: seen, lit, core (suite_regions), thin (the renderer scatters in
    at least half their light's weight), and each block's view."""
    case = bake_suite.case(CASE)
    origins, directions, tau = bake_suite.views(case)
    seen, lit, core = regions(case, origins, directions, tau)
    thin = shares_in(case, origins, directions, seen, scattered_region(case)) >= 0.5
    views = np.repeat(np.arange(len(case.views)), case.pixels ** 2)
    return case, origins, directions, tau, seen, lit, core, thin, views


def renders(case, seeds, mixed, cache, save, load):
    """Per seed: the baked and mixed renders, the reference and its error, the trace's processor seconds."""
    out = []
    with tempfile.TemporaryDirectory() as folder:
        for seed in range(seeds):
            file = os.path.join(load or save or folder, f"{case.name}_seed{seed}.npz")
            if not load:
                path = os.path.join(folder, case.name + ".vdb")
                run = bake_suite.baked_case(case, path, cache, "FINAL", seed)
                baked = firncore.render_baked(path, case.optics, run.origins, run.directions, occluders=case.occluders)
                mix, _ = firncore.render_scattering_where_thin(path, case.optics, run.origins, run.directions,
                                                               suns=case.suns(), sky=case.skies(),
                                                               occluders=case.occluders, samples=mixed,
                                                               seed=1000 + seed, traced_only=True)
                np.savez(file, baked=baked, mixed=mix, reference=run.mean, error=run.error,
                         trace=run.stats["cpu_seconds"]["trace"])
            out.append(dict(np.load(file)))
    return out


def lumps(mask):
    """Connected parts of `mask` (through faces, edges and corners): labels from 1, 0 outside."""
    label = np.zeros(mask.shape, int)
    count = 0
    for start in map(tuple, np.argwhere(mask)):
        if label[start]:
            continue
        count += 1
        label[start], stack = count, [start]
        while stack:
            c = np.array(stack.pop())
            for o in np.ndindex(3, 3, 3):
                q = tuple(c + np.array(o) - 1)
                if all(0 <= q[a] < mask.shape[a] for a in range(3)) and mask[q] and not label[q]:
                    label[q] = count
                    stack.append(q)
    return label


def region_table(form, rendered, reference, seen, parts, views):
    """Per region (label, mask) of the seeds' renders (seeds x blocks x channels): its figures, printed."""
    relative = rendered / np.maximum(reference, 1e-30) - 1.0
    total = 3 * seen.sum()
    mean = relative.mean(0)
    print(f"\n{form}: mean |error| per seed " + " ".join(f"{100 * np.abs(r[seen]).mean():.2f}" for r in relative) +
          f", mean {100 * np.abs(relative[:, seen]).mean():.2f} %")
    print(f"  {'region':<20} {'px':>3}  points  bias-free  bias of sum  noise rms  bias rms   per view (px): mean "
          "signed, %")
    for label, part in parts:
        w = seen & part
        points = 100 * np.abs(relative[:, w]).sum(axis=(1, 2)).mean() / total
        free = 100 * np.abs(relative[:, w] - mean[w]).sum(axis=(1, 2)).mean() / total
        bias = 100 * (rendered[:, w].sum() / len(rendered) / reference[w].sum() - 1.0)
        variance = relative[:, w].var(0, ddof=1)
        bias_squared = np.maximum(mean[w] ** 2 - variance / len(relative), 0.0)
        print(f"  {label:<20} {w.sum():3d}  {points:6.2f}  {free:9.2f}  {bias:+10.1f} %  "
              f"{100 * np.sqrt(variance.mean()):9.1f}  {100 * np.sqrt(bias_squared.mean()):8.1f}   " +
              " ".join(f"{100 * mean[w & (views == v)].mean():+6.1f} ({(w & (views == v)).sum():2d})"
                       if (w & (views == v)).any() else "     -      " for v in range(views.max() + 1)))
    return relative


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--mixed", type=int, default=2048, help="paths per block of the mixed render")
    parser.add_argument("--save", default="", help="a folder to keep the per-seed renders in")
    parser.add_argument("--load", default="", help="a folder of saved per-seed renders (no bake)")
    parser.add_argument("--classes", action="store_true", help="seed 0's bake with each voxel class's grids zeroed")
    parser.add_argument("--depths", action="store_true",
                        help="seed 0's bake rendered with the renderer scattering under sigma_t h 2, 10, 20.5")
    parser.add_argument("--facing", action="store_true",
                        help="the thick voxels' light split by their face towards each side view's camera")
    parser.add_argument("--segments", type=int, default=0,
                        help="seed 0: where along the rays the error arises, Monte Carlo of this many paths from "
                             "optical depths 0.3, 1, 3 (spray_rims_probe.segments)")
    parser.add_argument("--cache", default=bake_suite.CACHE)
    args = parser.parse_args()
    case, origins, directions, tau, seen, lit, core, thin, views = case_regions()
    runs = renders(case, args.seeds, args.mixed, args.cache, args.save, args.load)
    reference = runs[0]["reference"]
    print(f"{case.name}, FINAL, seeds 0-{len(runs) - 1}, mixed render {args.mixed} paths per block; views "
          f"{case.views}; trace {np.mean([r['trace'] for r in runs]):.2f} processor s")
    parts = [("lit core", lit & core), ("lit rim thin", lit & ~core & thin), ("lit rim thick", lit & ~core & ~thin),
             ("shadowed core", ~lit & core), ("shadowed rim thin", ~lit & ~core & thin),
             ("shadowed rim thick", ~lit & ~core & ~thin)]
    grouped = [("shadowed thick", ~lit & (core | ~thin))]
    for form in ("baked", "mixed"):
        relative = region_table(form, np.array([r[form] for r in runs]), reference, seen,
                                parts + [(f"{g} *", p) for g, p in grouped], views)
        masked = np.where(seen[None, :, None], np.abs(relative), 0.0).max(2)
        worst = masked.argmax(1)
        print("  the worst block per seed: " + ", ".join(
            f"{s}: px {p} {100 * relative[s, p].mean():+.0f} %" for s, p in enumerate(worst)))
        if form == "baked":
            worst_blocks(case, origins, directions, tau, seen, lit, core, thin, relative, runs, masked)
    print("\n(* the regions grouped: shadowed thick = shadowed cores and thick rims)")
    shadowed_thick, lit_core = seen & ~lit & (core | ~thin), seen & lit & core
    if args.facing:
        facing_shares(case, origins, directions, shadowed_thick, lit_core, views)
    if args.classes:
        class_shares(case, args.cache, shadowed_thick, lit_core, views)
    if args.depths:
        scatter_depths(case, args.cache, seen, shadowed_thick, lit_core, views)
    if args.segments:
        groups = [("shadowed thick 180", shadowed_thick & (views == 2)),
                  ("shadowed thick 90", shadowed_thick & (views == 1)),
                  ("lit core (0, 0)", lit_core & (views == 0)), ("lit core (0, 60)", lit_core & (views == 3))]
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, case.name + ".vdb")
            run = bake_suite.baked_case(case, path, args.cache, "FINAL", 0)
            rays = np.any([w for _, w in groups], axis=0)
            segments(case, path, origins, directions, rays, groups, run.mean, [0.3, 1.0, 3.0], args.segments)


def scatter_depths(case, cache, seen, shadowed_thick, lit_core, views):
    """Seed 0's bake with the renderer scattering in the traced voxels under each sigma_t h (and their 3^3 air),
    2048 paths per block: 20.5 scatters every traced voxel (the truth but for the render's noise)."""
    groups = {"shadowed thick, against the sun": shadowed_thick & (views == 2),
              "shadowed thick, other views": shadowed_thick & (views != 2), "lit core": lit_core, "all": seen}
    print("\nseed 0, the renderer scattering under sigma_t h: bias of the sum, mean |error| (in brackets what the "
          "render's and the reference's noise alone give), %")
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        run = bake_suite.baked_case(case, path, cache, "FINAL", 0)
        for depth in (2.0, 10.0, 20.5):
            r, e = firncore.render_scattering_where_thin(path, case.optics, run.origins, run.directions,
                                                         suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                                                         samples=2048, seed=1000, thin_depth=depth, traced_only=True)
            relative = r / np.maximum(run.mean, 1e-30) - 1.0
            noise = np.sqrt(2 / np.pi) * np.hypot(e, run.error) / np.maximum(run.mean, 1e-30)
            print(f"  under {depth:4g}: " + "  ".join(
                f"{g} {100 * (r[w].sum() / run.mean[w].sum() - 1):+.1f} / {100 * np.abs(relative[w]).mean():.1f}"
                f" ({100 * noise[w].mean():.1f})" for g, w in groups.items()), flush=True)


def facing_shares(case, origins, directions, shadowed_thick, lit_core, views):
    """Per side view, the regions' light weight (spray_rims_probe.whose_light) on air across a thick face, other air,
    thin snow, and thick snow (sigma_t h over 2) by what lies across its face towards the camera: air (the face is
    open and gathered), thin snow (closed: the voxel's own value shows that side), thick snow."""
    depth = case.density * case.sigma_t / case.rho * case.voxel
    base = np.minimum(voxel_classes(case), 2)
    names = ("air f, facing", "air o", "thin snow", "thick, open", "thick, on thin", "thick, on thick",
             "air f, lateral", "air f, away")
    print("\nthe light's weight by voxel, the thick voxels by their face towards the camera:")
    for v, towards in ((0, (1, 0, 0)), (1, (0, 1, 0)), (2, (-1, 0, 0))):  # the camera's side of the lumps
        across = np.roll(np.pad(depth, 1), tuple(-t for t in towards), axis=(0, 1, 2))[1:-1, 1:-1, 1:-1]
        kind = np.select([(depth > 2) & (across <= 0), (depth > 2) & (across < 2), depth > 2], [3, 4, 5], base)
        # air across a thick face (class 0) by the face's side: facing the camera (the thick voxel lies away from it),
        # lateral, or away from it; the facing side first where it borders several
        thick = np.pad(depth > 2, 1)
        facing = np.roll(thick, tuple(towards), axis=(0, 1, 2))[1:-1, 1:-1, 1:-1]  # thick at c - towards
        behind = np.roll(thick, tuple(-t for t in towards), axis=(0, 1, 2))[1:-1, 1:-1, 1:-1]  # thick at c + towards
        kind = np.where((kind == 0) & ~facing, np.where(behind, 7, 6), kind)
        for label, w in (("shadowed thick", shadowed_thick & (views == v)), ("lit core", lit_core & (views == v))):
            if w.any():
                shares = whose_light(case, origins, directions, w, kind, len(names))[w]
                shares = (shares / shares.sum(1, keepdims=True)).mean(0)
                print(f"  {str(case.views[v]):<9} {label:<15} ({w.sum():2d} px): " +
                      ", ".join(f"{n} {x:.2f}" for n, x in zip(names, shares)))


def worst_blocks(case, origins, directions, tau, seen, lit, core, thin, relative, runs, masked, count=4):
    """The `count` worst blocks over the seeds and the lump their ray reaches depth 1 in (or beside)."""
    label = lumps(case.density > 0.0)
    hit = bake_suite.depth_one_points(case, origins, directions, seen)
    depth = case.density * case.sigma_t / case.rho * case.voxel
    sigma_tr_h = case.sigma_t * (1.0 - case.omega[0] * case.g) * case.voxel  # at density rho
    mixed = np.array([r["mixed"] / np.maximum(r["reference"], 1e-30) - 1.0 for r in runs])
    reference, error = runs[0]["reference"], runs[0]["error"]
    for f in np.argsort(-masked.ravel())[:count]:
        s, p = divmod(int(f), masked.shape[1])
        c = np.round(hit[p] / case.voxel).astype(int)
        near = label[c[0] - 1:c[0] + 2, c[1] - 1:c[1] + 2, c[2] - 1:c[2] + 2].ravel()
        lump = label[tuple(c)] or np.bincount(near[near > 0]).argmax()
        voxels = label == lump
        print(f"  seed {s}, px {p}, view {case.views[p // case.pixels ** 2]}: baked "
              f"{100 * relative[s, p].mean():+.0f} %, seeds 0-{len(runs) - 1} baked "
              f"{' '.join(f'{100 * x:+.0f}' for x in relative[:, p].mean(1))}, mixed "
              f"{' '.join(f'{100 * x:+.0f}' for x in mixed[:, p].mean(1))} %; reference noise "
              f"{100 * error[p].mean() / reference[p].mean():.1f} %; ray tau {tau[p]:.1f}, "
              f"{'lit' if lit[p] else 'shadowed'}, {'core' if core[p] else 'rim'}, {'thin' if thin[p] else 'thick'}; "
              f"depth 1 at voxel {tuple(c)} (sigma_t h {depth[tuple(c)]:.1f}); lump {lump}: {voxels.sum()} voxels, "
              f"sum (sigma_tr h)^3 {np.sum((case.density[voxels] / case.rho * sigma_tr_h) ** 3):.0f}, thickest "
              f"sigma_t h {depth[voxels].max():.1f}, extent {tuple(np.ptp(np.argwhere(voxels), 0) + 1)}")


def class_shares(case, cache, shadowed_thick, lit_core, views):
    """Seed 0: each voxel class's light in the regions (its source grids zeroed), baked and mixed (1024 paths)."""
    groups = {"shadowed thick, against the sun": shadowed_thick & (views == 2),
              "shadowed thick, other views": shadowed_thick & (views != 2), "lit core": lit_core}
    classes = voxel_classes(case)
    n = np.array(case.density.shape)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        run = bake_suite.baked_case(case, path, cache, "FINAL", 0)

        def render(p, mixed):
            if mixed:
                return firncore.render_scattering_where_thin(p, case.optics, run.origins, run.directions,
                                                             suns=case.suns(), sky=case.skies(),
                                                             occluders=case.occluders, samples=1024, seed=1000,
                                                             traced_only=True)[0]
            return firncore.render_baked(p, case.optics, run.origins, run.directions, occluders=case.occluders)

        base = {m: render(path, m) for m in (False, True)}
        print("\nseed 0, each voxel class's light (its source grids zeroed): share of the bake's, then of the "
              "truth's, %")
        for m in (False, True):
            print(f"  {'mixed' if m else 'baked'} bias of the sum: " + ", ".join(
                f"{g} {100 * (base[m][w].sum() / run.mean[w].sum() - 1):+.1f} %" for g, w in groups.items()))
        for k, name in enumerate(CLASSES):
            grids, metadata = pyopenvdb.readAll(path)
            for g in grids:
                if g.name.startswith("firn_source"):
                    values = np.zeros(tuple(n) + (3,), np.float32)
                    g.copyToArray(values, ijk=(0, 0, 0))
                    values[classes == k] = 0.0
                    g.copyFromArray(values, ijk=(0, 0, 0), tolerance=(0.0, 0.0, 0.0))
            zeroed = os.path.join(folder, f"without_{k}.vdb")
            pyopenvdb.write(zeroed, grids=grids, metadata=metadata)
            for m in (False, True):
                r = render(zeroed, m)
                lost = {g: base[m][w].sum() - r[w].sum() for g, w in groups.items()}
                print(f"  {'mixed' if m else 'baked'} {name:<6}" + "".join(
                    f"   {g}: {100 * lost[g] / base[m][w].sum():5.1f} {100 * lost[g] / run.mean[w].sum():5.1f}"
                    for g, w in groups.items()), flush=True)


if __name__ == "__main__":
    main()
