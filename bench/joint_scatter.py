"""How much snow the renderer scatters in a joint bake's outputs (docs/vdb-contract.md, "Objects baked as one
medium"): bench/spray_light_bench.py's ski spray (the last of 12 frames, tracked snow and lumps) baked with
firncore.bake_joint, each output drawn with its own density and its own firn_scatter (min(ρᵢ, ρ_s,ᵢ) kg/m³ at a
point), summed over the points within reach of the union's scattered voxels (every half voxel of the coarse voxels
the union's firn_scatter holds), against the union baked alone (firncore.union_density, then bake: min(ρ, ρ_s)),
and against each output drawing the union's scattered density over its own (the rule before stop 96).

PYTHONPATH=build/python:bench /usr/bin/python3 bench/joint_scatter.py [--quality DRAFT]
"""

import argparse
import os
import tempfile

import numpy as np
import pyopenvdb

import firncore
import spray_light_bench as spray_bench


def reach_points(lit_union, union):
    """World points (N, 3) every half density voxel over the union's coarse scatter voxels' cells."""
    coarse = pyopenvdb.read(lit_union, firncore.SCATTER_GRID_NAME)
    density = pyopenvdb.read(union, "density")
    scale = firncore.SCATTER_SCALE
    offsets = np.array(list(np.ndindex(4, 4, 4))) / 2.0 - 1.0  # density voxels within one of the cell's corner
    points = set()
    for it in coarse.citerOnValues():
        if it.count != 1:
            raise ValueError("a tile in the scatter grid: not written by a bake")
        for o in offsets:
            points.add(density.transform.indexToWorld(tuple(float(v) for v in scale * np.array(it.min) + o)))
    return np.array(sorted(points), np.float32)


def scattered(path, vdb, points):
    """min(ρ, ρ_s) at the points (kg/m³): ρ of `vdb`, ρ_s of `path`'s firn_scatter (0 without one)."""
    rho = firncore.sample_grid(vdb, "density", points)
    if firncore.SCATTER_GRID_NAME not in firncore.grid_names(path):
        return np.zeros(len(points)), rho
    return np.minimum(rho, firncore.sample_grid(path, firncore.SCATTER_GRID_NAME, points)), rho


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quality", default="DRAFT")
    args = parser.parse_args()
    light = dict(suns=spray_bench.SUNS, sky=spray_bench.SKY, quality=args.quality)
    with tempfile.TemporaryDirectory() as folder:
        objects = spray_bench.ski_spray(folder, firncore.SpraySettings(seed=5))
        outputs = [os.path.join(folder, f"lit_{i}.vdb") for i in range(len(objects))]
        firncore.bake_joint(list(objects), outputs, spray_bench.OPTICS, **light)
        union, lit_union = os.path.join(folder, "union.vdb"), os.path.join(folder, "lit_union.vdb")
        firncore.union_density(list(objects), union)
        firncore.bake(union, spray_bench.OPTICS, output_path=lit_union, **light)
        points = reach_points(lit_union, union)
        alone, _ = scattered(lit_union, union, points)
        now, before = np.zeros(len(points)), np.zeros(len(points))
        union_share = firncore.sample_grid(lit_union, firncore.SCATTER_GRID_NAME, points)
        for vdb, out in zip(objects, outputs):
            own, rho = scattered(out, vdb, points)
            now += own
            before += np.minimum(rho, union_share)
        print(f"{len(points)} points within reach of the union's scattered voxels; scattered density summed (kg/m³):")
        for name, values in (("the union alone", alone), ("outputs now", now), ("outputs before", before)):
            over = int((values > 1.01 * alone + 1e-3).sum())
            under = int((values < 0.99 * alone - 1e-3).sum())
            print(f"  {name:15s} {values.sum():10.1f}   points over the union's by > 1 %: {over:5d}, under: {under:5d}")


if __name__ == "__main__":
    main()
