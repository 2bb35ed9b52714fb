"""bumpy_plate's blocks by the kind of snow their camera ray meets (docs/benchmarks.md, bumpy-blocks).

Bakes bumpy_plate with seeds 0..N-1 against the suite's cached reference (bench/bake_suite.py) and sorts the seen
blocks by where the ray reaches optical depth 1 (bench/edge_blocks.py's points): on a cut side of the layer (within
half a voxel of the grid's x or y ends), under the plate's footprint, on the top within 3 voxels of a cut side, or on
the open top; the top by the bump's phase
(crest: the height's wave over +1/2 of its amplitude, trough: under -1/2, else slope) and by the top's normal
there (the height field's, bench/bake_suite.bumpy_top): lit (the sun over the local horizon) or in the bump's own
shadow, and the camera's incidence on it. Per kind: blocks, share of the suite's mean (|error| summed over the
three channels, as the suite's mean is), mean signed error of the seeds' mean render (bias) and of one seed, the
seeds' spread; then the top's blocks' error against cos(sun, normal) and cos(camera, normal) (least squares).

With --uncut the same blocks of a layer that does not end: the layer continued by one wavelength beyond each cut side
(whole wavelengths: the same bumps under the same rays, the rays and the plate shifted with it), its own Monte Carlo
(4096 paths, kept in --uncut-cache), seed 0's bias and mean |error| per kind beside the cut layer's.

    PYTHONPATH=build/python:bench python3 bench/bumpy_blocks.py [--seeds 4] [--list] [--uncut]
"""

import argparse
import copy
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore

AMPLITUDE, DEPTH = 3.0, 6.0  # voxels: bake_suite's bumpy(30, 6, 3)


def top_normal(x, y):
    """Unit normal of the bumpy top over (x, y) (voxels; the height field's gradient)."""
    kx, ky = 2 * np.pi / bake_suite.BUMPS[0], 2 * np.pi / bake_suite.BUMPS[1]
    dx = AMPLITUDE * kx * np.cos(kx * x) * np.cos(ky * y)
    dy = -AMPLITUDE * ky * np.sin(kx * x) * np.sin(ky * y)
    n = np.stack([-dx, -dy, np.ones_like(x)], -1)
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def kinds(case, hits):
    """Per hit point (m): its kind (cut side, under plate, near cut side, top) and the bump's phase there."""
    p = hits / case.voxel
    last = case.density.shape[0] - 1
    plate = case.occluders[0][0]
    phase = (bake_suite.bumpy_top(p[:, 0], p[:, 1], DEPTH, AMPLITUDE) - DEPTH) / AMPLITUDE
    inward = np.minimum(np.minimum(p[:, 0], last - p[:, 0]), np.minimum(p[:, 1], last - p[:, 1]))  # voxels
    side = inward < 0.5
    under = ((hits[:, 0] > plate[:, 0].min()) & (hits[:, 0] < plate[:, 0].max()) &
             (hits[:, 1] > plate[:, 1].min()) & (hits[:, 1] < plate[:, 1].max()))
    out = np.where(side, "cut side", np.where(under, "under plate", np.where(inward < 3.0, "near cut side", "top")))
    return out.astype(object), phase


def uncut_case(case):
    """The case's layer continued by one wavelength beyond each cut side, and the shift (m) of the old grid in it."""
    shift = np.array(bake_suite.BUMPS + (0.0,))
    n = np.array(case.density.shape) + 2 * shift.astype(int)
    X, Y, Z = bake_suite.grid(tuple(n))
    fill = np.clip(bake_suite.bumpy_top(X, Y, DEPTH, AMPLITUDE) - Z + 0.5, 0.0, 1.0)  # bake_suite.bumpy's rule
    fill[:, :, 0] = 0.0
    out = copy.copy(case)
    out.density = fill * case.rho
    offset = shift * case.voxel
    out.occluders = [(v + offset, t, a) for v, t, a in case.occluders]
    return out, offset


def uncut(case, origins, directions, seen, cache):
    """Seed 0's render of the continued layer over its own Monte Carlo along the shifted rays (seen blocks x 3)."""
    wide, offset = uncut_case(case)
    o, d = origins[seen] + offset, directions[seen]
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "uncut.vdb")
        bake_suite.write_density(path, wide.density, wide.voxel)
        os.makedirs(cache, exist_ok=True)
        mean, _, _ = bake_suite.cached_monte_carlo(os.path.join(cache, "uncut_4096.npz"), wide, path, o, d, 4096, 11)
        firncore.bake(path, wide.optics, suns=wide.suns(), sky=wide.skies(), occluders=wide.occluders,
                      quality="FINAL", seed=0)
        baked = firncore.render_baked(path, wide.optics, o, d, occluders=wide.occluders)
    return baked / mean - 1.0


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--list", action="store_true", help="every block over 10 %%")
    parser.add_argument("--cache", default=bake_suite.CACHE)
    parser.add_argument("--uncut", action="store_true", help="the same blocks on a layer that does not end")
    parser.add_argument("--uncut-cache", default=os.path.join(tempfile.gettempdir(), "firn_bumpy_uncut"))
    args = parser.parse_args()
    case = bake_suite.case("bumpy_plate")
    origins, directions, tau = bake_suite.views(case)
    seen = tau >= 1.0
    with tempfile.TemporaryDirectory() as folder:
        runs = [bake_suite.run_case(case, folder, args.cache, seed=seed) for seed in range(args.seeds)]
    relative = np.array([r["relative"] for r in runs])  # seeds x seen blocks x channels
    bias = relative.mean(0).mean(1)  # the seeds' mean render, channels averaged
    one = relative[0].mean(1)
    spread = relative.mean(2).std(0, ddof=1) if args.seeds > 1 else np.zeros(seen.sum())
    share = np.abs(relative[0]).mean(1) / seen.sum()  # each block's part of the suite's mean
    hits = bake_suite.depth_one_points(case, origins, directions, seen)[seen]
    kind, phase = kinds(case, hits)
    n = top_normal(hits[:, 0] / case.voxel, hits[:, 1] / case.voxel)
    sun = np.array([math.cos(bake_suite.SUN_ELEVATION), 0.0, math.sin(bake_suite.SUN_ELEVATION)])
    cos_sun = n @ sun
    cos_view = -(n * directions[seen]).sum(1)
    view = np.nonzero(seen)[0] // case.pixels ** 2
    top = kind != "cut side"
    kind[top] = kind[top] + np.where(phase[top] > 0.5, " crest", np.where(phase[top] < -0.5, " trough", " slope"))
    kind[top] = kind[top] + np.where(cos_sun[top] > 0.0, " lit", " self-shadowed")
    print(f"bumpy_plate: seed 0 mean {100 * runs[0]['mean']:.2f} %, {seen.sum()} blocks, {args.seeds} seeds")
    print(f"  {'kind':<34} {'blocks':>6} {'share of mean':>13} {'bias':>7} {'seed 0':>7} {'spread':>6}  per view bias")
    for k in sorted(set(kind), key=lambda k: -share[kind == k].sum()):
        m = kind == k
        views = "  ".join(f"{case.views[v]} {100 * bias[m & (view == v)].mean():+5.1f}" if (m & (view == v)).any()
                          else f"{case.views[v]}   -  " for v in range(len(case.views)))
        print(f"  {k:<34} {m.sum():6d} {100 * share[m].sum():11.2f} % {100 * bias[m].mean():+6.1f}% "
              f"{100 * one[m].mean():+6.1f}% {100 * spread[m].mean():5.1f}%  {views}")
    print(f"  {'all':<34} {seen.sum():6d} {100 * share.sum():11.2f} % {100 * bias.mean():+6.1f}%")
    for v in range(len(case.views)):
        m = top & (view == v)
        a = np.stack([np.ones(m.sum()), cos_sun[m], cos_view[m]], 1)
        c, *_ = np.linalg.lstsq(a, bias[m], rcond=None)
        r = np.corrcoef(np.stack([bias[m], cos_sun[m], cos_view[m]]))
        print(f"  view {case.views[v]} open top and under plate ({m.sum()} blocks): bias ~ {100 * c[0]:+.1f} "
              f"{100 * c[1]:+.1f} cos(sun,n) {100 * c[2]:+.1f} cos(camera,n) %; correlation with cos(sun,n) "
              f"{r[0, 1]:+.2f}, cos(camera,n) {r[0, 2]:+.2f}")
    if args.uncut:
        wide = uncut(case, origins, directions, seen, args.uncut_cache)
        print(f"  uncut layer, seed 0: mean {100 * np.abs(wide).mean():.2f} % (cut: {100 * runs[0]['mean']:.2f} %)")
        print(f"  {'kind (on the cut layer)':<34} {'blocks':>6}  cut: bias, mean |error|   uncut: bias, mean |error|")
        for k in sorted(set(kind), key=lambda k: -share[kind == k].sum()):
            m = kind == k
            print(f"  {k:<34} {m.sum():6d}  {100 * relative[0][m].mean():+6.1f} % {100 * np.abs(relative[0][m]).mean():5.1f} %"
                  f"          {100 * wide[m].mean():+6.1f} % {100 * np.abs(wide[m]).mean():5.1f} %")
    if args.list:
        for i in np.argsort(-np.abs(one)):
            if abs(one[i]) <= 0.10:
                break
            q = np.nonzero(seen)[0][i] % case.pixels ** 2
            print(f"  {str(case.views[view[i]]):<10} row {q // case.pixels} col {q % case.pixels}  {kind[i]:<34} "
                  f"phase {phase[i]:+.2f}  cos sun {cos_sun[i]:+.2f}  cos camera {cos_view[i]:+.2f}  "
                  f"seed 0 {100 * one[i]:+6.1f} %  bias {100 * bias[i]:+6.1f} %  spread {100 * spread[i]:.1f} %")


if __name__ == "__main__":
    main()
