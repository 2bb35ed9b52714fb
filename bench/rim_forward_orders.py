"""The sun leaving a ball's rim towards a camera against the sun, split by scattering order and by where the sun
entered the path (docs/benchmarks.md, rim-forward). Needs the core built with bench/rim_forward_hooks.diff applied
(made on main 009960c; its Monte Carlo part applies on later trees)
(the Monte Carlo's FIRN_MC_GATE; the diff also holds the bake's switches of beamsInRamp that rim-forward tried:
FIRN_RIM_ORDERS, FIRN_RIM_KEEP, FIRN_RIM_ADD, FIRN_RIM_MU, FIRN_RIM_CONVEX): the camera paths' next-event sun is
counted only at collision orders lo..hi whose point (where the sun entered) lies in a radius band about the ball's
centre and a band of its radial cosine to the sun (mu0). Per block: the Monte Carlo's sun alone by order, the "more" (orders >= 2) by entry radius and mu0; the bake's
sun alone, its peaked and broad parts.

    PYTHONPATH=build/python python3 bench/rim_forward_orders.py [--case ball_issue] [--view 180,0]
        [--blocks 58,59,60,61,50,51,52,53,40,41,46,47] [--samples 4096] [--split orders,entry[,outer]]
(outer: the orders of the light entering past the last radius band's start only)
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from backlit_probe import sun_towards, write_without_peaks

ORDERS = [(1, 1), (2, 2), (3, 4), (5, 8), (9, 16), (17, 1 << 40)]


def gated(case, path, origins, directions, samples, lo, hi, rlo=0.0, rhi=1e9, mlo=-2.0, mhi=2.0):
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    s = sun_towards()
    os.environ["FIRN_MC_GATE"] = " ".join(str(v) for v in [lo, hi, *centre, rlo, rhi, mlo, mhi, *s])
    try:
        m, e = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                             samples=samples, seed=31)
    finally:
        del os.environ["FIRN_MC_GATE"]
    return m[:, 1], e[:, 1]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_issue")
    parser.add_argument("--view", default="180,0")
    parser.add_argument("--blocks", default="58,59,60,61,50,51,52,53,40,41,46,47")
    parser.add_argument("--samples", type=int, default=4096)
    parser.add_argument("--radii", default="0,4.0,4.5,4.8,5.0,5.3,99", help="entry radius bands, cm")
    parser.add_argument("--mu0", default="-2,0,0.3,2", help="entry mu0 bands")
    parser.add_argument("--split", default="orders,entry")
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    origins, directions, _ = bake_suite.views(case)
    view = case.views.index(tuple(int(x) for x in args.view.split(",")))
    blocks = [int(b) for b in args.blocks.split(",")]
    pick = [view * case.pixels ** 2 + b for b in blocks]
    o, d = origins[pick], directions[pick]
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "sun.vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        firncore.bake(path, case.optics, suns=case.suns(), quality="FINAL", seed=0)
        baked = firncore.render_baked(path, case.optics, o, d)[:, 1]
        write_without_peaks(path, path + ".broad.vdb")
        broad = firncore.render_baked(path + ".broad.vdb", case.optics, o, d)[:, 1]
        whole, err = gated(case, path, o, d, args.samples, 1, 1 << 40)
        print(f"{case.name} view {args.view}, the sun alone, {args.samples} paths; blocks {blocks}")
        fmt = lambda xs: " ".join(f"{x:7.4f}" for x in xs)
        print(f"{'MC sun':24s}{fmt(whole)}   sum {whole.sum():.4f} (+- {np.sqrt((err ** 2).sum()):.4f})")
        print(f"{'baked sun':24s}{fmt(baked)}   sum {baked.sum():.4f} ({baked.sum() / whole.sum() - 1:+.1%})")
        print(f"{'  its peak':24s}{fmt(baked - broad)}   sum {(baked - broad).sum():.4f}")
        print(f"{'  its broad':24s}{fmt(broad)}   sum {broad.sum():.4f}")
        print(f"{'baked/MC - 1':24s}" + " ".join(f"{b / w - 1:+7.0%}" for b, w in zip(baked, whole)))
        outer = float(args.radii.split(",")[-2]) / 100 if "outer" in args.split else 0.0
        if "orders" in args.split:
            for lo, hi in ORDERS:
                m, _ = gated(case, path, o, d, args.samples, lo, hi, rlo=outer)
                name = f"order {lo}" + (f"-{hi}" if hi != lo and hi < 1 << 40 else "+" if hi != lo else "")
                print(f"{name:24s}{fmt(m)}   sum {m.sum():.4f} ({m.sum() / whole.sum():.1%})")
        if "entry" in args.split:
            radii = [float(r) / 100 for r in args.radii.split(",")]
            mus = [float(m) for m in args.mu0.split(",")]
            for mlo, mhi in zip(mus, mus[1:]):
                for rlo, rhi in zip(radii, radii[1:]):
                    m, _ = gated(case, path, o, d, args.samples, 2, 1 << 40, rlo, rhi, mlo, mhi)
                    name = f"more r {rlo * 100:.1f}-{min(rhi * 100, 99):.1f} mu0 {max(mlo, -1):.1f}-{min(mhi, 1):.1f}"
                    print(f"{name:24s}{fmt(m)}   sum {m.sum():.4f} ({m.sum() / whole.sum():.1%})")


if __name__ == "__main__":
    main()
