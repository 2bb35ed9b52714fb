"""The sun's single scattering along a ball's top rows seen against the sun (branch backlit, docs/benchmarks.md
"backlit"): exact (trilinear density, midpoint rule on 0.5 mm steps), against the same source stored as each voxel's
mean (weighted by the renderer's trilinear hat and the extinction, 6^3 points per voxel) and read back trilinearly
(normalised over the snow's voxels, as the bake's shell carries surface values beyond the snow): what a voxel's one
source value can show of a sunlit density ramp seen edge-on. No bake involved.

    PYTHONPATH=build/python /usr/bin/python3 bench/backlit_single_scattering.py ball_issue
"""
import math
import sys
from functools import lru_cache

import numpy as np

import bake_suite as S
from backlit_probe import TOP_ROWS, single_scattering, sun_towards

STEP = 0.0005  # m, midpoint rule along rays
HAT_POINTS = 6  # per axis, points of the trilinear hat's box about a voxel's centre


def sun_transmittance(case, points):
    """exp(-optical depth) from each world point (m) towards the sun."""
    k, s = case.sigma_t / case.rho, np.arange(STEP / 2, 0.2, STEP)
    return np.array([math.exp(-k * S.trilinear(case.density, (p + s[:, None] * sun_towards()) / case.voxel).sum() * STEP)
                     for p in points])


def main():
    case = [c for c in S.cases() if c.name == (sys.argv[1] if len(sys.argv) > 1 else "ball_issue")][0]
    k, albedo, h = case.sigma_t / case.rho, case.omega[1], case.voxel
    origins, directions, tau = S.views(case)
    per = case.pixels ** 2
    against = case.views.index((180, 0))
    rows = [against * per + i for i in TOP_ROWS if tau[against * per + i] >= 1]
    g, mu = case.g, float(np.dot(directions[rows[0]], sun_towards()))
    scattered = albedo * (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * mu) ** 1.5)  # per unit sun and extinction
    side = (np.arange(HAT_POINTS) + 0.5) / HAT_POINTS * 2 - 1  # voxels about the centre
    offsets = np.array(np.meshgrid(side, side, side, indexing="ij")).reshape(3, -1).T
    hat = np.prod(1 - np.abs(offsets), axis=1)

    @lru_cache(maxsize=None)
    def voxel_mean(v):
        """The source's mean over voxel v weighted by the hat and the extinction; None outside the snow."""
        if min(v) < 0 or any(a >= b for a, b in zip(v, case.density.shape)) or case.density[v] <= 0:
            return None
        points = (np.array(v) + offsets) * h
        weight = hat * S.trilinear(case.density, points / h)
        return float((weight * sun_transmittance(case, points)).sum() / weight.sum()) * scattered

    for j in rows:
        s = np.arange(STEP / 2, 0.4, STEP)
        points = origins[j] + s[:, None] * directions[j]
        rho = S.trilinear(case.density, points / h)
        camera = np.exp(-k * (np.cumsum(rho) - rho / 2) * STEP)
        live = np.nonzero((rho > 0) & (camera > 1e-4))[0]
        exact = single_scattering(case, origins[j], directions[j])
        stored = 0.0
        for i in live:
            x = points[i] / h
            base, f = np.floor(x).astype(int), x - np.floor(x)
            value = weight = 0.0
            for corner in np.ndindex(2, 2, 2):
                J = voxel_mean(tuple(int(a) for a in base + np.array(corner)))
                if J is not None:
                    w = np.prod(np.where(np.array(corner) == 1, f, 1 - f))
                    value, weight = value + w * J, weight + w
            stored += k * rho[i] * camera[i] * (value / weight if weight > 0 else 0.0) * STEP
        print(f"  {j - against * per:2d}: exact {exact:.4f}, voxel means read trilinearly {stored:.4f} "
              f"({stored / exact - 1:+.0%})")


if __name__ == "__main__":
    main()
