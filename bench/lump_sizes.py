"""The suite's pieces of snow that the renderer could scatter whole (docs/benchmarks.md, spray-lumpscatter): per case
its pieces (connected through faces, edges and corners, as bake_thin_snow.cpp's pieceAround; spray_thick_probe.lumps),
and those of at most 343 voxels (a small piece, traced whole) holding a voxel of sigma_t h >= 2 with their voxels, the
sum of (sigma_tr h)^3 in the least absorbing channel, the thickest sigma_t h, how many voxels of sigma_t h >= 2, extent.

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/lump_sizes.py [spray_dense,spray_lumps]
"""

import sys

import numpy as np

import bake_suite
from spray_thick_probe import lumps

SMALL_PIECE_VOXELS = 343  # bake_thin_snow.cpp, kSmallPieceVoxels


def main():
    names = sys.argv[1].split(",") if len(sys.argv) > 1 else [c.name for c in bake_suite.cases()]
    for name in names:
        c = bake_suite.case(name)
        tau = c.sigma_t / c.rho * c.density * c.voxel
        reduced = tau * (1.0 - max(c.omega) * c.g)
        label = lumps(c.density > 0)
        found = [np.argwhere(label == k) for k in range(1, label.max() + 1)]
        print(f"{name}: {len(found)} pieces of {[len(p) for p in found]} voxels, {int((tau >= 2).sum())} voxels of "
              "sigma_t h >= 2")
        for p in sorted(found, key=lambda p: -(reduced[tuple(p.T)] ** 3).sum()):
            t = tau[tuple(p.T)]
            if len(p) <= SMALL_PIECE_VOXELS and (t >= 2).any():
                print(f"  {len(p):4d} voxels, sum (sigma_tr h)^3 {(reduced[tuple(p.T)] ** 3).sum():7.1f}, thickest "
                      f"sigma_t h {t.max():4.1f}, {int((t >= 2).sum())} of sigma_t h >= 2, extent "
                      f"{tuple(int(x) for x in p.max(0) - p.min(0) + 1)}")


main()
