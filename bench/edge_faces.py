"""box_sharp's edge voxels face by face: the baked render against the core's Monte Carlo on rays that reach each air face
of a sharp edge voxel (docs/benchmarks.md, edge-faces).

For edge voxels in the middle of the box's edges (lit top against the shadowed -x side, the grazing -y side, the
sunlit +x side; the bottom; the vertical edges), each of the voxel's two air faces is hit at three points across it
(a quarter, half and three quarters of a voxel from the edge, on the density's half level, in the middle along the
edge) from three directions towards the viewer: the face's normal ("head-on"), the diagonal between the two faces
("both": the camera sees both faces; the two faces' rows at it are the same direction), and the normal tilted as far
away from the other face ("own": only this face seen). Printed per face and direction: the Monte Carlo's radiance
(green), the bake's / Monte Carlo's, at each point.

    PYTHONPATH=build/python python3 bench/edge_faces.py [--case box_sharp] [--paths 4096] [--ground ALBEDO]

--ground puts a flat occluder under the box at its bottom (albedo grey, 0 = black) as plate-side's probe did.
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import firncore

# (voxel, air face normals), box_sharp's full voxels x 2..13, y 2..11, z 2..7 (sun from +x at 30 degrees).
EDGES = [
    ("top/-x (lit top, shadowed side)", (2, 6, 7), [(0, 0, 1), (-1, 0, 0)]),
    ("top/-y (lit top, grazing side)", (7, 2, 7), [(0, 0, 1), (0, -1, 0)]),
    ("top/+x (lit top, lit side)", (13, 6, 7), [(0, 0, 1), (1, 0, 0)]),
    ("bottom/+x (dark bottom, lit side)", (13, 6, 2), [(0, 0, -1), (1, 0, 0)]),
    ("bottom/-y (dark bottom, grazing side)", (7, 2, 2), [(0, 0, -1), (0, -1, 0)]),
    ("+x/-y vertical (lit side, grazing side)", (13, 2, 4), [(1, 0, 0), (0, -1, 0)]),
    ("-x/-y vertical (shadowed side, grazing side)", (2, 2, 4), [(-1, 0, 0), (0, -1, 0)]),
]
ACROSS = (0.25, 0.5, 0.75)  # voxels from the edge, on the face


def rays(case):
    """Origins, directions and labels (edge, face, direction, point) of every probe ray."""
    h = case.voxel
    origins, directions, labels = [], [], []
    for name, voxel, normals in EDGES:
        centre = np.array(voxel, dtype=float)
        for f, n in enumerate(normals):
            n = np.array(n, dtype=float)
            m = np.array(normals[1 - f], dtype=float)  # the other face's normal
            for way, w in (("head-on", n), ("both", n + m), ("own", n - m)):
                w = w / np.linalg.norm(w)
                for s in ACROSS:
                    point = (centre + 0.5 * n + (0.5 - s) * m) * h  # on the face's half-density plane
                    origins.append(point + 0.5 * w)
                    directions.append(-w)
                    labels.append((name, f, tuple(int(x) for x in n), way, s))
    return np.array(origins), np.array(directions), labels


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="box_sharp")
    parser.add_argument("--paths", type=int, default=4096)
    parser.add_argument("--ground", type=float, default=-1.0, help="albedo of a ground plane under the box (none < 0)")
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_edge_faces"))
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    if args.ground >= 0.0:
        bottom = (2 - 0.5) * case.voxel - 1e-4
        case.occluders = [bake_suite.plate(-1.0, 2.0, -1.0, 2.0, bottom, (args.ground,) * 3)]
    origins, directions, labels = rays(case)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        # bake_suite's kept Monte Carlo; _mc: not the older files' keys (mc, error)
        cached = os.path.join(args.cache, f"{case.name}_{args.ground:g}_{args.paths}_mc.npz")
        mc, error, _ = bake_suite.cached_monte_carlo(cached, case, path, origins, directions, args.paths, seed=11)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                      quality="FINAL", seed=0)
        baked = firncore.render_baked(path, case.optics, origins, directions, occluders=case.occluders)
    ratio = np.where(mc[:, 1] > 0.0, baked[:, 1] / np.maximum(mc[:, 1], 1e-30), np.nan)
    if args.ground >= 0.0:
        ratio[directions[:, 2] > 0.0] = np.nan  # seen from under the ground: not the snow's light
    print(f"{case.name}, ground {'none' if args.ground < 0 else args.ground}: bake / Monte Carlo (green) at "
          f"{', '.join(f'{s:g}' for s in ACROSS)} voxel from the edge; Monte Carlo radiance in brackets, noise "
          f"{100 * np.nanmedian(error[:, 1] / mc[:, 1]):.1f} %; '-' seen from under the ground")
    errors = []
    for k in range(0, len(labels), len(ACROSS)):
        name, f, n, way, _ = labels[k]
        if f == 0 and way == "head-on":
            print(f"  {name}")
        cut = slice(k, k + len(ACROSS))
        errors += list(np.abs(ratio[cut] - 1.0))
        print(f"    face {str(n):<12} {way:<8} " + "  ".join(
            f"{r:5.2f} ({m:.4f})" if np.isfinite(r) else "    -          " for r, m in zip(ratio[cut], mc[cut, 1])))
    print(f"  mean |bake / Monte Carlo - 1| {100 * np.nanmean(errors):.1f} % over the rays seen from above the ground")


if __name__ == "__main__":
    main()
