"""A ball case's lit surface voxels: the exitance of each one's baked lobes (both, integrated over the hemisphere
about the sphere's normal) over a flat slab's top voxel's at the same sun cosine mu0, the same snow and voxels
(docs/benchmarks.md, grey-lit): does the bake's per-patch return vary with where the staircase puts the node?

Surface voxels as snow_topology.cpp finds them (sigma_t h >= 0.1, the fringe peeled: under 5 with air one side and
5 or more the other; a face to a voxel that is no unknown is an air face), grouped by the node's depth under the
sphere (the density's half level). The flat table: a 16 x 16 x 6 slab baked under a sun at mu0 0.1 ... 1.

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/grey_lit_nodes.py [ball_grey]
"""
import math, os, sys, tempfile
import numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bake_suite, firncore, pyopenvdb
case = bake_suite.case(sys.argv[1] if len(sys.argv) > 1 else "ball_grey")
SUN = np.array([math.cos(bake_suite.SUN_ELEVATION), 0, math.sin(bake_suite.SUN_ELEVATION)])
h = case.voxel
NAMES = ("firn_source", "firn_source_x", "firn_source_y", "firn_source_z", "firn_source_peak", "firn_source_peak_l1")
def read(path):
    return {nm: pyopenvdb.read(path, nm).getConstAccessor() for nm in NAMES}
# hemisphere quadrature about z
mu_n, mu_w = np.polynomial.legendre.leggauss(12); mu_n = 0.5 * (mu_n + 1); mu_w = 0.5 * mu_w
phis = (np.arange(24) + 0.5) * 2 * np.pi / 24
dirs, wts = [], []
for m, w in zip(mu_n, mu_w):
    s = math.sqrt(1 - m * m)
    for p in phis:
        dirs.append((s * math.cos(p), s * math.sin(p), m)); wts.append(w * m * 2 * np.pi / 24)
dirs, wts = np.array(dirs), np.array(wts)
def frame(n):
    a = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    t = np.cross(n, a); t /= np.linalg.norm(t); b = np.cross(n, t)
    return np.stack([t, b, n], 1)
def lobe(m0, m1, mean, W):
    if m0 <= 0: return np.zeros(len(W))
    n1 = np.linalg.norm(m1)
    k = min(n1 / (3 * mean), 0.95) if n1 > 0 and mean > 0 else 0.0
    c = W @ m1 / n1 if n1 > 0 else np.zeros(len(W))
    return m0 * (1 - k * k) / (1 + k * k - 2 * k * c) ** 1.5
def exitance(acc, ijk, n):
    W = dirs @ frame(n).T
    l0 = acc["firn_source"].getValue(ijk)[1]; l1 = np.array([acc["firn_source_" + a].getValue(ijk)[1] for a in "xyz"])
    p0 = np.array(acc["firn_source_peak"].getValue(ijk)); p1 = np.array(acc["firn_source_peak_l1"].getValue(ijk))
    return float(wts @ (lobe(l0, l1, l0, W) + lobe(p0[1], p1, p0.mean(), W)))
with tempfile.TemporaryDirectory() as f:
    flat = {}
    dens = bake_suite.slab(16, 6) * case.density.max()
    fp = os.path.join(f, "flat.vdb")
    for mu0 in np.arange(0.1, 1.01, 0.1):
        bake_suite.write_density(fp, dens, h)
        s0 = math.sqrt(max(0, 1 - mu0 * mu0))
        firncore.bake(fp, case.optics, suns=[firncore.SunLight((s0, 0, mu0), (1.0,) * 3, 0.0093)], quality="FINAL", seed=0)
        flat[round(mu0, 1)] = exitance(read(fp), (dens.shape[0] // 2, dens.shape[1] // 2, 2 + 6 - 1), np.array([0, 0, 1.0]))
    mus = np.array(sorted(flat)); vals = np.array([flat[m] for m in mus])
    print("flat top voxel exitance / mu0:", " ".join(f"{m:.1f}:{flat[m] / m:.4f}" for m in mus))
    p = os.path.join(f, "ball.vdb"); bake_suite.write_density(p, case.density, h)
    firncore.bake(p, case.optics, suns=case.suns(), quality="FINAL", seed=0)
    acc = read(p)
    D = case.density / case.density.max(); n = D.shape[0]; c = (n - 1) / 2
    tau = case.density * case.sigma_t / case.rho * h
    dense = tau >= 0.1
    unknown = dense.copy()
    steps = ((1,0,0),(-1,0,0),(0,1,0),(0,-1,0),(0,0,1),(0,0,-1))
    def at(a, i, j, k):
        return a[i, j, k] if 0 <= i < n and 0 <= j < n and 0 <= k < n else 0
    for i, j, k in zip(*np.nonzero(dense)):
        if tau[i, j, k] >= 5.0: continue
        for a, b, e in steps:
            if not at(dense, i + a, j + b, k + e) and at(tau, i - a, j - b, k - e) >= 5.0:
                unknown[i, j, k] = False; break
    rows = []
    for i, j, k in zip(*np.nonzero(unknown)):
        faces = sum(not at(unknown, i + a, j + b, k + e) for a, b, e in steps)
        if faces == 0: continue
        v = np.array([i, j, k]) - c; r = np.linalg.norm(v); nn = v / r; mu0 = nn @ SUN
        if mu0 < 0.3: continue
        M = exitance(acc, (int(i), int(j), int(k)), nn)
        rows.append((r, faces, mu0, M / np.interp(mu0, mus, vals), tau[i, j, k]))
    rows = np.array(rows)
    R = float(__import__("re").search(r"r (\d+) cm", case.what).group(1)) / 100 / h
    print(f"{case.name}: lit surface nodes (mu0 >= 0.3), exitance along the sphere normal over the flat top's at that mu0")
    for rr in np.unique(np.round(rows[:, 0], 2)):
        kk = np.round(rows[:, 0], 2) == rr
        print(f"  node {R - rr:5.2f} voxels under the surface: {kk.sum():3d} nodes, ratio mean {rows[kk, 3].mean():.3f} "
              f"(min {rows[kk, 3].min():.3f}, max {rows[kk, 3].max():.3f}), air faces {np.mean(rows[kk, 1]):.1f}, sigma_t h {np.mean(rows[kk, 4]):.2f}")
    print(f"  all: {len(rows)} nodes, ratio mean {rows[:, 3].mean():.3f}")
