"""What light tracing costs (docs/bake.md, Method 3) in a bake that light traces: thrown snow over the snow it
flies over, as a spray's lumps in the joint medium (their paths enter the thick snow: too costly to gather per
voxel). `--lumps` lumps of 0.5-1.5 cm radius through a 40 x 40 x 30 cm box on 1 cm voxels (partly filled voxels at
their rims) over a layer 8 cm deep; full voxels of optical depth `--tau`; g 0.85, sun and sky; baked by two builds alternating
in one run (the machine's load shared alike). Per bake: the trace's processor seconds (stats["cpu_seconds"]
["trace"]), the photons and the bytes of the per-voxel sums the photons add to (stats["light_tracing_bytes"]; a
build without that statistic held 792 bytes per light-traced voxel: ArrivingLight with the 39 directions' sums in
every voxel), and whether both builds' grids are identical.

    /usr/bin/python3 bench/light_tracing_cost.py BUILD_A/python BUILD_B/python [--lumps 400] [--tau 6] [--rounds 3]
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

VOXEL = 0.01  # m
BAKE = r"""
import json, math, sys
sys.path.insert(0, sys.argv[1])
import firncore
path, tau = sys.argv[2], float(sys.argv[3])
optics = firncore.VolumeOptics(tau / (0.01 * 300.0), (0.999,) * 3, 0.85)  # m^2/kg: tau per full voxel at 300 kg/m^3
sun = firncore.SunLight((math.cos(math.radians(30.0)), 0.0, math.sin(math.radians(30.0))), (1.0,) * 3, 0.0093)
stats = firncore.bake(path, optics, suns=[sun], sky=firncore.Sky((0.05,) * 3), output_path=sys.argv[4])
print(json.dumps({"trace_cpu_s": stats["cpu_seconds"]["trace"], "photons": stats["photons"],
                  "voxels": stats["light_traced_voxels"],
                  "bytes": stats.get("light_tracing_bytes", 792 * stats["light_traced_voxels"])}))
"""


def cloud(path, lumps, seed=3):
    """The layer's and lumps' density (300 kg/m^3 where full), each lump's voxel the fraction of its 4^3 points
    inside it."""
    import numpy as np
    import pyopenvdb

    n, sub = 40, 4
    rng = np.random.default_rng(seed)
    fill = np.zeros((n, n, n))
    offsets = (np.arange(sub) + 0.5) / sub - 0.5
    fill[:, :, :8] = 1.0  # the layer
    centres = rng.uniform((0.03, 0.03, 0.1), (0.37, 0.37, 0.37), size=(lumps, 3))
    for centre, radius in zip(centres, rng.uniform(0.005, 0.015, size=lumps)):
        lo = np.maximum(np.floor((centre - radius) / VOXEL).astype(int) - 1, 0)
        hi = np.minimum(np.ceil((centre + radius) / VOXEL).astype(int) + 2, n)
        X, Y, Z = np.meshgrid(*(np.arange(lo[a], hi[a]) for a in range(3)), indexing="ij")
        inside = np.zeros(X.shape)
        for a in offsets:
            for b in offsets:
                for c in offsets:
                    d2 = ((X + a) * VOXEL - centre[0]) ** 2 + ((Y + b) * VOXEL - centre[1]) ** 2 + ((Z + c) * VOXEL - centre[2]) ** 2
                    inside += d2 < radius * radius
        box = fill[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]]
        np.maximum(box, inside / sub ** 3, out=box)
    grid = pyopenvdb.FloatGrid()
    grid.name = "density"
    grid.transform = pyopenvdb.createLinearTransform(voxelSize=VOXEL)
    grid.copyFromArray((fill * 300.0).astype(np.float32), tolerance=0.0)
    pyopenvdb.write(path, grids=[grid])


def bake(build, path, tau, output):
    env = dict(os.environ, PYTHONPATH=os.path.abspath(build))
    out = subprocess.run([sys.executable, "-c", BAKE, os.path.abspath(build), path, str(tau), output],
                         env=env, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("builds", nargs=2, help="two folders holding firncore (build/python)")
    parser.add_argument("--lumps", type=int, default=400)
    parser.add_argument("--tau", type=float, default=6.0, help="optical depth of a full voxel")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from grids_identical import compare

    with tempfile.TemporaryDirectory() as folder:
        density = os.path.join(folder, "cloud.vdb")
        cloud(density, args.lumps)
        runs = {b: [] for b in args.builds}
        for _ in range(args.rounds):
            for k, b in enumerate(args.builds):
                runs[b].append(bake(b, density, args.tau, os.path.join(folder, f"baked{k}.vdb")))
        for b in args.builds:
            r = runs[b]
            seconds = ", ".join(f"{x['trace_cpu_s']:.2f}" for x in r)
            print(f"{b}: {r[0]['voxels']} light-traced voxels, {r[0]['photons']} photons, sums "
                  f"{r[0]['bytes'] / 2**20:.2f} MiB; trace processor s {seconds} (min {min(x['trace_cpu_s'] for x in r):.2f})")
        compare(os.path.join(folder, "baked0.vdb"), os.path.join(folder, "baked1.vdb"))


if __name__ == "__main__":
    main()
