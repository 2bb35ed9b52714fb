"""Point, spot and area lamps as the bake reads them (bake/inputs.py) light a surface as Cycles lights it: a white
diffuse plane rendered by Cycles (direct light only) shows E / π, E the irradiance the core computes from the
gathered lamp (firncore.Lamp.irradiance). This is where Blender's Power becomes W/sr or W/m²/sr."""

import math

import bpy
import pytest

from bake_helpers import black_world, ortho_camera, render
from firn.bake import inputs as bake_inputs
from firn.common.core import firncore


def white_plane(location):
    bpy.ops.mesh.primitive_plane_add(size=0.05, location=location)
    material = bpy.data.materials.new("White")
    material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    material.node_tree.links.new(diffuse.outputs[0], nodes["Material Output"].inputs["Surface"])
    bpy.context.object.data.materials.append(material)


def lamp(kind, location, rotation=(0.0, 0.0, 0.0), scale=(1.0, 1.0, 1.0), **settings):
    light = bpy.data.lights.new("Lamp", kind)
    for key, value in settings.items():
        setattr(light, key, value)
    obj = bpy.data.objects.new("Lamp", light)
    obj.location, obj.rotation_euler, obj.scale = location, rotation, scale
    bpy.context.scene.collection.objects.link(obj)
    return obj


LAMPS = {
    "point": ("POINT", (0.0, 0.0, 2.0), {}, {"energy": 1000.0, "shadow_soft_size": 0.5}),
    "spot, blended edge": ("SPOT", (0.0, 0.0, 2.0), {}, {"energy": 1000.0, "spot_size": math.radians(90),
                                                      "spot_blend": 1.0, "shadow_soft_size": 0.0}),
    "square, scaled": ("AREA", (0.0, 0.0, 1.5), {"scale": (2.0, 1.0, 1.0)}, {"energy": 500.0, "size": 0.8}),
    "disk, tilted": ("AREA", (0.0, 0.0, 1.5), {"rotation": (0.4, 0.0, 0.0)},
                     {"energy": 500.0, "shape": "DISK", "size": 1.2}),
    "ellipse": ("AREA", (0.0, 0.0, 1.0), {}, {"energy": 300.0, "shape": "ELLIPSE", "size": 1.5, "size_y": 0.5}),
}


@pytest.mark.parametrize("name", LAMPS)
def test_lamp_lights_a_plane_as_cycles_does(clean_scene, tmp_path, name):
    kind, location, placement, settings = LAMPS[name]
    black_world()
    point = (0.8, 0.3, 0.0)  # off every lamp's axis
    white_plane(point)
    lamp(kind, location, **placement, **settings)
    ortho_camera(point, (0.0, 0.0, 1.0), scale=0.02, distance=0.5)
    scene = bpy.context.scene
    scene.cycles.max_bounces = 0  # direct light only
    scene.cycles.sample_clamp_direct = scene.cycles.sample_clamp_indirect = 0.0
    bpy.context.view_layer.update()
    cycles = render(str(tmp_path), size=(4, 4), samples=256).reshape(-1, 3).mean(axis=0)

    _, (found,) = bake_inputs.gather_lights(bake_inputs.lamp_objects(bpy.context.view_layer),
                                            bake_inputs.Frame(bpy.data.objects.new("Origin", None)))
    core = firncore.Lamp(found.shape, found.position, found.emission, axis=found.axis, tangent=found.tangent,
                         radius=found.radius, spot_angle=found.spot_angle, spot_blend=found.spot_blend,
                         size=found.size)
    irradiance = core.irradiance(point, (0.0, 0.0, 1.0), samples=400000, seed=1)
    assert irradiance[0] > 1.0  # the plane is well lit
    assert cycles == pytest.approx([E / math.pi for E in irradiance], rel=0.02)
