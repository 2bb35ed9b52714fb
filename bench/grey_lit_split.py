"""What a ball case's sunlit smooth patches return of the sun, split into the bake's terms, per band of the sphere's
sun cosine (docs/benchmarks.md, grey-lit): the share of the half-space's return P A (sunIn times the sun lobe's
albedo) that escaped at once (the beam scattered above the node), that the node's diffusion sends out
(outConductance phi), the half-space correction (A minus schemeBeamAlbedo's closed form, `sunMissed`), what moves
downstream (at once + missed: sunLeavingDownstream), and all that leaves over P A.

Needs the hooks: `git apply bench/grey_lit_sunsplit_hooks.diff` and a build (FIRN_DEBUG_SUNSPLIT=1 prints each
patch's terms, channel G, sun alone).

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/grey_lit_split.py ball_grey
"""
import math, os, sys, tempfile, subprocess
import numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bake_suite, firncore
name = sys.argv[1]
case = bake_suite.case(name)
SUN = np.array([math.cos(bake_suite.SUN_ELEVATION), 0, math.sin(bake_suite.SUN_ELEVATION)])
with tempfile.TemporaryDirectory() as f:
    p = os.path.join(f, "b.vdb"); bake_suite.write_density(p, case.density, case.voxel)
    code = f"import sys; sys.path.insert(0,'bench'); import bake_suite, firncore; c=bake_suite.case('{name}'); firncore.bake('{p}', c.optics, suns=c.suns(), quality='FINAL', seed=0)"
    out = subprocess.run([sys.executable, "-c", code], env=dict(os.environ, FIRN_DEBUG_SUNSPLIT="1"), capture_output=True, text=True).stderr
rows = np.array([[float(x) for x in l.split()[1:]] for l in out.splitlines() if l.startswith("SUNSPLIT")])
n = case.density.shape[0]; c = (n - 1) / 2
v = rows[:, :3] - c; r = np.linalg.norm(v, axis=1); mu0 = (v / r[:, None]) @ SUN
ret, once, missed, diff, esc = rows[:, 5], rows[:, 6], rows[:, 7], rows[:, 8], rows[:, 9]
print(f"{name}: {len(rows)} sunlit smooth patches; shares of what the half-space returns (P A), summed per band of the sphere's mu0")
print("  mu0 band   patches  at once  diffusion(node)  missed (A - scheme)  moved downstream  (leaving+missed)/PA")
for lo, hi in ((0.9, 1.01), (0.7, 0.9), (0.5, 0.7), (0.3, 0.5), (0.1, 0.3), (-1, 0.1)):
    k = (mu0 >= lo) & (mu0 < hi)
    if not k.any(): continue
    R = ret[k].sum()
    print(f"  {lo:4.1f}-{hi:4.2f}  {k.sum():4d}     {once[k].sum() / R:6.3f}   {diff[k].sum() / R:6.3f}           {missed[k].sum() / R:+6.3f}              "
          f"{(once[k] + missed[k]).sum() / R:6.3f}            {(esc[k] + diff[k] + missed[k]).sum() / R:6.3f}")
