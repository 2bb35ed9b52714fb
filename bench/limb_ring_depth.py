"""Where along a ball's limb-ring rays seen against the sun the bake misses the sun's light (docs/benchmarks.md,
ball-back).

bench/bake_suite.py's case, its view (180, 0), the rays of against_sun.py's bands (the ball's normal at the ray's
optical depth 1 point: lit limb, terminator, dark limb; rim: total optical depth under 30): each ray restarted at the
camera-side optical depths DEPTHS (trilinear density, as the renderer's), the sun alone, baked (FINAL, seed 0) and
rendered from each start against the core's Monte Carlo from the same start. The light scattered within one depth
segment [a, b) and seen at a is L(a) - exp(-(b - a)) L(b), the Monte Carlo's and the bake's; summed over the band's rays.
Divided by the segment's own opacity 1 - exp(-(b - a)) it is the mean source seen there (W/m^2/sr). Where the
deficit lies in the first segments it is the density ramp's (the trilinear density's fall into the air voxel), where
it lies deeper the solid skin's. With --orders the Monte Carlo's segments by order of scattering too
(backlit_light_split.py's --orders: render_scattering_where_thin scattering everywhere, at most that many bounces after
the first scattering), and the bake's segments without its peaked lobes (grids firn_source_peak* cleared).

    PYTHONPATH=build/python:bench python3 bench/limb_ring_depth.py [--case ball_snow] [--samples 4096] [--orders 0,1,3]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite as S
import firncore
from against_sun import limb_bands
from backlit_probe import write_without_peaks

DEPTHS = (0.0, 0.5, 1.0, 2.0, 4.0, 8.0)  # camera-side optical depths where the rays restart


def restarts(case, origin, direction):
    """The points along a camera ray where its optical depth reaches DEPTHS, and the density (of full) there."""
    steps = np.arange(0.0, 2.0, case.voxel / 64)
    rho = S.trilinear(case.density, (origin + steps[:, None] * direction) / case.voxel)
    tau = np.concatenate([[0.0], np.cumsum(rho[:-1] * np.diff(steps))]) * case.sigma_t / case.rho
    at = [min(np.searchsorted(tau, d), len(steps) - 1) for d in DEPTHS]
    return origin + steps[at, None] * direction, rho[at] / case.density.max()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_snow")
    parser.add_argument("--samples", type=int, default=4096)
    parser.add_argument("--orders", default="", help="bounces after the first scattering, e.g. 0,1,3")
    args = parser.parse_args()
    bounces = [int(b) for b in args.orders.split(",") if b]
    case = S.case(args.case)
    case.views = [(180, 0)]
    origins, directions, tau = S.views(case)
    _, _, bands = limb_bands(case, origins, directions, tau)
    chosen = [(what, label, k) for what, label, k, _, _ in bands if k.sum() and what != "dark face"]
    rays = np.concatenate([np.nonzero(k)[0] for _, _, k in chosen])
    starts, fills = zip(*(restarts(case, origins[i], directions[i]) for i in rays))
    o = np.concatenate(starts)
    d = np.repeat(directions[rays], len(DEPTHS), axis=0)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "sun.vdb")
        S.write_density(path, case.density, case.voxel)
        firncore.bake(path, case.optics, quality="FINAL", seed=0, suns=case.suns())
        baked = firncore.render_baked(path, case.optics, o, d)[:, 1].reshape(len(rays), len(DEPTHS))
        mc = firncore.monte_carlo_radiance(path, case.optics, o, d, suns=case.suns(), samples=args.samples,
                                           seed=13)[0][:, 1].reshape(len(rays), len(DEPTHS))
        parts = {f"MC orders <={b + 1}": firncore.render_scattering_where_thin(
            path, case.optics, o, d, suns=case.suns(), samples=args.samples, seed=13, thin_depth=1e30,
            bounces=b)[0][:, 1].reshape(len(rays), len(DEPTHS)) for b in bounces}
        if bounces:
            write_without_peaks(path, path + ".broad.vdb")
            parts["baked broad"] = firncore.render_baked(path + ".broad.vdb", case.optics, o, d)[:, 1].reshape(
                len(rays), len(DEPTHS))
    fills = np.array(fills)
    attenuation = np.exp(-np.diff(DEPTHS))
    print(f"{case.name}, view (180, 0), the sun alone, green; per band: from each start the Monte Carlo / baked "
          f"(baked / MC - 1), then per segment [a, b) its own light MC / baked; {args.samples} paths per ray")
    at = 0
    for what, label, k in chosen:
        n = int(k.sum())
        m, b, f = mc[at:at + n], baked[at:at + n], fills[at:at + n]
        part = {key: v[at:at + n] for key, v in parts.items()}
        at += n
        print(f"  {what} {label} ({n} rays), density at the starts (of full): "
              + " ".join(f"{x:.2f}" for x in f.mean(0)))
        print("    from   " + "  ".join(f"{t:>3}: {m[:, j].sum():.4f} / {b[:, j].sum():.4f} "
                                       f"({b[:, j].sum() / max(m[:, j].sum(), 1e-12) - 1:+6.1%})" for j, t in enumerate(DEPTHS)))
        sm = m[:, :-1] - attenuation * m[:, 1:]
        sb = b[:, :-1] - attenuation * b[:, 1:]
        print("    segs   " + "  ".join(f"{a}-{c}: {sm[:, j].sum():.4f} / {sb[:, j].sum():.4f}"
                                       for j, (a, c) in enumerate(zip(DEPTHS[:-1], DEPTHS[1:]))))
        opacity = 1 - attenuation
        print("    source " + "  ".join(f"{a}-{c}: {sm[:, j].sum() / opacity[j] / n:.4f} / {sb[:, j].sum() / opacity[j] / n:.4f}"
                                       for j, (a, c) in enumerate(zip(DEPTHS[:-1], DEPTHS[1:]))))
        for key, v in part.items():
            s = v[:, :-1] - attenuation * v[:, 1:]
            print(f"    {key:<16}" + "  ".join(f"{a}-{c}: {s[:, j].sum():.4f}"
                                               for j, (a, c) in enumerate(zip(DEPTHS[:-1], DEPTHS[1:]))))


if __name__ == "__main__":
    main()
