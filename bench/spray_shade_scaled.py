"""spray-shade (2): seed 0's thick voxels' (and all taken voxels') six source grids scaled by Monte Carlo / baked at the
camera's direction, from bench/spray_shade_probe.py's voxel centres (its /tmp/spray_shade_seed0.npz: run
`spray_shade_probe.py --seeds 0 --no-rays --share 0.6` first), and view (180, 0)'s shadowed thick blocks rendered
baked and mixed (2048 paths) against the suite's reference (docs/benchmarks.md, spray-shade). A view-specific
correction: the voxel's source set to Monte Carlo's towards this camera only.

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/spray_shade_scaled.py
"""

import os
import sys
import tempfile

import numpy as np
import pyopenvdb

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bake_suite  # noqa: E402
import firncore  # noqa: E402
from spray_rims_probe import scattered_region, shares_in
from suite_regions import regions
from spray_shade_probe import GRIDS
case = bake_suite.case("spray_dense")
origins, directions, tau = bake_suite.views(case)
seen, lit, core = regions(case, origins, directions, tau)
thin = shares_in(case, origins, directions, seen, scattered_region(case)) >= 0.5
views = np.repeat(np.arange(len(case.views)), case.pixels ** 2)
against = seen & ~lit & (core | ~thin) & (views == 2)
d = np.load("/tmp/spray_shade_seed0.npz")
ratio = d["mc"][:, 1] / np.maximum(d["baked"][:, 1], 1e-30)
n = np.array(case.density.shape)
with tempfile.TemporaryDirectory() as folder:
    path = os.path.join(folder, "s.vdb")
    run = bake_suite.baked_case(case, path, bake_suite.CACHE, "FINAL", 0)
    def show(p, label):
        b = firncore.render_baked(p, case.optics, run.origins[against], run.directions[against], occluders=case.occluders)
        m, _ = firncore.render_scattering_where_thin(p, case.optics, run.origins[against], run.directions[against],
                 suns=case.suns(), sky=case.skies(), occluders=case.occluders, samples=2048, seed=1000, traced_only=True)
        t = run.mean[against]
        print(f"  {label:<40} baked {100 * (b.sum() / t.sum() - 1):+5.1f} %, mixed {100 * (m.sum() / t.sum() - 1):+5.1f} % (bias of the sum)")
    print(f"seed 0, view (180, 0), {against.sum()} shadowed thick blocks:")
    show(path, "main")
    for label, keep in (("thick voxels (sigma_t h > 2) set to MC", [3, 4]), ("all 46 taken voxels set to MC", [0, 1, 2, 3, 4])):
        grids, metadata = pyopenvdb.readAll(path)
        sel = np.isin(d["classes"], keep)
        for g in grids:
            if g.name in GRIDS:
                values = np.zeros(tuple(n) + (3,), np.float32)
                g.copyToArray(values, ijk=(0, 0, 0))
                for (i, j, k), r in zip(d["voxels"][sel], ratio[sel]):
                    values[i, j, k] *= r
                g.copyFromArray(values, ijk=(0, 0, 0), tolerance=(0.0, 0.0, 0.0))
        out = os.path.join(folder, "scaled.vdb")
        pyopenvdb.write(out, grids=grids, metadata=metadata)
        show(out, label)
