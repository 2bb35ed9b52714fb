"""The sun skimming a grazing face beside a lit vertical edge, against the core's Monte Carlo (docs/benchmarks.md,
edge-skim).

slab_thick's worst block ((90, 80) row 0 col 0) runs down the +y face's density ramp beside the lit +x face (the sun
from +x at 30 degrees lies in the +y face's plane). Printed per probe ray, green: the Monte Carlo, the bake (FINAL,
seed 0) and their ratio, in the scene as it is and with a black screen standing beyond the lit face's ramp over the
strip outside the grazing face's half level (x past the lit face's ramp, y beyond the grazing face's half-density
plane, every height): the screen takes away only the sun that would enter the grazing face's ramp from the edge,
which no face's intake counts; the difference is that light (its single scattering in the ramp and all it becomes).
Probes: (1) the worst block's ray shifted along the image's u (across x, quarter voxels); (2) points on the grazing
face's half-density plane at 0.125 .. 3.5 voxels in from the lit face's plane at the block's depth-one height, seen
head-on and along the block's direction (box_sharp: its +x/-y vertical edge, no block; seen from above instead).

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/edge_skim.py [--case slab_thick] [--paths 8192]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from edge_blocks import image_axis

# case: (block's view, row, column; None: no block), the edge voxel column's (x, y), the lit face's normal, the grazing face's normal,
# the probes' height (voxels)
EDGES = {
    "slab_thick": ((2, 0, 0), (25, 25), (1, 0, 0), (0, 1, 0), 15.0),
    "box_sharp": (None, (13, 2), (1, 0, 0), (0, -1, 0), 4.0),
}
IN = (0.125, 0.375, 0.625, 0.875, 1.25, 1.75, 2.5, 3.5)  # voxels in from the lit face's half-density plane


def screen(case, column, lit, grazing):
    """A black vertical quad beyond the lit face's ramp (1.2 voxels out of its half level) over the strip outside the
    grazing face's half level, every height."""
    h = case.voxel
    lit, grazing = np.array(lit, float), np.array(grazing, float)
    edge = np.array([column[0], column[1], 0.0]) + 0.5 * lit + 0.5 * grazing  # the two half levels' corner, z 0
    top = case.density.shape[2] + 10.0
    a, b = edge + 1.2 * lit, edge + 1.2 * lit + 6.0 * grazing
    vertices = np.array([a + [0, 0, -10.0], b + [0, 0, -10.0], b + [0, 0, top], a + [0, 0, top]]) * h
    return vertices, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32), (0.0, 0.0, 0.0)


def rays(case):
    block, edge, lit, grazing, z = EDGES[case.name]
    h = case.voxel
    out_o, out_d, labels = [], [], []
    seen = -np.array(grazing, float) - np.array([0.0, 0.0, 5.0])  # travel: down, a little into the face
    if block:
        view, row, column = block
        origins, directions, _ = bake_suite.views(case)
        k = view * case.pixels ** 2 + row * case.pixels + column
        along = image_axis(case, view, "u")
        for s in np.arange(-4, 7) / 4.0:
            out_o.append(origins[k] + s * h * along), out_d.append(directions[k])
            labels.append(f"block shifted u {s:+.2f}")
        seen = directions[k]
    lit, grazing = np.array(lit, float), np.array(grazing, float)
    corner = np.array([edge[0], edge[1], z]) + 0.5 * lit + 0.5 * grazing
    for way, w in (("head-on", grazing), ("block's", -seen / np.linalg.norm(seen))):
        for s in IN:
            point = (corner - s * lit) * h
            out_o.append(point + 0.3 * w), out_d.append(-w)
            labels.append(f"{way:<8} {s:5.3f} in")
    return np.array(out_o), np.array(out_d), labels


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="slab_thick", choices=sorted(EDGES))
    parser.add_argument("--paths", type=int, default=8192)
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_edge_skim"))
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    _, edge, lit, grazing, _ = EDGES[case.name]
    origins, directions, labels = rays(case)
    results = {}
    for name, occluders in (("as is", []), ("screen", [screen(case, edge, lit, grazing)])):
        case.occluders = occluders
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, case.name + ".vdb")
            bake_suite.write_density(path, case.density, case.voxel)
            cached = os.path.join(args.cache, f"{case.name}_{name.replace(' ', '_')}_{args.paths}.npz")
            mc, error, _ = bake_suite.cached_monte_carlo(cached, case, path, origins, directions, args.paths, seed=13)
            firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=occluders,
                          quality="FINAL", seed=0)
            baked = firncore.render_baked(path, case.optics, origins, directions, occluders=occluders)
        results[name] = (mc[:, 1], error[:, 1], baked[:, 1])
    print(f"{case.name}: Monte Carlo (noise %) / bake, green; the screen takes the sun entering the grazing face's "
          f"ramp from the edge; 'skim' = as is - screen")
    print(f"  {'ray':<26} {'MC as is':>15} {'bake':>8} {'ratio':>6}   {'MC screen':>15} {'bake':>8} {'ratio':>6}   "
          f"{'skim MC':>8} {'bake':>8}")
    for k, label in enumerate(labels):
        row = []
        for name in ("as is", "screen"):
            m, e, b = (x[k] for x in results[name])
            row.append(f"{m:8.5f} ({100 * e / max(m, 1e-30):4.1f}) {b:8.5f} {b / max(m, 1e-30):6.3f}")
        skim_mc = results["as is"][0][k] - results["screen"][0][k]
        skim_b = results["as is"][2][k] - results["screen"][2][k]
        print(f"  {label:<26} {row[0]}   {row[1]}   {skim_mc:8.5f} {skim_b:8.5f}")


if __name__ == "__main__":
    main()
