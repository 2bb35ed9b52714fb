"""How much sun a ball's density ramp intercepts beyond its surface patches (docs/benchmarks.md, ramp-cell).

1. The sun the trilinear density intercepts, 1 - exp(-tau) over the sun's cross-section (rays on a 0.1-voxel grid,
   tau marched on 0.1-voxel steps), by impact radius b in voxels: the ramp's rim outside the half-density sphere (the
   bake's patches take E mu0 per patch area, about pi R^2 in all) against its inside.
2. The uncollided sun averaged over a ramp cell's trilinear hat, weighted by the density (what beamsInRamp weighs), on
   the ball and on a flat snow whose top voxel has the cell's fill, the sun at the cell's mu0 (the ball's normal at the
   cell's centre): how much more sun a convex limb's ramp gets than the half-space model's ramp at the same angle.

    PYTHONPATH=build/python /usr/bin/python3 bench/ramp_interception.py [--cases ball_grey,ball_issue] \
        [--cells 10,3,7:10,3,8]
"""

import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bake_suite  # noqa: E402
from backlit_probe import sun_towards  # noqa: E402

STEP = 0.1  # voxels, across the sun's cross-section and along its rays


def intercepted_by_ring(case, rings):
    """Voxels^2 of unit sun the snow intercepts (all, and per ring [lo, hi) of impact radius) and each ring's area."""
    s = sun_towards()
    u = np.cross(s, [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(s, u)
    optical_depth = case.sigma_t / case.rho * case.voxel  # per voxel per unit density
    centre = (np.array(case.density.shape) - 1) / 2
    half = max(case.density.shape) / 2
    a = np.arange(-half, half, STEP) + STEP / 2
    A, B = np.meshgrid(a, a, indexing="ij")
    origins = centre + A.ravel()[:, None] * u + B.ravel()[:, None] * v
    tau = np.zeros(len(origins))
    for t in np.arange(-2 * half, 2 * half, STEP):
        tau += bake_suite.trilinear(case.density, origins + t * s) * STEP * optical_depth
    hit, b = 1.0 - np.exp(-tau), np.hypot(A.ravel(), B.ravel())
    per_ring = [(hit[(b >= lo) & (b < hi)].sum() * STEP ** 2, ((b >= lo) & (b < hi)).sum() * STEP ** 2)
                for lo, hi in rings]
    return hit.sum() * STEP ** 2, per_ring


def hat_transmittance(density, optical_depth, cell, sun, points=6):
    """The uncollided sun's transmittance averaged over voxel `cell`'s trilinear hat, weighted by the density."""
    offsets = 2.0 * ((np.arange(points) + 0.5) / points - 0.5)  # across the hat, +-1 voxel
    along = np.arange(STEP / 2, 12.0, STEP)[:, None] * sun
    total = weights = 0.0
    for dx in offsets:
        for dy in offsets:
            for dz in offsets:
                q = np.array(cell, float) + (dx, dy, dz)
                w = (1 - abs(dx)) * (1 - abs(dy)) * (1 - abs(dz)) * bake_suite.trilinear(density, q[None])[0]
                if w <= 0.0:
                    continue
                column = bake_suite.trilinear(density, q + along).sum() * STEP
                total += w * math.exp(-optical_depth * column)
                weights += w
    return total / weights


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", default="ball_grey,ball_issue")
    parser.add_argument("--cells", default="10,3,7:10,3,8:11,4,7", help="ramp cells (voxels), ':'-separated")
    args = parser.parse_args()
    rings = [(0, 4.5), (4.5, 5), (5, 5.5), (5.5, 6), (6, 7)]
    for name in args.cases.split(","):
        case = bake_suite.case(name)
        total, per_ring = intercepted_by_ring(case, rings)
        print(f"{name}: sun intercepted {total:.1f} voxel^2 (pi ({math.sqrt(total / math.pi):.2f})^2; the "
              f"half-density sphere pi 5^2 = {math.pi * 25:.1f})")
        for (lo, hi), (hit, area) in zip(rings, per_ring):
            print(f"  b {lo}-{hi}: {hit:6.2f} of {area:6.2f} voxel^2")
        optical_depth = case.sigma_t / case.rho * case.voxel
        centre = (np.array(case.density.shape) - 1) / 2
        full = case.density.max()
        for text in args.cells.split(":"):
            cell = tuple(int(x) for x in text.split(","))
            normal = (np.array(cell) - centre) / np.linalg.norm(np.array(cell) - centre)
            mu0 = float(normal @ sun_towards())
            flat = np.zeros((5, 5, 8))
            flat[:, :, :5], flat[:, :, 5] = full, case.density[cell]
            flat_sun = np.array([math.sqrt(1 - mu0 * mu0), 0.0, mu0])
            ball_t = hat_transmittance(case.density, optical_depth, cell, sun_towards())
            flat_t = hat_transmittance(flat, optical_depth, (2, 2, 5), flat_sun)
            print(f"  cell {cell} fill {case.density[cell] / full:.2f} mu0 {mu0:+.2f}: hat transmittance ball "
                  f"{ball_t:.3f}, flat top of that fill {flat_t:.3f} ({ball_t / flat_t:.2f}x)")


if __name__ == "__main__":
    main()
