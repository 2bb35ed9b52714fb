"""The shadowed side under a lit top, across its edge voxel and the one below: what lights it, measured with the core's
Monte Carlo and the bake (docs/benchmarks.md, corner-fwd).

box_sharp's top/-x edge (voxel (2, 6, 7); the box's full voxels x 2..13, y 2..11, z 2..7), the sun alone (no sky) at
the case's elevation (30 degrees: mu0 0.5 on the top), from +x (its light travels towards the -x side: forward light
crosses the corner) or from +y (the top lit alike, the -x side grazed: its light then is the top's diffuse light that
leaks round the corner, not the sun's forward light). The -x face hit at depths 0.125 .. 1.75 voxel below the edge on
its half-density plane, seen head-on, "both" (the diagonal between top and side) and "own" (the normal tilted away
from the top, downwards): green radiance, Monte Carlo and bake.

With --voxels also the baked source S(w) (broad + peaked lobe, green) of the voxels around the edge in its y = 6
slice, x 1..3 (the air across the side, the edge voxel, the top beside it), z 5..8 (the air row above the edge down
the side), towards each of the three ways (bench/spray_shade_probe.py's `lobes`; docs/benchmarks.md, corner-lean).

    PYTHONPATH=build/python python3 bench/corner_light.py [--paths 4096] [--voxels]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore

DEPTHS = (0.125, 0.375, 0.625, 0.875, 1.25, 1.75)  # voxels below the top edge, on the -x face
WAYS = (("head-on", (-1.0, 0.0, 0.0)), ("both", (-1.0, 0.0, 1.0)), ("own", (-1.0, 0.0, -1.0)))


def rays(h):
    origins, directions = [], []
    for _, w in WAYS:
        w = np.array(w) / np.linalg.norm(w)
        for s in DEPTHS:
            point = np.array([2 - 0.5, 6.0, 7 + 0.5 - s]) * h
            origins.append(point + 0.5 * w)
            directions.append(-w)
    return np.array(origins), np.array(directions)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--paths", type=int, default=4096)
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_corner_light"))
    parser.add_argument("--voxels", action="store_true", help="print the baked source of the voxels around the edge")
    args = parser.parse_args()
    case = bake_suite.case("box_sharp")
    e = bake_suite.SUN_ELEVATION
    suns = {"+x": (math.cos(e), 0.0, math.sin(e)), "+y": (0.0, math.cos(e), math.sin(e))}
    origins, directions = rays(case.voxel)
    os.makedirs(args.cache, exist_ok=True)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "box.vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        for name, d in suns.items():
            sun = [firncore.SunLight(d, (case.sun,) * 3, 0.0093)]
            cached = os.path.join(args.cache, f"sun{name}_{args.paths}.npz")
            if os.path.exists(cached):
                mc, error = (np.load(cached)[k] for k in ("mc", "error"))
            else:
                mc, error = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=sun, sky=None,
                                                          occluders=[], samples=args.paths, seed=11)
                np.savez(cached, mc=mc, error=error)
            firncore.bake(path, case.optics, suns=sun, sky=None, occluders=[], quality="FINAL", seed=0)
            baked = firncore.render_baked(path, case.optics, origins, directions, occluders=[])
            print(f"sun from {name}: the -x face at {', '.join(f'{s:g}' for s in DEPTHS)} voxel below the top edge, "
                  f"Monte Carlo (noise {100 * np.median(error[:, 1] / mc[:, 1]):.1f} %) / bake, green")
            for k, (way, _) in enumerate(WAYS):
                cut = slice(k * len(DEPTHS), (k + 1) * len(DEPTHS))
                print(f"  {way:<8} MC   " + "  ".join(f"{m:.4f}" for m in mc[cut, 1]))
                print(f"  {'':<8} bake " + "  ".join(f"{b:.4f}" for b in baked[cut, 1]))
            if args.voxels:
                print_voxels(path, case.voxel)


def print_voxels(path, h):
    """The baked source S(w) (broad + peaked, green) of voxels (x, 6, z), x 1..3, z 8..5, towards each way."""
    from spray_shade_probe import grid_values, lobes
    voxels = [(x, 6, z) for z in (8, 7, 6, 5) for x in (1, 2, 3)]
    values = grid_values(path, np.array(voxels, dtype=np.float64) * h)
    for way, w in WAYS:
        w = np.array(w) / np.linalg.norm(w)
        broad, peak = lobes(values, w, "broad")[:, 1], lobes(values, w, "peak")[:, 1]
        print(f"  {way:<8} source at (x, 6, z), broad + peak:")
        for row in range(4):
            cells = range(3 * row, 3 * row + 3)
            print("    " + "  ".join(f"{voxels[i]}: {broad[i]:.4f} + {peak[i]:.4f}" for i in cells))


if __name__ == "__main__":
    main()
