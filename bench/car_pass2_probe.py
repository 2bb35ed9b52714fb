"""What the car's second (gathering) pass changes (docs/benchmarks.md, car-pass2), from a build with
bench/car_pass2_probe.diff applied to main dfbe0c5's bake.cpp (prints per pass and channel the CG iterations, the
sources' sum before and after the gathered light, the gathering's patch counts and phase seconds; FIRN_DBG_PASSES forces
the passes, FIRN_DBG_TOLP1 the earlier passes' tolerance, FIRN_DBG_DUMP=DIR writes each solve's phi and the gathered
irradiance).

    FIRN_DBG=1 FIRN_DBG_DUMP=DIR PYTHONPATH=build/python:bench python3 bench/car_pass2_probe.py bake OUT [seed]
    python3 bench/car_pass2_probe.py phi DIR                # how far pass 2 moves phi, where the gathered light lands
    python3 bench/car_pass2_probe.py grids A.vdb B.vdb      # the source grids' relative differences over voxels
"""

import os
import shutil
import sys

import numpy as np


def bake(out, seed=0, folder="/work/car_inputs"):
    import car_bake

    os.makedirs(out, exist_ok=True)
    path = shutil.copy(os.path.join(folder, "car_density.vdb"), os.path.join(out, "car.vdb"))
    stats = car_bake.bake_copy(path, *car_bake.car_inputs(folder), seed)
    print({k: stats[k] for k in ("iterations", "passes", "cpu_seconds", "voxels")})


def phi(folder):
    coord = np.fromfile(f"{folder}/coord.bin", np.int32).reshape(-1, 3)
    gathered = np.fromfile(f"{folder}/gathered.bin", np.float32)  # grey W/m^2; -1 inside the snow
    surface = gathered >= 0
    print(f"unknowns {len(coord)}, surface {surface.sum()}, gathered > 0 {np.sum(gathered > 0)} "
          f"({np.sum(gathered > 0) / surface.sum():.3f} of the surface)")
    g = gathered[gathered > 0]
    print(f"gathered grey W/m^2 where > 0: mean {g.mean():.4g}, median {np.median(g):.4g}, "
          f"p90 {np.percentile(g, 90):.4g}, max {g.max():.4g}")
    for c in range(3):
        p0 = np.fromfile(f"{folder}/phi_p0_c{c}.bin", np.float64)
        p1 = np.fromfile(f"{folder}/phi_p1_c{c}.bin", np.float64)
        rel = np.abs(p1 - p0) / np.maximum(np.abs(p1), 1e-30)
        print(f"channel {c}: phi sum {p0.sum():.6g} -> {p1.sum():.6g} ({p1.sum() / p0.sum() - 1:+.2%}); relative change "
              f"median {np.median(rel):.3g}, p90 {np.percentile(rel, 90):.3g}; share over 1e-2 {np.mean(rel > 1e-2):.3f}, "
              f"over 1e-3 {np.mean(rel > 1e-3):.3f}; surface voxels over 1e-3 {np.mean(rel[surface] > 1e-3):.3f}")


def grids(a, b):
    import pyopenvdb

    for name in (g.name for g in pyopenvdb.readAllGridMetadata(a) if g.name.startswith("firn_source")):
        ga, gb = pyopenvdb.read(a, name), pyopenvdb.read(b, name)
        boxes = ga.evalActiveVoxelBoundingBox(), gb.evalActiveVoxelBoundingBox()
        lo = [min(boxes[0][0][k], boxes[1][0][k]) for k in range(3)]
        hi = [max(boxes[0][1][k], boxes[1][1][k]) for k in range(3)]
        va = np.zeros(tuple(hi[k] - lo[k] + 1 for k in range(3)) + (3,), np.float32)
        vb = va.copy()
        ga.copyToArray(va, ijk=tuple(lo))
        gb.copyToArray(vb, ijk=tuple(lo))
        va, vb = va.mean(-1), vb.mean(-1)  # grey
        held = (va != 0) | (vb != 0)
        x, y = va[held].astype(np.float64), vb[held].astype(np.float64)
        rel = np.abs(x - y) / np.maximum(np.abs(y), 1e-3 * np.abs(y).max())
        print(f"{name}: {held.sum()} voxels, sum {x.sum():.5g} -> {y.sum():.5g} ({y.sum() / x.sum() - 1:+.4%}); "
              f"relative difference median {np.median(rel):.3g}, p90 {np.percentile(rel, 90):.3g}, "
              f"p99 {np.percentile(rel, 99):.3g}; share over 1 % {np.mean(rel > 0.01):.3f}")


if __name__ == "__main__":
    what = sys.argv[1]
    if what == "bake":
        bake(sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 0)
    elif what == "phi":
        phi(sys.argv[2])
    else:
        grids(sys.argv[2], sys.argv[3])
