"""Where a ball's sun leaves: the bake's power by angle to the sun against the core's Monte Carlo's, under scratch
switches of the sun's half-space return (docs/benchmarks.md, lead-100).

The sun alone (the suite case's sun, no sky), green. Views in the sun's plane towards the horizon at angle theta from
the sun (ball_energy_balance.py's rays), each view's power sum(L) dA per W of sun entering the ball; integrated over
the sphere (its symmetry about the sun assumed) into the half the sun lights (theta < 90: light leaving on the side
it entered) and the half against it (theta > 90: the limb's forward light and what crossed the ball). The Monte Carlo's power (the same rays,
--samples paths per ray, seed 7) is cached in --cache. Each --settings entry is `name:VAR=value,VAR=value` (empty:
main's bake), the variables set in the environment before that bake; with the scratch core of
`bench/ball_sun_return_switch.diff` they are
  FIRN_SW_MISSED k   scales what the sun's half-space return (the sun lobe's albedo) adds beyond the voxel scheme's
                     own (sunMissed: extra light, not conserved, leaving at and downstream of the entry patch),
  FIRN_SW_ATONCE k   keeps k of the sun's light that the scheme lets escape at once at the entry patch (sunEscaped),
                     the rest into the node's source (carried by the solve; conserved),
  FIRN_PROBE_HEMI    (always set here) the core prints the green sun terms summed over surface patches by the
                     cosine of their normal to the sun: W in, escaped at once, the solve's leaving, the half-space's
                     missed, its whole return; the last surfaceLight call's lines are shown.
Without the scratch core the variables do nothing and every setting bakes main's.
--suite-samples N: instead, the suite's own views and blocks (bake_suite.run_case) of the case with its sky removed,
a reference of N paths per block cached in --cache; per view the bias over all seen blocks, over the inner ones
(the ray passing within 0.6 of the ball's radius of its centre) and the outer ones (the rest, limb and rim), and
each part's mean |relative error| per block. --with-sky: the case as the suite bakes it (its sky kept, its own
reference paths per block, the suite's cached reference when --cache is the suite run's).

    PYTHONPATH=build/python:bench python3 bench/ball_sun_return.py [--case ball_deep] [--step 15] [--pixels 12]
        [--samples 1024] [--cache /tmp/lead100_cache] [--settings "main:;missed0:FIRN_SW_MISSED=0"]
        [--suite-samples 4096 [--with-sky]]
"""

import argparse
import dataclasses
import math
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore
from ball_energy_balance import sun_entering, towards_camera, view_rays


def captured_bake(path, case):
    """Bake the sun alone (FINAL, seed 0), returning the core's HEMI probe lines of its last surfaceLight call."""
    with tempfile.TemporaryFile(mode="w+b") as err:
        saved = os.dup(2)
        os.dup2(err.fileno(), 2)
        try:
            firncore.bake(path, case.optics, quality="FINAL", seed=0, suns=case.suns())
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        err.seek(0)
        lines = [l for l in err.read().decode(errors="replace").splitlines() if l.startswith("HEMI")]
    return lines[-4:]


def halves(thetas, power):
    """2 pi int f sin(theta) dtheta over theta < 90 and theta > 90 (midpoint rule)."""
    t = np.radians(thetas)
    w = 2.0 * math.pi * np.sin(t) * (t[1] - t[0])
    lit = thetas < 90.0
    return float((power * w)[lit].sum()), float((power * w)[~lit].sum())


def settings_of(entry):
    """(name, the variables set) of a --settings entry, the environment set for it."""
    name, _, assignments = entry.partition(":")
    set_here = dict(a.split("=", 1) for a in assignments.split(",") if a)
    for var in ("FIRN_SW_MISSED", "FIRN_SW_ATONCE"):
        os.environ.pop(var, None)
    os.environ.update(set_here)
    return name, set_here


def suite_views(case, args):
    """The suite's views of the case under the sun alone, per setting: mean, bias, per view all / inner / outer."""
    sun_only = case if args.with_sky else dataclasses.replace(case, sky=0.0, samples=args.suite_samples)
    print(f"{case.name} " + ("as the suite bakes it (sun and sky)" if args.with_sky else "under the sun alone") +
          f", the suite's views and blocks; reference {sun_only.samples} paths per block")
    os.environ.pop("FIRN_PROBE_HEMI", None)
    with tempfile.TemporaryDirectory() as folder:
        for entry in args.settings.split(";"):
            name, set_here = settings_of(entry)
            r = bs.run_case(sun_only, folder, args.cache)
            run = bs.baked_case(sun_only, os.path.join(folder, "again.vdb"), args.cache)  # the same bake, its rays
            baked = firncore.render_baked(os.path.join(folder, "again.vdb"), case.optics, run.origins, run.directions)
            n = np.array(case.density.shape)
            centre = (n - 1) / 2 * case.voxel
            radius = 0.5 * (np.ptp(np.argwhere(case.density > 0.5 * case.density.max())[:, 0]) + 1) * case.voxel
            offset = run.origins - centre
            across = np.linalg.norm(offset - (offset * run.directions).sum(1)[:, None] * run.directions, axis=1)
            seen = run.tau >= 1.0
            per = case.pixels ** 2
            print(f"  [{name}] {set_here or 'main'}: mean {100 * r['mean']:.1f} %, bias {100 * r['bias']:+.1f} %, "
                  f"ref noise {100 * r['noise']:.1f} %, ref s {r['reference_s']:.0f}")
            for v, view in enumerate(case.views):
                k = slice(v * per, (v + 1) * per)
                parts = []
                for what, pick in (("all", seen[k]), ("inner", seen[k] & (across[k] < 0.6 * radius)),
                                   ("outer", seen[k] & (across[k] >= 0.6 * radius))):
                    b, m = baked[k][pick].sum(), run.mean[k][pick].sum()
                    error = np.abs(baked[k][pick] / np.maximum(run.mean[k][pick], 1e-30) - 1.0).mean()
                    parts.append(f"{what} {b / m - 1:+6.1%} ({pick.sum()} px, MC {m:.4g}, mean |err| {error:.1%})")
                print(f"    view {view}: " + ", ".join(parts))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_deep")
    parser.add_argument("--step", type=float, default=15.0, help="deg between views in the sun's plane")
    parser.add_argument("--pixels", type=int, default=12, help="per side of each view")
    parser.add_argument("--samples", type=int, default=1024, help="Monte Carlo paths per ray")
    parser.add_argument("--cache", default="/tmp/lead100_cache")
    parser.add_argument("--settings", default="main:", help="name:VAR=value,... entries separated by ';'")
    parser.add_argument("--suite-samples", type=int, default=0, help="the suite's views instead (paths per block)")
    parser.add_argument("--with-sky", action="store_true", help="with --suite-samples: the sky kept, the case's paths")
    args = parser.parse_args()
    case = bs.case(args.case)
    if args.suite_samples:
        suite_views(case, args)
        return
    thetas = np.arange(args.step / 2, 180.0, args.step)
    rays = [view_rays(case, towards_camera(-t), args.pixels) for t in thetas]
    origins = np.concatenate([o for o, _, _ in rays])
    directions = np.concatenate([d for _, d, _ in rays])
    area = rays[0][2]
    entering = sun_entering(case, args.pixels)
    os.makedirs(args.cache, exist_ok=True)
    file = os.path.join(args.cache, f"sun_return_{case.name}_{case.key()}_{args.step:g}_{args.pixels}_{args.samples}.npz")
    os.environ["FIRN_PROBE_HEMI"] = "1"
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "snow.vdb")
        bs.write_density(path, case.density, case.voxel)
        if os.path.exists(file):
            mc = np.load(file)["power"]
        else:
            mean, _ = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                                    samples=args.samples, seed=7)
            mc = mean[:, 1].reshape(len(thetas), -1).sum(1) * area / entering
            np.savez(file, power=mc)
        mc_lit, mc_far = halves(thetas, mc)
        print(f"{case.name}: {case.what}; the sun alone, green, {args.pixels}^2 px per view, views every "
              f"{args.step:g} deg towards the horizon; Monte Carlo {args.samples} paths per ray")
        print(f"  Monte Carlo, per W entering: sunlit half (theta < 90) {mc_lit:.4f}, far half {mc_far:.4f}, "
              f"all {mc_lit + mc_far:.4f}")
        print("  theta: " + " ".join(f"{t:6.1f}" for t in thetas))
        print("  MC/sr: " + " ".join(f"{p:6.4f}" for p in mc))
        for entry in args.settings.split(";"):
            name, set_here = settings_of(entry)
            probe = captured_bake(path, case)
            baked = np.array([firncore.render_baked(path, case.optics, o, d)[:, 1].sum() * area
                              for o, d, _ in rays]) / entering
            lit, far = halves(thetas, baked)
            print(f"  [{name}] {set_here or 'main'}: sunlit half {lit:.4f} ({lit / mc_lit - 1:+.1%}), far half "
                  f"{far:.4f} ({far / mc_far - 1:+.1%}), all {lit + far:.4f} ({(lit + far) / (mc_lit + mc_far) - 1:+.1%})"
                  f"; moved from MC: sunlit {lit - mc_lit:+.4f}, far {far - mc_far:+.4f}")
            print("    baked/MC-1: " + " ".join(f"{b / m - 1:+6.1%}" for b, m in zip(baked, mc)))
            for line in probe:
                print("    " + line)


if __name__ == "__main__":
    main()
