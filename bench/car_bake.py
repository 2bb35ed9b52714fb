"""The car sample's bake outside Blender (docs/bake.md, Performance and Memory): bake seconds, µs per active voxel,
the phases (`stats["seconds"]`, `stats["cpu_seconds"]`) and the bake's peak memory per active voxel, FINAL quality
on all the cores firncore sees, each bake in a fresh process (bench/bake_measure.py).

    PYTHONPATH=build/python /usr/bin/python3 bench/car_bake.py [FOLDER [repeats [seed]]]

FOLDER (default build/car_inputs, beside the build's add-on; $FIRN_BUILD as bench/run.sh) holds the car's bake inputs;
where it has none they are written first by `bench/run.sh bench/car_scene.py -- FOLDER` (Blender, about a minute),
so a fresh clone with a build needs only the line above.

Each bake reads a fresh copy of FOLDER's density (the core rewrites the file it bakes), and is followed by the slab
of bench/bake_scaling.py at 1 M voxels: the car's processor µs per active voxel over the slab's, measured side by
side so that the shared machine's load cancels (issue 10 item 4's ratio). With repeats > 1 the run ends with the
medians over the pairs and their ratio: one pair's ratio moved by 20 % between consecutive pairs on stop 73's
machine (docs/benchmarks.md, lead-73).
"""

import argparse
import os
import shutil
import statistics
import subprocess
import tempfile
import time

import bake_measure
import bake_scaling


HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_FOLDER = os.path.join(os.environ.get("FIRN_BUILD", os.path.join(HERE, "..", "build")), "car_inputs")


def car_folder(folder=None):
    """`folder` (default DEFAULT_FOLDER) holding the car's bake inputs, written by bench/car_scene.py (Blender through
    bench/run.sh) where it has none."""
    folder = os.path.abspath(folder or DEFAULT_FOLDER)
    if not os.path.exists(os.path.join(folder, "car_inputs.npz")):
        print(f"car inputs: none in {folder}; writing them (bench/car_scene.py in Blender)", flush=True)
        subprocess.run([os.path.join(HERE, "run.sh"), os.path.join(HERE, "car_scene.py"), "--", folder], check=True)
        if not os.path.exists(os.path.join(folder, "car_inputs.npz")):
            raise RuntimeError(f"bench/car_scene.py wrote no car_inputs.npz in {folder} (is Blender on the PATH?)")
    return folder


def car_inputs(folder):
    """The car's optics, suns, sky and occluders as bench/car_scene.py wrote them."""
    import numpy as np

    import firncore

    inputs = np.load(os.path.join(folder, "car_inputs.npz"))
    optics = firncore.VolumeOptics(float(inputs["optics_k"]), tuple(inputs["optics_albedo"]), float(inputs["optics_g"]))
    suns = [firncore.SunLight(tuple(d), tuple(e), float(a)) for d, e, a in
            zip(inputs["sun_direction"], inputs["sun_irradiance"], inputs["sun_angular_diameter"])]
    sky = firncore.Sky(tuple(inputs["sky_radiance"]), inputs["sky_map"] if "sky_map" in inputs else None)
    occluders = [(inputs[f"occluder_{k}_vertices"], inputs[f"occluder_{k}_triangles"],
                  tuple(inputs[f"occluder_{k}_albedo"])) for k in range(int(inputs["occluders"]))]
    return optics, suns, sky, occluders


def bake_car(folder, seed=0, progress=None):
    """One FINAL bake of the car's inputs (bench/car_scene.py); firncore's stats plus the active voxels. The core
    rewrites the density's file with the baked grids, as Bake Scattering does."""
    with tempfile.TemporaryDirectory() as scratch:
        path = shutil.copy(os.path.join(folder, "car_density.vdb"), scratch)
        return bake_copy(path, *car_inputs(folder), seed, progress)


def bake_copy(path, optics, suns, sky, occluders, seed, progress=None):
    import firncore

    started = time.perf_counter()
    stats = firncore.bake(path, optics, suns=suns, sky=sky, occluders=occluders, quality="FINAL", seed=seed,
                          progress=progress)
    stats["bake_call_seconds"] = time.perf_counter() - started  # the file read, baked and written, as Blender's call
    stats["voxels"] = firncore.grid_statistics(path, "density")["active_voxels"]
    return stats


def main():
    import firncore

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folder", nargs="?", help="the car's bake inputs (default: build/car_inputs, written if absent)")
    parser.add_argument("repeats", nargs="?", type=int, default=1)
    parser.add_argument("seed", nargs="?", type=int, default=0)
    args = parser.parse_args()
    folder, repeats, seed = car_folder(args.folder), args.repeats, args.seed
    print(f"firncore {firncore.__version__}, car sample, {firncore.hardware_threads()} threads, FINAL quality")
    print("wall: seconds on the clock; cpu: processor seconds of all threads (on a busy machine wall > cpu / threads)")
    pairs = []  # (car, slab) processor µs per active voxel
    for _ in range(repeats):
        load = os.getloadavg()[0]
        r = bake_measure.measure_fresh(bake_car, folder, seed)
        voxels = r["voxels"]
        print(f"{voxels} active voxels, {r['unknowns']} unknowns, {r['surface_voxels']} surface, "
              f"{r['traced_voxels']} traced, iterations {r['iterations']}; peak {r['peak_bytes'] / voxels:.0f} bytes "
              f"per active voxel ({r['peak_bytes'] / 1e6:.0f} MB); load average {load:.1f}")
        # total s below also holds the imports, the inputs' read and the voxel count's read of the file afterwards
        print(f"firncore.bake's own call {r['bake_call_seconds']:.2f} s wall")
        print(f"{'':>5} {'total s':>8} {'us/voxel':>8}  " + " ".join(f"{name:>8}" for name in r["seconds"]))
        # (per-phase processor time: firncore builds since bake-perf; earlier ones show the total only)
        for label, total, phases in (("wall", r["wall_seconds"], r["seconds"]),
                                     ("cpu", r["cpu_seconds_total"], r.get("cpu_seconds", {}))):
            print(f"{label:>5} {total:>8.2f} {1e6 * total / voxels:>8.2f}  " +
                  " ".join(f"{value:>8.2f}" for value in phases.values()), flush=True)
        with tempfile.TemporaryDirectory() as scratch:
            path = os.path.join(scratch, "slab.vdb")
            slab_voxels = bake_scaling.bumpy_layer(path, 1_000_000)
            slab = bake_measure.measure_fresh(bake_scaling.bake_layer, path)
        car_us, slab_us = 1e6 * r["cpu_seconds_total"] / voxels, 1e6 * slab["cpu_seconds_total"] / slab_voxels
        print(f"slab {slab_voxels} active voxels: cpu {slab['cpu_seconds_total']:.2f} s, {slab_us:.2f} us/voxel; "
              f"car / slab {car_us / slab_us:.2f}x", flush=True)
        pairs.append((car_us, slab_us))
    if len(pairs) > 1:
        print(median_summary(pairs))


def median_summary(pairs):
    """The medians of (car, slab) processor µs per active voxel over the pairs, and their ratio: one pair's ratio
    moves with the slab's few seconds on a shared machine, the medians' far less."""
    car, slab = statistics.median(c for c, _ in pairs), statistics.median(s for _, s in pairs)
    ratios = [c / s for c, s in pairs]
    return (f"over {len(pairs)} pairs: car median {car:.2f} us/voxel, slab median {slab:.2f} us/voxel; "
            f"car / slab of the medians {car / slab:.2f}x (pairs {min(ratios):.2f}-{max(ratios):.2f}x)")


if __name__ == "__main__":
    main()
