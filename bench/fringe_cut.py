"""What the balls' fringe (their partly filled voxels below a fill) brings the bake and the truth under the sky alone
(docs/benchmarks.md, "ball-outflow").

Per case and cut: the case's density with the voxels below cut x its full density cleared, baked (FINAL, seed 0) and
rendered against the core's Monte Carlo under a uniform sky alone (0.05 W/m^2/sr) on one orthographic view (180, 0)
of 32 x 32 pixels over the ball: the Monte Carlo's summed radiance per channel and the bake's relative error. The
fringe's worth is the ratio of the uncut to the cut sum, the bake's against the Monte Carlo's.

    PYTHONPATH=build/python python3 bench/fringe_cut.py [--cases ball_issue,ball_grey] [--cuts 0,0.25,0.5,0.75]
        [--samples 1024]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import firncore

SKY = 0.05  # W/m^2/sr
PIXELS = 32


def view(density, voxel):
    """Orthographic rays from -x along +x over the snow's extent: the suite's view (180, 0)."""
    centre = (np.array(density.shape) - 1) / 2 * voxel
    filled = np.argwhere(density > 0)
    half = 0.55 * np.max((filled.max(0) - filled.min(0) + 1) * voxel)
    s = ((np.arange(PIXELS) + 0.5) / PIXELS * 2.0 - 1.0) * half
    along = np.array([1.0, 0.0, 0.0])
    origins = np.array([centre - 3.0 * half * along + np.array([0.0, u, v]) for v in s for u in s])
    return origins, np.tile(along, (len(origins), 1))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="ball_issue,ball_grey,ball_sky,ball_rgb")
    parser.add_argument("--cuts", default="0,0.5", help="fills below which voxels are cleared")
    parser.add_argument("--samples", type=int, default=1024, help="Monte Carlo paths per pixel")
    args = parser.parse_args()
    sky = firncore.Sky((SKY,) * 3)
    for name in args.cases.split(","):
        case = bake_suite.case(name)
        for cut in (float(x) for x in args.cuts.split(",")):
            density = case.density.copy()
            density[density < cut * case.rho] = 0.0
            origins, directions = view(density, case.voxel)
            with tempfile.TemporaryDirectory() as folder:
                path = os.path.join(folder, "cut.vdb")
                bake_suite.write_density(path, density, case.voxel)
                firncore.bake(path, case.optics, sky=sky, quality="FINAL", seed=0)
                baked = firncore.render_baked(path, case.optics, origins, directions)
                mc, error = firncore.monte_carlo_radiance(path, case.optics, origins, directions, sky=sky,
                                                          samples=args.samples, seed=5)
            total = mc.sum(0)
            print(f"{name} cut {cut:g}: Monte Carlo " + " ".join(f"{x:.3f}" for x in total) + " W/m^2/sr summed; "
                  "baked / Monte Carlo - 1: " + " ".join(f"{x:+.2%}" for x in baked.sum(0) / total - 1.0)
                  + f" (standard error {np.sqrt((error[:, 1] ** 2).sum()) / total[1]:.2%})", flush=True)


if __name__ == "__main__":
    main()
