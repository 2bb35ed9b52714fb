"""spray_dense's lit lump faces seen straight on at their centres (docs/benchmarks.md, spray-cores): per lit face the
baked render, the brute-force truth, the face's own Monte Carlo towards its normal and its fitted lobes there. Needs a
bake of spray_dense by the core built with bench/spray_cores_hooks.diff, its stderr kept (the SCFACE lines):

    FIRN_SC_FIT=1 FIRN_SC_PATHS=2048 (bake spray_dense FINAL seed 0 into BAKED.vdb) 2> faces.txt
    PYTHONPATH=build/python python3 bench/spray_cores_faces.py faces.txt BAKED.vdb
"""

import sys

import numpy as np

import bake_suite
import firncore

case = bake_suite.case("spray_dense")
h = case.voxel
rows = [l.split()[1:] for l in open(sys.argv[1]) if l.startswith("SCFACE")]
rows = [r for r in rows if len(r) == 9]
rng = np.random.default_rng(2)
O, D, F, info = [], [], [], []
axes = {1: (0, 1), 3: (1, 1), 5: (2, 1), 0: (0, -1), 2: (1, -1), 4: (2, -1)}
for r in rows:
    lit, x, y, z, f = map(int, r[:5]); s, car, sho, fit = map(float, r[5:])
    if not lit: continue
    ax, sg = axes[f]
    n = np.zeros(3); n[ax] = sg
    for k in range(8):
        q = np.array([x, y, z], float) * h
        q[ax] += 0.5 * h * sg
        for a in range(3):
            if a != ax: q[a] += (rng.random() - 0.5) * 0.2 * h
        O.append(q + n * 0.5 * h); D.append(-n); F.append(len(info))
    info.append((s, car, sho, fit))
O, D, F = np.array(O), np.array(D), np.array(F)
info = np.array(info)
vdb = sys.argv[2]
b = firncore.render_baked(vdb, case.optics, O, D).mean(1)
t, _ = firncore.monte_carlo_radiance(vdb, case.optics, O, D, suns=case.suns(), sky=case.skies(), samples=512, seed=3)
t = t.mean(1)
tf = np.bincount(F, t) / 8; bf = np.bincount(F, b) / 8
s, car, sho, fit = info.T
face = (1 - s) * car + s * sho
print(f"{len(info)} lit faces, straight rays at their centres: baked / truth {bf.sum() / tf.sum():.3f}; the face's own Monte Carlo "
      f"((1 - s) carried + s shown, towards its normal) / truth {face.sum() / tf.sum():.3f}; carried alone / truth {car.sum() / tf.sum():.3f}; "
      f"its fit / truth {fit.sum() / tf.sum():.3f}; shown / carried {sho.sum() / car.sum():.3f}")
