"""What light tracing costs (docs/bake.md, Method 3) in a bake that light traces: a cube of thin snow too large to
gather per voxel (`--side` voxels of 1 cm a side, optical depth `--tau` per voxel, albedo 0.999, `--g`; a sun 30
degrees up and a sky), baked by two builds alternating in one run (the machine's load shared alike). Per bake: the
trace's processor seconds (stats["cpu_seconds"]["trace"]), the photons and the bytes of the per-voxel sums the
photons add to (stats["light_tracing_bytes"]; a build without that statistic held 792 bytes per light-traced
voxel: ArrivingLight with the 39 directions' sums in every voxel); then whether both builds' grids are identical.
At g 0.8 and above the thin voxels are fitted by direction and gather the 39 directions (traced_source.h), below
not. `--ground`: an open ground plane (two triangles, albedo 0.5) under the cube as the occluders, the spray's
usual scene (no closed surface: nothing is enclosed). `--ski`: a closed box 0.37 voxel thick and 10 voxels wide
across the cube inside its middle layer of voxels (a ski in a spray: outsideShare's cut voxels, 10 of each 40 of
that layer); `--ski-far`: the same box 10 m under the cube (closed, far from every voxel).

    /usr/bin/python3 bench/light_tracing_cost.py BUILD_A/python BUILD_B/python [--side 40] [--tau 0.5] [--g 0.7]
        [--rounds 2] [--ground] [--ski | --ski-far]
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
import numpy as np
sys.path.insert(0, sys.argv[1])
import firncore
path, tau, g, ground = sys.argv[2], float(sys.argv[3]), float(sys.argv[5]), float(sys.argv[6])
ski = json.loads(sys.argv[7])  # [lo, hi] of a closed box, or null
z = -0.006  # m: just under the cube's lowest voxels
occluders = [] if ground <= 0.0 else [(np.array([(-1, -1, z), (ground, -1, z), (ground, ground, z), (-1, ground, z)],
                                                np.float32), np.array([(0, 1, 2), (0, 2, 3)], np.uint32), (0.5,) * 3)]
if ski:
    corners = np.array([[ski[i & 1][0], ski[i >> 1 & 1][1], ski[i >> 2][2]] for i in range(8)], np.float32)
    faces = [(0, 2, 1), (1, 2, 3), (4, 5, 6), (5, 7, 6), (0, 1, 4), (1, 5, 4), (2, 6, 3), (3, 6, 7), (0, 4, 2),
             (2, 4, 6), (1, 3, 5), (3, 7, 5)]  # wound outwards
    occluders.append((corners, np.array(faces, np.uint32), (0.5,) * 3))
optics = firncore.VolumeOptics(tau / (0.01 * 300.0), (0.999,) * 3, g)  # m^2/kg: tau per voxel at 300 kg/m^3
sun = firncore.SunLight((math.cos(math.radians(30.0)), 0.0, math.sin(math.radians(30.0))), (1.0,) * 3, 0.0093)
stats = firncore.bake(path, optics, suns=[sun], sky=firncore.Sky((0.05,) * 3), occluders=occluders,
                      output_path=sys.argv[4])
print(json.dumps({"trace_cpu_s": stats["cpu_seconds"]["trace"], "photons": stats["photons"],
                  "voxels": stats["light_traced_voxels"],
                  "bytes": stats.get("light_tracing_bytes", 792 * stats["light_traced_voxels"])}))
"""


def cloud(path, side, density=300.0):
    import numpy as np
    import pyopenvdb

    grid = pyopenvdb.FloatGrid()
    grid.name = "density"
    grid.transform = pyopenvdb.createLinearTransform(voxelSize=VOXEL)
    grid.copyFromArray(np.full((side,) * 3, density, np.float32), tolerance=0.0)
    pyopenvdb.write(path, grids=[grid])


def bake(build, path, tau, g, output, ground, ski):
    env = dict(os.environ, PYTHONPATH=os.path.abspath(build))
    out = subprocess.run([sys.executable, "-c", BAKE, os.path.abspath(build), path, str(tau), output, str(g),
                          str(ground), json.dumps(ski)],
                         env=env, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("builds", nargs=2, help="two folders holding firncore (build/python)")
    parser.add_argument("--side", type=int, default=40)
    parser.add_argument("--tau", type=float, default=0.5)
    parser.add_argument("--g", type=float, default=0.7)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--ground", action="store_true", help="an open ground plane under the cube")
    parser.add_argument("--ski", action="store_true", help="a closed box 0.37 voxel thick in the middle layer")
    parser.add_argument("--ski-far", action="store_true", help="that box 10 m under the cube")
    args = parser.parse_args()
    middle = (args.side // 2) * VOXEL  # m: the middle layer's centres
    ski = None
    if args.ski or args.ski_far:
        drop = 10.0 if args.ski_far else 0.0
        ski = [[-0.1, 0.1, middle + 0.05 * VOXEL - drop], [args.side * VOXEL + 0.1, 0.2, middle + 0.42 * VOXEL - drop]]
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from grids_identical import compare

    with tempfile.TemporaryDirectory() as folder:
        density = os.path.join(folder, "cloud.vdb")
        cloud(density, args.side)
        runs = {b: [] for b in args.builds}
        for _ in range(args.rounds):
            for k, b in enumerate(args.builds):
                runs[b].append(bake(b, density, args.tau, args.g, os.path.join(folder, f"baked{k}.vdb"),
                                    args.side * VOXEL + 1.0 if args.ground else 0.0, ski))
        for b in args.builds:
            r = runs[b]
            seconds = ", ".join(f"{x['trace_cpu_s']:.2f}" for x in r)
            print(f"{b}: {r[0]['voxels']} light-traced voxels, {r[0]['photons']} photons, sums "
                  f"{r[0]['bytes'] / 2**20:.2f} MiB; trace processor s {seconds} (min {min(x['trace_cpu_s'] for x in r):.2f})")
        compare(os.path.join(folder, "baked0.vdb"), os.path.join(folder, "baked1.vdb"))


if __name__ == "__main__":
    main()
