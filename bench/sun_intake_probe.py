"""The sun each surface voxel of bumpy_plate's layer takes in, the bake's (its patches' sunIn: read from a temporary
print, FIRN_PROBE_SUNIN, of bench/sun_intake_switch.diff) against the sun's rays marched through the density
(docs/benchmarks.md, bumpy-blocks).

The marched oracle: parallel sun rays 1 mm apart on a plane across the sun, each carrying E dA (1 W/m^2 across the
sun) and leaving (1 - exp(-tau)) of it in the snow (tau: the trilinear density's optical depth along the ray, 0.5 mm
steps); each ray's share goes to the surface voxel nearest where the ray reaches optical depth 1 (or, a ray that never
does, its deepest point). No plate (the plate's shadow falls off the layer), sun only, sun elevation 30 degrees.
Per kind of surface voxel (crest, slope, trough of the bump's phase; lit or self-shadowed by the top's normal; the
cut sides), the bake's intake over the marched intake.

    git apply bench/sun_intake_switch.diff && cmake --build build --target firncore
    PYTHONPATH=build/python:bench python3 bench/sun_intake_probe.py [--flat] [--reduced] [--against BUILD]
    (the switch's FIRN_PROBE_SUNSCALE=x multiplies every patch's sun: the sensitivity test in docs/benchmarks.md)

--reduced: the oracle's rays lose the similarity beam's sigma_tr, as the bake's beams do (what a crest's ramp scatters
forwards goes on to the next bump); --against BUILD: another firncore built with the switch (e.g. main's, with this
build carrying bench/sun_intake_marched.diff too), its intake per kind printed beside (docs/benchmarks.md,
bumpy-intake).
"""

import argparse
import copy
import math
import os
import pickle
import subprocess
import sys
import tempfile

import numpy as np

import bake_suite
import bumpy_blocks


def baked_intake(case, build=None):
    """Per surface voxel (i, j, k): the bake's green sunIn (W), from the switch's print in a child process (sun only,
    no plate); `build`: the folder holding that firncore (default: this process's PYTHONPATH)."""
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "layer.vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        pickled = os.path.join(folder, "case.pkl")
        with open(pickled, "wb") as f:
            pickle.dump((case.density, case.voxel), f)
        code = ("import sys, pickle, copy, bake_suite, firncore; d, h = pickle.load(open(sys.argv[2], 'rb')); "
                "c = copy.copy(bake_suite.case('bumpy_plate')); c.density = d; c.sky = 0.0; "
                "c.occluders = c.occluders[1:]; "
                "firncore.bake(sys.argv[1], c.optics, suns=c.suns(), sky=None, occluders=c.occluders, "
                "quality='FINAL', seed=0)")
        err = subprocess.run([sys.executable, "-c", code, path, pickled], capture_output=True, text=True,
                             env=dict(os.environ, FIRN_PROBE_SUNIN="1",
                                      **({"PYTHONPATH": build + os.pathsep + os.path.dirname(__file__)} if build
                                         else {}))).stderr
    out = {}
    for line in err.splitlines():
        if line.startswith("VOX "):
            i, j, k, w = line.split()[1:]
            out[(int(i), int(j), int(k))] = float(w)
    return out


def marched_intake(case, surface, spacing=0.001, step=0.0005, reduced=False):
    """Per surface voxel: the sun's power (W) its rays leave in the snow, by the rule in the module's text; `reduced`:
    the similarity beam's extinction (1 - omega g) sigma_t, green, as the bake's beams, instead of sigma_t."""
    sun = np.array([math.cos(bake_suite.SUN_ELEVATION), 0.0, math.sin(bake_suite.SUN_ELEVATION)])
    across = np.array([-sun[2], 0.0, sun[0]])
    n = np.array(case.density.shape)
    corners = np.array([[a, b, c] for a in (-1, n[0]) for b in (-1, n[1]) for c in (-1, n[2])]) * case.voxel
    v = corners @ across
    us = np.arange(-case.voxel, n[1] * case.voxel, spacing) + spacing / 2
    vs = np.arange(v.min(), v.max(), spacing) + spacing / 2
    U, V = np.meshgrid(us, vs, indexing="ij")
    starts = U.reshape(-1, 1) * np.array([0.0, 1.0, 0.0]) + V.reshape(-1, 1) * across + 0.6 * sun
    t = np.arange(0.0, 1.2, step)
    keys = np.array(list(surface))
    out = dict.fromkeys(surface, 0.0)
    sigma = case.sigma_t / case.rho * ((1.0 - case.omega[1] * case.g) if reduced else 1.0)
    for chunk in np.array_split(starts, max(1, len(starts) // 2000)):
        p = chunk[:, None, :] - t[None, :, None] * sun
        p = np.where(p[:, :, 2:3] > 0.005, p, 1e3)  # the ground stops the ray (1e3: outside the grid)
        dens = bake_suite.trilinear(case.density, p.reshape(-1, 3) / case.voxel).reshape(p.shape[:2])
        tau = np.cumsum(dens, 1) * step * sigma
        power = (1.0 - np.exp(-tau[:, -1])) * spacing ** 2
        at = np.minimum((tau < 1.0).sum(1), len(t) - 1)
        at = np.where(tau[:, -1] < 1.0, dens.argmax(1), at)
        hit = p[np.arange(len(p)), at] / case.voxel
        for q, w in zip(hit[power > 0], power[power > 0]):
            nearest = keys[np.argmin(((keys - q) ** 2).sum(1))]
            out[tuple(nearest)] += w
    return out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--flat", action="store_true", help="the layer flat (6 voxels) instead of bumpy")
    parser.add_argument("--reduced", action="store_true", help="the oracle's rays lose sigma_tr, not sigma_t")
    parser.add_argument("--against", metavar="BUILD", help="another firncore's folder (built with the switch): its "
                        "intake per kind beside this one's (bench/sun_intake_marched.diff against main)")
    args = parser.parse_args()
    case = copy.copy(bake_suite.case("bumpy_plate"))
    if args.flat:
        X, Y, Z = bake_suite.grid(case.density.shape)
        fill = np.clip(6.0 - Z + 0.5, 0.0, 1.0)
        fill[:, :, 0] = 0.0
        case.density = fill * case.rho
    baked = baked_intake(case)
    other = baked_intake(case, args.against) if args.against else None
    marched = marched_intake(case, baked, reduced=args.reduced)
    keys = np.array(list(baked))
    b = np.array([baked[k] for k in baked])
    m = np.array([marched[k] for k in baked])
    print(f"{'flat' if args.flat else 'bumpy'} layer, sun 30 deg: bake {b.sum():.5f} W, marched {m.sum():.5f} W "
          f"({100 * (b.sum() / m.sum() - 1):+.1f} %), {len(keys)} surface voxels")
    last = case.density.shape[0] - 1
    side = (keys[:, 0] == 0) | (keys[:, 0] == last) | (keys[:, 1] == 0) | (keys[:, 1] == last)
    phase = (bake_suite.bumpy_top(keys[:, 0], keys[:, 1], 6.0, 3.0) - 6.0) / 3.0
    normal = bumpy_blocks.top_normal(keys[:, 0].astype(float), keys[:, 1].astype(float))
    sun = np.array([math.cos(bake_suite.SUN_ELEVATION), 0.0, math.sin(bake_suite.SUN_ELEVATION)])
    lit = normal @ sun > 0.0
    kind = np.where(side, "cut side", np.where(phase > 0.5, "crest", np.where(phase < -0.5, "trough", "slope")))
    kind = np.where(side, kind, np.char.add(kind.astype(str), np.where(lit, " lit", " self-shadowed")))
    for k in sorted(set(kind)):
        w = kind == k
        print(f"  {k:<22} {w.sum():5d} voxels  bake {b[w].sum():.5f} W  marched {m[w].sum():.5f} W  "
              f"bake/marched {b[w].sum() / max(m[w].sum(), 1e-30):.3f}" +
              (f"  against {sum(other.get(tuple(q), 0.0) for q in keys[w]):.5f} W" if other else ""))


if __name__ == "__main__":
    main()
