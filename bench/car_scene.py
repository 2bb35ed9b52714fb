"""Writes the car sample's bake inputs (blend_samples/car_under_snow.py: its snow's density VDB, the sun, the sky and
the occluders exactly as Bake Scattering hands them to the core) to a folder, for bench/car_bake.py, which bakes
them outside Blender.

bench/run.sh bench/car_scene.py -- FOLDER
"""

import os
import shutil
import sys

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blend_samples"))
import car_under_snow as car  # noqa: E402
import sample_common as common  # noqa: E402


def capture_bake_inputs(snow, folder):
    """Runs Bake Scattering (DRAFT, to be quick) with the add-on's call into the core wrapped by a recorder of its
    inputs."""
    from firn.bake import operators

    core_bake = operators.core_bake

    def record(path, output, volume_optics, inputs, quality, seed, progress):
        if inputs.lamps:
            raise RuntimeError("the car sample has no lamps; car_bake.py does not replay them")
        shutil.copyfile(path, os.path.join(folder, "car_density.vdb"))
        arrays = {"optics_k": volume_optics.extinction_per_density, "optics_albedo": volume_optics.albedo,
                  "optics_g": volume_optics.g, "sun_direction": [s.direction for s in inputs.suns],
                  "sun_irradiance": [s.irradiance for s in inputs.suns],
                  "sun_angular_diameter": [s.angular_diameter for s in inputs.suns],
                  "sky_radiance": inputs.sky.radiance, "occluders": len(inputs.occluders)}
        if inputs.sky.map is not None:
            arrays["sky_map"] = inputs.sky.map
        for k, occluder in enumerate(inputs.occluders):
            arrays[f"occluder_{k}_vertices"], arrays[f"occluder_{k}_triangles"] = occluder.vertices, occluder.triangles
            arrays[f"occluder_{k}_albedo"] = occluder.albedo
        np.savez(os.path.join(folder, "car_inputs.npz"), **arrays)
        return core_bake(path, output, volume_optics, inputs, "DRAFT", seed, progress)

    operators.core_bake = record
    try:
        common.bake([snow])
    finally:
        operators.core_bake = core_bake


def main():
    folder = sys.argv[sys.argv.index("--") + 1]
    os.makedirs(folder, exist_ok=True)
    _scene, targets = car.build_scene()
    snow = car.add_car_snow(targets)
    capture_bake_inputs(snow, folder)
    print(f"car scene: bake inputs -> {folder}")


main()
