"""The low sun's overshoot over flat snow split into its parts (docs/benchmarks.md, grazing-peak): grazing_sun.py's
slab, views and suns, the baked render cut by lobe (broad: firn_source{,_x,_y,_z}; peaked: firn_source_peak{,_l1})
and by layer (deep: under the top layer; top: the top layer, z 7; ramp: the air voxels over it, z 8 and up), each
part rendered alone (the emission-absorption integral is linear in the emission), against the Monte Carlo's total
(grazing_sun.py's cached reference) and its single scattering (render_scattering_where_thin path tracing every voxel
with no bounce). Figures per view, in % of the Monte Carlo's total, green.

    PYTHONPATH=build/python:bench python3 bench/grazing_peak.py [--snows grey,issue] [--elevations 3,10]
        [--cache /tmp/firn_grazing_sun] [--single-samples 256]
"""

import argparse
import os
import tempfile

import numpy as np
import pyopenvdb

import firncore
import lamp_slab_pieces as pieces

LOBES = {"broad": ("firn_source", "firn_source_x", "firn_source_y", "firn_source_z"),
         "peak": ("firn_source_peak", "firn_source_peak_l1")}
TOP = 7  # the slab's top layer (index z); the ramp's air voxels lie over it


def layers(z):
    """The layer masks over index z: deep, top, ramp."""
    return {"deep": z < TOP, "top": z == TOP, "ramp": z > TOP}


def part_file(baked, out, lobe, layer):
    """`baked` written to `out` with every source grid zeroed but lobe `lobe`'s voxels of layer `layer`."""
    grids, metadata = pyopenvdb.readAll(baked)
    for grid in grids:
        if grid.name == "density":
            continue
        lo, hi = grid.evalActiveVoxelBoundingBox()
        values = np.zeros(tuple(np.array(hi) - np.array(lo) + 1) + (3,), np.float32)
        grid.copyToArray(values, ijk=lo)
        keep = grid.name in LOBES[lobe]
        z = np.arange(lo[2], hi[2] + 1)[None, None, :]
        values[~np.broadcast_to(keep & layers(z)[layer], values.shape[:3])] = 0.0
        grid.clear()  # copyFromArray leaves the voxels whose new value is the background (0) as they were
        grid.copyFromArray(values, ijk=lo)
    pyopenvdb.write(out, grids=grids, metadata=metadata)


def split(cache, snow, elevation, single_samples):
    """Per view: the Monte Carlo's total (W/m^2/sr summed over the view's rays), its single scattering's share, and
    each baked part's share of the total."""
    folder = tempfile.mkdtemp(prefix="firn_grazing_peak_")
    path, optics, top = pieces.slab_scene(folder, snow)
    sun = pieces.light(f"sun{elevation}", top)
    origins, directions, per_view = pieces.rays(top)
    total = np.load(os.path.join(cache, f"{snow}_sun{elevation}_4096.npy"))[:, 1]
    baked = path + ".baked.vdb"
    firncore.bake(path, optics, suns=[sun], quality="FINAL", seed=0, output_path=baked)
    single, _ = firncore.render_scattering_where_thin(baked, optics, origins, directions, suns=[sun],
                                                      samples=single_samples, seed=5, thin_depth=1e9, bounces=0)

    def per(values):
        return values.reshape(len(pieces.VIEWS), per_view).sum(axis=1)

    reference = per(total)
    rows = {"MC single": per(single[:, 1]) / reference}
    rows["MC multiple"] = 1.0 - rows["MC single"]
    rows["baked"] = per(firncore.render_baked(baked, optics, origins, directions)[:, 1]) / reference
    for lobe in LOBES:
        for layer in ("deep", "top", "ramp"):
            out = os.path.join(folder, f"{lobe}_{layer}.vdb")
            part_file(baked, out, lobe, layer)
            rows[f"{lobe} {layer}"] = per(firncore.render_baked(out, optics, origins, directions)[:, 1]) / reference
    return rows


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--snows", default="grey,issue")
    parser.add_argument("--elevations", default="3,10")
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_grazing_sun"))
    parser.add_argument("--single-samples", type=int, default=256)
    args = parser.parse_args()
    print("part             per view, % of the Monte Carlo's total (0, 90, 180, 270 at 30 deg; above)")
    for snow in args.snows.split(","):
        for elevation in args.elevations.split(","):
            print(f"{snow} sun {elevation} deg")
            for name, shares in split(args.cache, snow, elevation, args.single_samples).items():
                print(f"  {name:13s} " + " ".join(f"{100 * s:6.1f}" for s in shares), flush=True)


if __name__ == "__main__":
    main()
