"""The sun's single scattering along a ball's top rows seen against the sun (branch backlit, docs/benchmarks.md
"backlit"): exact (trilinear density, midpoint rule on 0.5 mm steps), against the same source stored as each voxel's
mean (weighted by the renderer's trilinear hat and the extinction, 6^3 points per voxel) and read back trilinearly
(normalised over the snow's voxels, as the bake's shell carries surface values beyond the snow): what a voxel's one
source value can show of a sunlit density ramp seen edge-on. No bake involved.
Branch seen-sun adds the same source stored as cameras see each voxel (Method 3's visible-source weight: hat x
extinction x the sum over the 26 neighbour directions w of exp(-optical depth from the point along w out of the
hat's box)), and as this camera alone sees it (the one direction -view): does a camera-seen voxel value recover
the ramp's lit top?

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
OUT_STEPS = 16  # midpoint steps of the optical depth out of the hat's box


def sun_transmittance(case, points):
    """exp(-optical depth) from each world point (m) towards the sun."""
    k, s = case.sigma_t / case.rho, np.arange(STEP / 2, 0.2, STEP)
    return np.array([math.exp(-k * S.trilinear(case.density, (p + s[:, None] * sun_towards()) / case.voxel).sum() * STEP)
                     for p in points])


def depth_out(case, v, y, w):
    """Optical depth from index-space offsets y about voxel v's centre along unit w to leaving the box [-1, 1]^3."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.min(np.where(w != 0, (np.sign(w) - y) / np.where(w != 0, w, 1), np.inf), axis=1)
    total = sum(S.trilinear(case.density, np.array(v) + y + ((i + 0.5) / OUT_STEPS * t)[:, None] * w) for i in range(OUT_STEPS))
    return case.sigma_t / case.rho * case.voxel * total * t / OUT_STEPS


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

    neighbours = np.array([d for d in np.ndindex(3, 3, 3) if d != (1, 1, 1)], float) - 1
    neighbours /= np.linalg.norm(neighbours, axis=1)[:, None]

    @lru_cache(maxsize=None)
    def voxel_values(v):
        """The source over voxel v weighted by the hat and the extinction: its mean, as all cameras see it, as this
        one sees it; None outside the snow."""
        if min(v) < 0 or any(a >= b for a, b in zip(v, case.density.shape)) or case.density[v] <= 0:
            return None
        points = (np.array(v) + offsets) * h
        mean = hat * S.trilinear(case.density, points / h)
        seen = mean * sum(np.exp(-depth_out(case, v, offsets, w)) for w in neighbours)
        this = mean * np.exp(-depth_out(case, v, offsets, -directions[rows[0]]))
        sun = sun_transmittance(case, points)
        return np.array([(w * sun).sum() / w.sum() for w in (mean, seen, this)]) * scattered

    for j in rows:
        s = np.arange(STEP / 2, 0.4, STEP)
        points = origins[j] + s[:, None] * directions[j]
        rho = S.trilinear(case.density, points / h)
        camera = np.exp(-k * (np.cumsum(rho) - rho / 2) * STEP)
        live = np.nonzero((rho > 0) & (camera > 1e-4))[0]
        exact = single_scattering(case, origins[j], directions[j])
        stored = np.zeros(3)
        for i in live:
            x = points[i] / h
            base, f = np.floor(x).astype(int), x - np.floor(x)
            value, weight = np.zeros(3), 0.0
            for corner in np.ndindex(2, 2, 2):
                J = voxel_values(tuple(int(a) for a in base + np.array(corner)))
                if J is not None:
                    w = np.prod(np.where(np.array(corner) == 1, f, 1 - f))
                    value, weight = value + w * J, weight + w
            stored += k * rho[i] * camera[i] * (value / weight if weight > 0 else 0.0) * STEP
        print(f"  {j - against * per:2d}: exact {exact:.4f}, read trilinearly: voxel means {stored[0]:.4f} "
              f"({stored[0] / exact - 1:+.0%}), as cameras see them {stored[1]:.4f} ({stored[1] / exact - 1:+.0%}), "
              f"as this camera sees them {stored[2]:.4f} ({stored[2] / exact - 1:+.0%})")


if __name__ == "__main__":
    main()
