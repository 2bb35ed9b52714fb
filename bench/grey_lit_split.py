"""What a ball case's sunlit smooth patches return of the sun, split into the bake's terms, per band of the sphere's
sun cosine (docs/benchmarks.md, grey-lit): the share of the half-space's return P A (sunIn times the sun lobe's
albedo) that escaped at once (the beam scattered above the node), that the node's diffusion sends out
(outConductance phi), the half-space correction (A minus schemeBeamAlbedo's closed form, `sunMissed`), what moves
downstream (at once + missed: sunLeavingDownstream), and all that leaves over P A.

With --budget instead (docs/benchmarks.md, thin-beam): each unknown's beam budget in `assemble` (sun alone, channel
G), W: its boundary faces, what its surface patch lets in, what enters through its links, what it passes on through its links, and what
it scatters, a' max(0, in - out); per class of unknown (lit surface voxels by the node's depth under the density's
half level and their sigma_t h; the voxels behind them) and over the whole ball: how much more the nodes scatter
than the patches let in (the clipped voxels' out - in).

Needs the hooks: `git apply bench/grey_lit_sunsplit_hooks.diff` and a build (FIRN_DEBUG_SUNSPLIT=1 prints each
patch's terms, FIRN_DEBUG_BEAMBUDGET=1 each unknown's beam budget).

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/grey_lit_split.py ball_grey [--budget]
"""
import math, os, sys, tempfile, subprocess
import numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bake_suite, firncore
name = sys.argv[1]
budget = "--budget" in sys.argv
case = bake_suite.case(name)
SUN = np.array([math.cos(bake_suite.SUN_ELEVATION), 0, math.sin(bake_suite.SUN_ELEVATION)])
with tempfile.TemporaryDirectory() as f:
    p = os.path.join(f, "b.vdb"); bake_suite.write_density(p, case.density, case.voxel)
    code = f"import sys; sys.path.insert(0,'bench'); import bake_suite, firncore; c=bake_suite.case('{name}'); firncore.bake('{p}', c.optics, suns=c.suns(), quality='FINAL', seed=0)"
    hook = "FIRN_DEBUG_BEAMBUDGET" if budget else "FIRN_DEBUG_SUNSPLIT"
    out = subprocess.run([sys.executable, "-c", code], env=dict(os.environ, **{hook: "1"}), capture_output=True, text=True).stderr
tag = "BEAMBUDGET" if budget else "SUNSPLIT"
rows = np.array([[float(x) for x in l.split()[1:]] for l in out.splitlines() if l.startswith(tag)])
n = case.density.shape[0]; c = (n - 1) / 2
v = rows[:, :3] - c; r = np.linalg.norm(v, axis=1); mu0 = (v / r[:, None]) @ SUN


def print_budget():
    # the last stored bake's rows may repeat (passes): keep each voxel's last
    keys = {tuple(map(int, row[:3])): k for k, row in enumerate(rows)}
    ks = np.array(sorted(keys.values()))
    q, dens, patch_in, inn, outt, surf = rows[ks, :3], rows[ks, 3], rows[ks, 5], rows[ks, 6], rows[ks, 7], rows[ks, 8]
    air = (rows[ks, 11:17] == 9).sum(1)  # boundary faces (the hook writes 9 for a boundary face without a link flow)
    link_in = inn - patch_in
    depth = float(__import__("re").search(r"r (\d+) cm", case.what).group(1)) / 100 / case.voxel - r[ks]
    tau = dens * case.sigma_t / case.rho * case.voxel
    lit = (patch_in > 0) & (mu0[ks] >= 0.3)
    print(f"{name}: beam budget per unknown (sun, G), W summed per class; lit surface voxels mu0 >= 0.3")
    print("  class                      voxels  air faces  patch in  link in   out      out/in  clipped (out-in)+  scattered/a'")
    def line(label, k):
        if not k.any(): return
        pi, li, o = patch_in[k].sum(), link_in[k].sum(), outt[k].sum()
        clip = np.maximum(0, outt[k] - inn[k]).sum(); sc = np.maximum(0, inn[k] - outt[k]).sum()
        print(f"  {label:26s} {k.sum():5d}  {air[k].mean():6.1f}     {pi:8.4g}  {li:8.4g}  {o:8.4g}  {o / max(pi + li, 1e-30):6.3f}  {clip:8.4g}  {sc:8.4g}")
    for d in np.unique(np.round(depth[lit], 2)):
        k = lit & (np.round(depth, 2) == d)
        line(f"lit, depth {d:+.2f} tau {tau[k].mean():.1f}", k)
    line("lit surface, all", lit)
    line("surface, not lit", (surf > 0) & ~lit)
    line("inner", surf == 0)
    allin = patch_in.sum(); sc = np.maximum(0, inn - outt).sum(); clip = np.maximum(0, outt - inn).sum()
    print(f"  whole ball: patches let in {allin:.4g} W, the nodes scatter {sc:.4g} / a' ({sc / allin:.3f} of it); "
          f"clipped out - in {clip:.4g} ({clip / allin:.3f})")


if budget:
    print_budget(); sys.exit()
ret, once, missed, diff, esc = rows[:, 5], rows[:, 6], rows[:, 7], rows[:, 8], rows[:, 9]
print(f"{name}: {len(rows)} sunlit smooth patches; shares of what the half-space returns (P A), summed per band of the sphere's mu0")
print("  mu0 band   patches  at once  diffusion(node)  missed (A - scheme)  moved downstream  (leaving+missed)/PA")
for lo, hi in ((0.9, 1.01), (0.7, 0.9), (0.5, 0.7), (0.3, 0.5), (0.1, 0.3), (-1, 0.1)):
    k = (mu0 >= lo) & (mu0 < hi)
    if not k.any(): continue
    R = ret[k].sum()
    print(f"  {lo:4.1f}-{hi:4.2f}  {k.sum():4d}     {once[k].sum() / R:6.3f}   {diff[k].sum() / R:6.3f}           {missed[k].sum() / R:+6.3f}              "
          f"{(once[k] + missed[k]).sum() / R:6.3f}            {(esc[k] + diff[k] + missed[k]).sum() / R:6.3f}")
