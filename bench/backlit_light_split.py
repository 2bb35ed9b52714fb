"""A suite case's view against the sun split by light (docs/benchmarks.md, "ball-outflow", "ball-back"): the sun alone
and the sky alone, each baked (FINAL, seed 0) and rendered against the core's Monte Carlo, the sun's single scattering
exact (backlit_probe.single_scattering; the rest of the Monte Carlo's sun is its multiple scattering), the baked sun's
peaked lobes' part apart (its grids firn_source_peak* cleared); with --orders, the Monte Carlo's sun by order of
scattering (render_scattering_where_thin scattering everywhere, no baked emission, at most that many bounces after the
first scattering: 0 is single scattering, the exact one's check), summed over the view's pixels that cross optical depth
1: all, the rim (total optical depth under 30) and the core, and for a ball's view (180, 0) by against_sun.py's bands
(the ball's normal at the ray's optical depth 1 point: lit limb, terminator, dark limb, dark face; rim or core).

    PYTHONPATH=build/python:bench python3 bench/backlit_light_split.py [--case ball_issue] [--view 180,0]
        [--samples 4096] [--orders 0,1,2,4] [--sharp] [--maps] [--sun-azimuth 0]

--sharp: the case's density thresholded at half its largest value (a staircase ball, no antialiased skin), both for
the bake and the Monte Carlo: how much of the view's deficit the soft skin holds.
--maps: per pixel, baked / Monte Carlo - 1 for the sun (with and without its peaked lobes) and the sky, as
bake_suite.py --maps lays the view out. --sun-azimuth: the case's sun turned about the vertical by that many degrees
(from +x towards +y), so the terminator moves off the ball's +y pole (docs/benchmarks.md, lead-87); the sun's exact
single scattering ("once", nan) and the limb bands, which are the case's own sun's, are then left out.
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from against_sun import limb_bands
from backlit_probe import single_scattering, write_without_peaks


def turned(suns, degrees):
    """`suns` turned about the vertical (z) by `degrees`, from +x towards +y."""
    a = math.radians(degrees)
    out = []
    for sun in suns:
        x, y, z = sun.direction
        out.append(firncore.SunLight((x * math.cos(a) - y * math.sin(a), x * math.sin(a) + y * math.cos(a), z),
                                     tuple(sun.irradiance), sun.angular_diameter))
    return out


def print_maps(case, seen, errors):
    """Each light's per-pixel relative error, laid out as bake_suite.py --maps does (nan: the pixel is left out)."""
    for name, error in errors.items():
        print(f"  baked / Monte Carlo - 1, {name}:")
        print(bake_suite.view_map(case, np.where(seen, error, np.nan)))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_issue")
    parser.add_argument("--view", default="180,0", help="azimuth, elevation (deg)")
    parser.add_argument("--samples", type=int, default=4096, help="Monte Carlo paths per pixel")
    parser.add_argument("--orders", default="", help="bounces after the first scattering, e.g. 0,1,2,4")
    parser.add_argument("--sharp", action="store_true", help="the density thresholded at half its largest value")
    parser.add_argument("--maps", action="store_true", help="per pixel baked / Monte Carlo - 1, sun and sky")
    parser.add_argument("--sun-azimuth", type=float, default=0.0, help="the sun turned about the vertical (deg)")
    args = parser.parse_args()
    bounces = [int(b) for b in args.orders.split(",") if b]
    case = bake_suite.case(args.case)
    case.views = [tuple(int(x) for x in args.view.split(","))]
    if args.sharp:
        case.density = np.where(case.density >= 0.5 * case.density.max(), case.density.max(), 0.0)
    origins, directions, tau = bake_suite.views(case)
    seen = tau >= 1.0
    light = {"sun": dict(suns=turned(case.suns(), args.sun_azimuth)), "sky": dict(sky=case.skies())}
    baked, mc = {}, {}
    with tempfile.TemporaryDirectory() as folder:
        for name, kw in light.items():
            path = os.path.join(folder, name + ".vdb")
            bake_suite.write_density(path, case.density, case.voxel)
            firncore.bake(path, case.optics, quality="FINAL", seed=0, **kw)
            baked[name] = firncore.render_baked(path, case.optics, origins, directions)[:, 1]
            mc[name] = firncore.monte_carlo_radiance(path, case.optics, origins, directions, samples=args.samples,
                                                     seed=11, **kw)[0][:, 1]
            if name == "sun":
                write_without_peaks(path, path + ".broad.vdb")
                broad = firncore.render_baked(path + ".broad.vdb", case.optics, origins, directions)[:, 1]
                upto = {b: firncore.render_scattering_where_thin(path, case.optics, origins, directions, samples=args.samples,
                                                                 seed=11, thin_depth=1e30, bounces=b, **kw)[0][:, 1]
                        for b in bounces}
    # The exact single scattering and the limb bands are the case's own sun's: not shown for a turned one.
    turned_sun = args.sun_azimuth != 0.0
    once = np.full(len(seen), np.nan) if turned_sun else case.sun * np.array(
        [single_scattering(case, o, d) if s else 0.0 for o, d, s in zip(origins, directions, seen)])
    regions = [("all", "", seen), ("rim (tau < 30)", "", seen & (tau < 30)), ("core", "", seen & (tau >= 30))]
    split = None if turned_sun else limb_bands(case, origins, directions, tau)
    if split is not None:
        regions += [(what, label, k) for what, label, k, _, _ in split[2] if k.sum()]
    print(f"{case.name}, view {args.view}, green, W/m^2/sr summed over the pixels; {args.samples} paths per pixel")
    print("  region               pixels | Monte Carlo: sun (once, more)          sky    | baked: sun (peaked)       "
          "sky     | baked / MC: sun   sky   both  | missing: sun    sky")
    for what, label, m in regions:
        sun, sky, sun_b, sky_b = mc["sun"][m].sum(), mc["sky"][m].sum(), baked["sun"][m].sum(), baked["sky"][m].sum()
        print(f"  {what + ' ' + label:<20} {m.sum():4d}   | {sun:.4f} ({once[m].sum():.4f}, {sun - once[m].sum():.4f})  "
              f"{sky:.4f} | {sun_b:.4f} ({sun_b - broad[m].sum():.4f})  {sky_b:.4f} | "
              f"{sun_b / sun - 1:+6.1%} {sky_b / sky - 1:+6.1%} {(sun_b + sky_b) / (sun + sky) - 1:+6.1%} | "
              f"{sun - sun_b:+.4f} {sky - sky_b:+.4f}")
    if args.maps:
        with np.errstate(divide="ignore", invalid="ignore"):  # pixels the sun does not reach
            print_maps(case, seen, {"sun": baked["sun"] / mc["sun"] - 1,
                                    "sun without its peaked lobes": broad / mc["sun"] - 1,
                                    "sky": baked["sky"] / mc["sky"] - 1})
    if bounces:
        print("  the Monte Carlo's sun by order: the share of all orders in orders 1..n (n = bounces + 1), then the "
              "baked sun's share")
        for what, label, m in regions:
            sun = mc["sun"][m].sum()
            print(f"  {what + ' ' + label:<20} " + "  ".join(f"<={b + 1}: {upto[b][m].sum() / sun:5.3f}" for b in bounces)
                  + f"  baked {baked['sun'][m].sum() / sun:5.3f} (peaked {(baked['sun'][m] - broad[m]).sum() / sun:5.3f})")


if __name__ == "__main__":
    main()
