"""spray_dense's baked light against the suite's reference by scattering order and by where the camera's first
collision falls in the trilinear hat (docs/benchmarks.md, spray-cores). Needs the core built with
bench/spray_cores_hooks.diff applied (made on main bd12301): FIRN_SC_HANDOFF=k makes the mixed render
(render_scattering_where_thin with every snow voxel scattering) trace the first k collisions exactly and take the
baked source at collision k + 1 (k 0: the baked render itself, as a collision estimate); FIRN_SC_GATE="lo hi" counts
only paths whose first collision has a snow hat share in [lo, hi) (with FIRN_SC_DIAG: the hat share of air voxels
with no snow face neighbour); FIRN_SC_PATHS=N bakes every traced voxel at N paths, their faces at N / 2, past the
budget. Per region the sum of a render over the reference's.

    PYTHONPATH=build/python python3 bench/spray_cores_split.py [--paths 2048] [--handoffs 0,1,2,4,8,16]
        [--bounces 1,3,15] [--gates "0 0.25,0.25 0.5,0.5 0.75,0.75 0.999,0.999 2"] [--samples 1024]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from suite_regions import regions


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--paths", type=int, default=0, help="FIRN_SC_PATHS for the bake (0: the preset's)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--samples", type=int, default=512, help="paths per block of each split render")
    parser.add_argument("--handoffs", default="0,1,2,4,8,16", help="exact collisions before the baked source")
    parser.add_argument("--bounces", default="1,3,15", help="the truth's orders 1..b+1 alone")
    parser.add_argument("--gates", default="", help="first-collision hat share bands 'lo hi,...' (lit cores only)")
    args = parser.parse_args()
    case = bake_suite.case("spray_dense")
    origins, directions, tau = bake_suite.views(case)
    seen, lit, core = regions(case, origins, directions, tau)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        reference, _, _ = bake_suite.reference(case, path, origins, directions,
                                               bake_suite.CACHE)
        if args.paths:
            os.environ["FIRN_SC_PATHS"] = str(args.paths)
        firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                      quality="FINAL", seed=args.seed)
        os.environ.pop("FIRN_SC_PATHS", None)
        at = np.nonzero(seen)[0]
        o, d, ref = origins[at], directions[at], reference[at]
        view = np.repeat(np.arange(len(case.views)), case.pixels ** 2)[at]
        L, C = lit[at], core[at]
        groups = [("all", np.ones(len(at), bool)), ("lit core", L & C), ("lit rim", L & ~C),
                  ("shad core", ~L & C), ("shad rim", ~L & ~C)] + [(f"{v}", view == i) for i, v in enumerate(case.views)]

        def split(env, rays=slice(None), bounces=1 << 30):
            os.environ.update(env)
            try:
                m, _ = firncore.render_scattering_where_thin(
                    path, case.optics, o[rays], d[rays], suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                    samples=args.samples, seed=77, thin_depth=1e9, traced_only=False,
                    bounces=bounces)
            finally:
                for k in env:
                    os.environ.pop(k, None)
            return m

        def show(name, x):
            print(f"{name:14s}" + "  ".join(f"{g} {x[w].sum() / ref[w].sum():.3f}" for g, w in groups if w.any()),
                  flush=True)

        show("baked", firncore.render_baked(path, case.optics, o, d, occluders=case.occluders))
        for b in [int(x) for x in args.bounces.split(",") if x]:
            show(f"truth <= {b + 1}", split({}, bounces=b))
        for k in [int(x) for x in args.handoffs.split(",") if x]:
            show(f"E{k}", split({"FIRN_SC_HANDOFF": str(k)}))
        if args.gates:
            cores = L & C
            whole = split({"FIRN_SC_GATE": "-1 9"}, cores)
            print(f"lit cores: the split's truth / reference {whole.sum() / ref[cores].sum():.3f}")
            for band in args.gates.split(","):
                truth = split({"FIRN_SC_GATE": band}, cores)
                baked = split({"FIRN_SC_GATE": band, "FIRN_SC_HANDOFF": "0"}, cores)
                print(f"  first collision's hat share in [{band.replace(' ', ', ')}): "
                      f"{truth.sum() / whole.sum():.3f} of the light, baked / truth {baked.sum() / truth.sum():.3f}",
                      flush=True)


if __name__ == "__main__":
    main()
