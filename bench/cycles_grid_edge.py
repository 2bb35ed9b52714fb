"""How far Cycles reads a grid's edge value (docs/vdb-contract.md, firn_scatter: whether a float grid needs a ring
of zeros as the source grids do). A float grid and a Vec3 grid of 1 over 20 voxels along x (0.1 m; translation
-h/2, Firn's convention), each read by an Attribute node (Color) into the Color of a volume Emission of Strength
1, seen along x by an orthographic camera: a read that tapers to the zero beyond the last voxel centre gives exactly 2.0 (1.9 m
between the end voxels' centres, half a voxel of ramp at each end); one that holds the edge value half a voxel
further gives 2.1.

    bench/run.sh bench/cycles_grid_edge.py
"""

import os
import tempfile

import bpy
import numpy as np
import pyopenvdb

VOXEL = 0.1  # m


def write_grids(path):
    ones = np.ones((20, 11, 11), np.float32)
    share = pyopenvdb.FloatGrid()
    share.copyFromArray(ones, ijk=(0, -5, -5), tolerance=0.0)
    vector = pyopenvdb.Vec3SGrid()
    vector.copyFromArray(np.repeat(ones[..., None], 3, axis=3), ijk=(0, -5, -5), tolerance=(0.0, 0.0, 0.0))
    for grid, name in ((share, "float"), (vector, "vec3")):
        grid.name = name
        grid.transform = pyopenvdb.createLinearTransform(voxelSize=VOXEL)
        grid.transform.translate((-VOXEL / 2,) * 3)
    pyopenvdb.write(path, grids=[share, vector])


def scene_reading(path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = "CPU", 4, False
    scene.render.resolution_x = scene.render.resolution_y = 4
    scene.render.image_settings.file_format, scene.render.image_settings.color_depth = "OPEN_EXR", "32"
    scene.world = bpy.data.worlds.new("black")
    scene.world.color = (0.0, 0.0, 0.0)
    volume = bpy.data.volumes.new("edge")
    volume.filepath = path
    volume.render.precision, volume.render.clipping = "FULL", 0.0
    snow = bpy.data.objects.new("edge", volume)
    scene.collection.objects.link(snow)
    camera = bpy.data.cameras.new("camera")
    camera.type, camera.ortho_scale = "ORTHO", 0.2
    scene.camera = bpy.data.objects.new("camera", camera)
    scene.collection.objects.link(scene.camera)
    scene.camera.location, scene.camera.rotation_euler = (5.0, 0.0, 0.0), (np.pi / 2, 0.0, np.pi / 2)  # along -x
    return scene, snow


def emission_of(scene, snow, grid, folder):
    """The mean pixel (red) with the Emission's Color the grid's value (emission 1 per metre where it is 1)."""
    material = bpy.data.materials.new(grid)
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    attribute, emission = nodes.new("ShaderNodeAttribute"), nodes.new("ShaderNodeEmission")
    attribute.attribute_name = grid
    links.new(attribute.outputs["Color"], emission.inputs["Color"])
    links.new(emission.outputs[0], nodes.new("ShaderNodeOutputMaterial").inputs["Volume"])
    snow.data.materials.clear()
    snow.data.materials.append(material)
    scene.render.filepath = os.path.join(folder, grid + ".exr")
    bpy.ops.render.render(write_still=True)
    return float(np.array(bpy.data.images.load(scene.render.filepath).pixels[:]).reshape(-1, 4)[:, 0].mean())


def main():
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "edge.vdb")
        write_grids(path)
        scene, snow = scene_reading(path)
        for grid in ("float", "vec3"):
            print(f"{grid}: {emission_of(scene, snow, grid, folder):.4f} (2.0: exact taper, 2.1: half a voxel further)")


main()
