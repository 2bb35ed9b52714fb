"""The sun's single scattering along a ball's top rows seen against the sun (branch backlit, docs/benchmarks.md
"backlit"): exact (trilinear density, midpoint rule on 0.5 mm steps), against the same source stored as each voxel's
mean (weighted by the renderer's trilinear hat and the extinction, 6^3 points per voxel) and read back trilinearly
(normalised over the snow's voxels, as the bake's shell carries surface values beyond the snow): what a voxel's one
source value can show of a sunlit density ramp seen edge-on. No bake involved.

    PYTHONPATH=build/python /usr/bin/python3 bench/backlit_single_scattering.py ball_issue
"""
import math
import sys

import numpy as np

import bake_suite as S
from backlit_probe import TOP_ROWS, sun_towards
name = sys.argv[1]
case = [c for c in S.cases() if c.name == name][0]
k, w, g, h = case.sigma_t / case.rho, case.omega[1], case.g, case.voxel
sun = sun_towards()
def tsun(P):  # P: (n,3) world points
    s = np.arange(0.00025, 0.2, 0.0005)
    out = np.empty(len(P))
    for i, p in enumerate(P):
        out[i] = math.exp(-k * S.trilinear(case.density, (p + s[:, None] * sun) / h).sum() * 0.0005)
    return out
o, d, tau = S.views(case)
per = 64; rows = [2 * per + i for i in TOP_ROWS if tau[2 * per + i] >= 1]
mu = float(np.dot(d[rows[0]], sun)); phase = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * mu) ** 1.5)
# voxels the rays touch
sub = (np.arange(6) + 0.5) / 6 * 2 - 1  # hat box offsets in voxels
off = np.array(np.meshgrid(sub, sub, sub, indexing="ij")).reshape(3, -1).T
hat = np.prod(1 - np.abs(off), axis=1)
cache = {}
def Jmean(v):
    if v not in cache:
        P = (np.array(v) + off) * h
        rho = S.trilinear(case.density, P / h)
        wgt = hat * rho
        cache[v] = float((wgt * tsun(P)).sum() / wgt.sum()) * w * phase if wgt.sum() > 0 else None
    return cache[v]
for j in rows:
    s = np.arange(0.00025, 0.4, 0.0005); P = o[j] + s[:, None] * d[j]
    rho = S.trilinear(case.density, P / h); cam = np.exp(-k * (np.cumsum(rho) - rho / 2) * 0.0005)
    live = np.nonzero((rho > 0) & (cam > 1e-4))[0]
    exact = (k * rho[live] * cam[live] * tsun(P[live])).sum() * 0.0005 * w * phase
    stored = 0.0
    for i in live:
        x = P[i] / h; base = np.floor(x).astype(int); f = x - base
        num = den = 0.0
        for c in np.ndindex(2, 2, 2):
            v = tuple(base + np.array(c)); wt = np.prod(np.where(np.array(c) == 1, f, 1 - f))
            J = Jmean(v) if min(v) >= 0 and all(a < b for a, b in zip(v, case.density.shape)) and case.density[v] > 0 else None
            if J is not None: num += wt * J; den += wt
        stored += k * rho[i] * cam[i] * (num / den if den > 0 else 0.0) * 0.0005
    print(f"  {j - 2 * per:2d}: exact {exact:.4f}, voxel means read trilinearly {stored:.4f} ({stored / exact - 1:+.0%})")
