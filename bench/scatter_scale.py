"""The firn_scatter grid's voxel size against what it renders (docs/benchmarks.md, scatter-coarse): each of the
suite's cases baked (FINAL, seed 0), then rendered as Cycles renders the mixed material (render_scattering_where_thin
with the bake's rule B: the density of the traced voxels of sigma_t h < 2) with the scattered density read from the
density's own voxels (scale 1) and from voxels `--scales` times as large (the bake's: firncore.SCATTER_SCALE), the
same seed each time, and the noise: scale 1 again with another seed. Per scale against scale 1, over the blocks the
suite scores (optical depth >= 1): the mean |relative difference| and the bias, all and per view; and the grid's
box as Cycles would hold it (4 bytes a voxel) at each scale. Needs no cached reference.

    PYTHONPATH=build/python /usr/bin/python3 bench/scatter_scale.py [--cases a,b] [--samples 1024] [--scales 2]
"""

import argparse
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import bake_suite  # noqa: E402
import firncore  # noqa: E402


def share_box(voxels, scale):
    """The voxels of the grid's bounding box at `scale` (the coarse voxels J within `scale` voxels of a scattered
    voxel v: |v - scale J| <= scale, as core scatteredDensity writes them)."""
    low = -(-voxels.min(axis=0) // scale) - 1
    high = voxels.max(axis=0) // scale + 1
    return int(np.prod(high - low + 1))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="ball_forward,spray_lumps,spray_dense,ball_rgb,ball_issue")
    parser.add_argument("--samples", type=int, default=1024, help="paths per camera ray")
    parser.add_argument("--scales", default=str(firncore.SCATTER_SCALE))
    args = parser.parse_args()
    print(f"firncore {firncore.__version__}; {args.samples} paths per ray; against the shares on the density's voxels: "
          "mean |difference|, bias, per-view bias; the share's box")
    with tempfile.TemporaryDirectory() as folder:
        for name in args.cases.split(","):
            c = bake_suite.case(name)
            path = os.path.join(folder, name + ".vdb")
            bake_suite.write_density(path, c.density, c.voxel)
            firncore.bake(path, c.optics, suns=c.suns(), sky=c.skies(), occluders=c.occluders, quality="FINAL",
                          seed=0)
            origins, directions, tau = bake_suite.views(c)
            seen = tau >= 1.0
            voxels = firncore.scatter_voxels(path, c.optics, occluders=c.occluders)
            if len(voxels) == 0:
                print(f"{name}: no voxel scatters")
                continue

            def render(scale, seed=5):
                return firncore.render_scattering_where_thin(
                    path, c.optics, origins, directions, suns=c.suns(), sky=c.skies(), occluders=c.occluders,
                    samples=args.samples, seed=seed, traced_only=True, scatter_scale=scale)[0]

            fine = render(1)
            print(f"{name}: {len(voxels)} share-1 voxels, box {share_box(voxels, 1):,} voxels "
                  f"({4e-3 * share_box(voxels, 1):.1f} kB)")
            per = c.pixels ** 2

            def compare(label, estimate, box):
                relative = estimate[seen] / np.maximum(fine[seen], 1e-30) - 1.0
                views = []
                for v in range(len(c.views)):
                    part = slice(v * per, (v + 1) * per)
                    views.append(estimate[part][seen[part]].sum() / fine[part][seen[part]].sum() - 1.0)
                bias = estimate[seen].sum() / fine[seen].sum() - 1.0
                print(f"  {label:<14} {100 * np.abs(relative).mean():5.2f} %  bias {100 * bias:+6.2f} %  views "
                      + " ".join(f"{100 * b:+5.1f}" for b in views)
                      + f"   box {box:,} voxels ({4e-3 * box:.1f} kB, {box / share_box(voxels, 1):.3f} of the fine)",
                      flush=True)

            compare("x1, seed 6", render(1, seed=6), share_box(voxels, 1))
            for scale in [int(x) for x in args.scales.split(",")]:
                compare(f"x{scale}", render(scale), share_box(voxels, scale))

if __name__ == "__main__":
    main()
