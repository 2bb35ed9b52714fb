"""What the bake's world costs, on Blender's main thread and in the worker (issue 10, item 6).

bench/run.sh bench/world_light_bench.py [-- --runs N]   (blender -b with the add-on from the build tree)

Main thread (bake/inputs.py world_request, run by the operator's invoke): a Nishita sky has its node settings
read; any other world is saved alone into a .blend for the child Blender that renders it, here an equirect
HDRI (random float pixels) on disk and packed. Worker: the core's Nishita map and sun (NishitaWorld.light).
Prints markdown rows; the fastest of N runs. Timings vary with the machine's load.
"""

import argparse
import os
import sys
import tempfile

import addon_utils
import bpy
import numpy as np

addon_utils.enable("firn", default_set=True)
from firn.bake import inputs as bake_inputs  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from timing import fastest  # noqa: E402

HDRI_SIZES = ((2048, 1024), (4096, 2048))


def nishita_world(scene):
    world = bpy.data.worlds.new("Nishita")
    world.use_nodes = True
    sky = world.node_tree.nodes.new("ShaderNodeTexSky")
    sky.sky_type = "NISHITA"
    world.node_tree.links.new(sky.outputs["Color"], world.node_tree.nodes["Background"].inputs["Color"])
    scene.world = world


def hdri_world(scene, width, height, folder):
    world = bpy.data.worlds.new(f"HDRI {width}")
    world.use_nodes = True
    environment = world.node_tree.nodes.new("ShaderNodeTexEnvironment")
    world.node_tree.links.new(environment.outputs["Color"], world.node_tree.nodes["Background"].inputs["Color"])
    image = bpy.data.images.new(f"hdri{width}", width, height, float_buffer=True)
    image.pixels.foreach_set(np.random.default_rng(0).random(width * height * 4, dtype=np.float32))
    image.filepath_raw, image.file_format = os.path.join(folder, f"hdri{width}.exr"), "OPEN_EXR"
    image.save()
    environment.image = image
    scene.world = world
    return image


def request_row(name, scene, frame, runs):
    def request():
        made = bake_inputs.world_request(scene, [frame])
        size = os.path.getsize(made.request.blend) if hasattr(made, "request") else 0
        made.discard()
        return size

    seconds, size = fastest(runs, request)
    return f"| {name} | {seconds * 1e3:.2f} | {size / 1e6:.1f} |"


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=5)
    runs = parser.parse_args(argv).runs
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("firn", default_set=True)
    scene = bpy.context.scene
    frame = bake_inputs.Frame(bpy.data.objects.new("Frame", None))
    rows = []
    nishita_world(scene)
    rows.append(request_row("Nishita sky (node settings read)", scene, frame, runs))
    sky_seconds, _ = fastest(runs, lambda: bake_inputs.world_request(scene, [frame]).light(frame))
    with tempfile.TemporaryDirectory() as folder:
        for width, height in HDRI_SIZES:
            image = hdri_world(scene, width, height, folder)
            rows.append(request_row(f"HDRI {width} × {height} float, on disk", scene, frame, runs))
            image.pack()
            rows.append(request_row(f"HDRI {width} × {height} float, packed", scene, frame, runs))
    print("| world | main thread: world_request (ms) | .blend saved for the child (MB) |\n|---|---|---|")
    print("\n".join(rows))
    print(f"\nWorker: the core's Nishita sky, 128 × 64 map (2 × 2 directions per pixel) and sun: {sky_seconds:.3f} s")


main()
