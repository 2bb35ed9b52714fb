"""A snowy street at night: a street lamp (a Spot) and a lit window (an Area lamp) on snow, under a dark sky.
Point, spot and area lamps light the bake as they light the rest of the scene. Saves night_street.blend next to
this script.

blender -b --factory-startup --python blend_samples/night_street.py -- [--output out/night_street.png]
"""

import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sample_common as common  # noqa: E402

NIGHT_SKY = (0.004, 0.006, 0.015)  # W/m²/sr: a moonless sky over a town
SODIUM = (1.0, 0.62, 0.3)  # a warm street lamp
TUNGSTEN = (1.0, 0.75, 0.45)  # a room behind a window


def night_world(scene):
    world = bpy.data.worlds.new("Night")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (*NIGHT_SKY, 1.0)
    scene.world = world


def box(name, location, size, rgb, roughness=0.8):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=location, scale=size)
    obj = bpy.context.object
    obj.name = name
    obj.data.materials.append(common.material(name, rgb, roughness=roughness))
    return obj


def glowing(name, rgb, strength):
    """A material that shows a lamp's glow to the camera only: the lamp itself lights the scene."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    tree = mat.node_tree
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (*rgb, 1.0)
    camera_only = tree.nodes.new("ShaderNodeMath")
    camera_only.operation = "MULTIPLY"
    camera_only.inputs[1].default_value = strength
    tree.links.new(tree.nodes.new("ShaderNodeLightPath").outputs["Is Camera Ray"], camera_only.inputs[0])
    tree.links.new(camera_only.outputs[0], emission.inputs["Strength"])
    tree.links.new(emission.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    mat.cycles.sample_as_light = False
    return mat


def street_lamp(location, height=3.0):
    """A pole with a head, and a Spot under the head shining down."""
    x, y = location
    pole = box("Lamp Post", (x, y, height / 2), (0.08, 0.08, height), (0.05, 0.05, 0.05), roughness=0.4)
    head = box("Lamp Head", (x, y, height + 0.05), (0.5, 0.3, 0.1), (0.05, 0.05, 0.05), roughness=0.4)
    bpy.ops.mesh.primitive_plane_add(size=0.28, location=(x, y, height - 0.005))
    bpy.context.object.name = "Lamp Glass"
    bpy.context.object.data.materials.append(glowing("Lamp Glass", SODIUM, 40.0))
    bpy.context.object.visible_shadow = False  # glass: the spot shines through it
    bpy.ops.object.light_add(type="SPOT", location=(x, y, height - 0.02))
    spot = bpy.context.object
    spot.name = "Street Lamp"
    spot.data.energy, spot.data.color = 900.0, SODIUM
    spot.data.spot_size, spot.data.spot_blend = math.radians(120), 0.4
    spot.data.shadow_soft_size = 0.08
    return [pole, head]


def lit_window(house, centre, size):
    """A window pane that glows, and an Area lamp just in front of it shining out of the house."""
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=centre, rotation=(math.radians(90), 0, 0))
    pane = bpy.context.object
    pane.name = "Window"
    pane.scale = (size[0], size[1], 1.0)
    pane.data.materials.append(glowing("Window", TUNGSTEN, 6.0))
    pane.visible_shadow = False
    bpy.ops.object.light_add(type="AREA", location=(centre[0], centre[1] - 0.02, centre[2]),
                             rotation=(-math.radians(90), 0, 0))  # the lamp's -Z turns to -Y: out of the house
    lamp = bpy.context.object
    lamp.name = "Window Light"
    lamp.data.shape, lamp.data.size, lamp.data.size_y = "RECTANGLE", size[0], size[1]
    lamp.data.energy, lamp.data.color = 400.0, TUNGSTEN


def build_scene():
    scene = common.new_scene()
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    ground = bpy.context.object
    ground.scale = (7.0, 5.0, 1.0)
    ground.name = "Street"
    ground.data.materials.append(common.material("Asphalt", (0.08, 0.08, 0.09), roughness=0.9))
    house = box("House", (0.0, 2.2, 1.3), (4.0, 2.0, 2.6), (0.45, 0.3, 0.22))
    lit_window(house, (-0.8, 1.19, 1.3), (1.0, 0.9))
    lamp_parts = street_lamp((1.4, -0.4))
    bench = box("Bench", (-1.4, -0.6, 0.45), (1.4, 0.45, 0.06), (0.3, 0.18, 0.1))
    night_world(scene)
    common.camera(location=(2.6, -5.4, 1.5), look_at=(-0.1, 0.4, 1.45), lens=24)
    scene.view_settings.exposure = 0.5
    return scene, [ground, house, bench] + lamp_parts


def main():
    common.snow_bake_render(__file__, __doc__, build_scene, depth=0.08, spacing=0.04, voxel_size=0.02)


if __name__ == "__main__":
    main()
