"""A suite case's view against the sun split by light (docs/benchmarks.md, "ball-outflow"): the sun alone and the sky
alone, each baked (FINAL, seed 0) and rendered against the core's Monte Carlo, the sun's single scattering exact
(backlit_probe.single_scattering; the rest of the Monte Carlo's sun is its multiple scattering), summed over the
view's pixels that cross optical depth 1, over the rim (total optical depth under 30) and the core.

    PYTHONPATH=build/python python3 bench/backlit_light_split.py [--case ball_issue] [--view 180,0] [--samples 4096]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from backlit_probe import single_scattering


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_issue")
    parser.add_argument("--view", default="180,0", help="azimuth, elevation (deg)")
    parser.add_argument("--samples", type=int, default=4096, help="Monte Carlo paths per pixel")
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    case.views = [tuple(int(x) for x in args.view.split(","))]
    origins, directions, tau = bake_suite.views(case)
    seen = tau >= 1.0
    light = {"sun": dict(suns=case.suns()), "sky": dict(sky=case.skies())}
    baked, mc = {}, {}
    with tempfile.TemporaryDirectory() as folder:
        for name, kw in light.items():
            path = os.path.join(folder, name + ".vdb")
            bake_suite.write_density(path, case.density, case.voxel)
            firncore.bake(path, case.optics, quality="FINAL", seed=0, **kw)
            baked[name] = firncore.render_baked(path, case.optics, origins, directions)[:, 1]
            mc[name] = firncore.monte_carlo_radiance(path, case.optics, origins, directions, samples=args.samples,
                                                     seed=11, **kw)[0][:, 1]
    once = case.sun * np.array([single_scattering(case, o, d) if s else 0.0
                                for o, d, s in zip(origins, directions, seen)])
    print(f"{case.name}, view {args.view}, green, W/m^2/sr summed over the pixels; {args.samples} paths per pixel")
    for label, m in (("all", seen), ("rim (tau < 30)", seen & (tau < 30)), ("core", seen & (tau >= 30))):
        sun, sky = mc["sun"][m].sum(), mc["sky"][m].sum()
        both = (baked["sun"][m] + baked["sky"][m]).sum() / (sun + sky) - 1
        print(f"  {label:<15} {m.sum():3d} pixels: Monte Carlo sun {sun:.4f} (once {once[m].sum():.4f}, more "
              f"{sun - once[m].sum():.4f}), sky {sky:.4f}; baked sun {baked['sun'][m].sum() / sun - 1:+.1%}, sky "
              f"{baked['sky'][m].sum() / sky - 1:+.1%}, both {both:+.1%}")


if __name__ == "__main__":
    main()
