"""A suite case's volume baked on voxels N times finer (docs/benchmarks.md, lead-88): its density resampled trilinearly at
h / N, which is the same field exactly (trilinear interpolation reproduces a trilinear field on cells nested in the
coarse ones), so the case's own views and cached Monte Carlo reference still hold; only the bake's grid changes. The
one-voxel density ramp of the case's surface (bake_suite.ball) becomes N voxels wide: a snow layer's or a spray's own
ramp is one voxel at any voxel size (docs/vdb-contract.md), so this measures how the bake depends on the ramp's width
in voxels, not a case users make.

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/finer_voxels.py [--cases ball_grey,ball_rgb] [--factor 2]
        [--mixed 32768] [--brute-force 32] [--maps]

--mixed: paths per block of the mixed render (the renderer scattering in the bake's traced thin voxels, as
bake_suite.py renders it; 0: the baked form alone). --brute-force B: the refined volume also rendered by the renderer
scattering everywhere with at most B volume bounces, at --mixed paths (no baked light at all): it meets the coarse
reference within its noise where B is enough, the check that the volume is the same. --maps: per view, each block's
render / reference - 1 (green), as bake_suite.py --maps lays it out.
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import firncore


def refined(density, factor):
    """`density` sampled trilinearly at every 1 / factor voxel: (n - 1) * factor + 1 voxels per axis, voxel i of the
    result at index-space point i / factor of the original."""
    shape = (np.array(density.shape) - 1) * factor + 1
    points = np.stack(np.meshgrid(*[np.arange(m) / factor for m in shape], indexing="ij"), -1).reshape(-1, 3)
    return bake_suite.trilinear(density, points).reshape(shape)


def renders(case, path, origins, directions, mixed, brute_force):
    """The refined bake's renders along the case's rays, by form."""
    out = {"baked": firncore.render_baked(path, case.optics, origins, directions, occluders=case.occluders)}
    if mixed:
        out["mixed"] = bake_suite.mixed_render(case, path, origins, directions, mixed, 1000, out["baked"])[0]
    if brute_force:
        out[f"brute force, {brute_force} bounces"] = firncore.render_scattering_where_thin(
            path, case.optics, origins, directions, samples=mixed or 4096, seed=2000, thin_depth=float("inf"),
            bounces=brute_force, traced_only=False, suns=case.suns(), sky=case.skies(),
            occluders=case.occluders)[0]
    return out


def run(case, factor, folder, cache, mixed, brute_force, maps):
    coarse, fine = os.path.join(folder, "coarse.vdb"), os.path.join(folder, "fine.vdb")
    bake_suite.write_density(coarse, case.density, case.voxel)
    origins, directions, tau = bake_suite.views(case)
    mean, _, _ = bake_suite.reference(case, coarse, origins, directions, cache)
    bake_suite.write_density(fine, refined(case.density, factor), case.voxel / factor)
    stats = firncore.bake(fine, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                          quality="FINAL", seed=0)
    seen = tau >= 1.0
    tau_voxel = case.sigma_t * case.voxel / factor
    print(f"{case.name} on voxels {factor}x finer (sigma_t h {tau_voxel:.2f} at the case's density, "
          f"{stats['traced_voxels']} traced voxels):", flush=True)
    for form, render in renders(case, fine, origins, directions, mixed, brute_force).items():
        s = bake_suite.scored(case, render, mean, seen)
        print(f"  {form}: mean {100 * s['mean']:.2f} %, worst {100 * s['worst_signed']:+.0f} %, bias "
              f"{100 * s['bias']:+.2f} %; per view: " +
              ", ".join(f"{v} {100 * b:+.1f} %" for v, b in zip(case.views, s["view_bias"])), flush=True)
        if maps:
            bake_suite.print_view_maps(case, s["relative"][:, 1], seen)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="ball_grey,ball_rgb")
    parser.add_argument("--factor", type=int, default=2, help="voxels per original voxel along each axis")
    parser.add_argument("--cache", default=bake_suite.CACHE, help="folder caching the Monte Carlo reference per case")
    parser.add_argument("--mixed", type=int, default=bake_suite.MIXED_PATHS)
    parser.add_argument("--brute-force", type=int, default=0, help="volume bounces (0: not rendered)")
    parser.add_argument("--maps", action="store_true")
    args = parser.parse_args()
    if args.factor < 1:
        parser.error("--factor must be at least 1")
    os.makedirs(args.cache, exist_ok=True)
    for name in args.cases.split(","):
        with tempfile.TemporaryDirectory() as folder:
            run(bake_suite.case(name), args.factor, folder, args.cache, args.mixed, args.brute_force, args.maps)


if __name__ == "__main__":
    main()
