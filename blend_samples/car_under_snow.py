"""A car under snow, in the spirit of Nishita et al. (1997), Fig. 5: a car-like body, a few trees, ground,
sun and Nishita sky. Builds the scene, adds snow, renders, saves car_under_snow.blend next to this script.

blender -b --factory-startup --python blend_samples/car_under_snow.py -- [--output out/car.png] [--width 500]
"""

import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sample_common as common  # noqa: E402


def rounded_box(name, size, location, bevel, mat, subdivisions=2):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=location)
    obj = bpy.context.object
    obj.name = name
    obj.scale = size
    bpy.ops.object.transform_apply(scale=True)
    mod = obj.modifiers.new("Bevel", "BEVEL")
    mod.width = bevel
    mod.segments = 4
    sub = obj.modifiers.new("Subdivision", "SUBSURF")
    sub.levels = sub.render_levels = subdivisions
    obj.data.materials.append(mat)
    bpy.ops.object.shade_smooth()
    return obj


def car(paint, glass, rubber):
    body = rounded_box("Car Body", (4.2, 1.8, 0.7), (0, 0, 0.65), 0.2, paint)
    cabin = rounded_box("Car Cabin", (2.2, 1.6, 0.6), (-0.25, 0, 1.25), 0.25, glass)
    wheels = []
    for x in (-1.35, 1.35):
        for y in (-0.85, 0.85):
            bpy.ops.mesh.primitive_cylinder_add(radius=0.38, depth=0.3, location=(x, y, 0.38),
                                                rotation=(1.5708, 0, 0), vertices=32)
            wheel = bpy.context.object
            wheel.data.materials.append(rubber)
            wheels.append(wheel)
    return [body, cabin] + wheels


def tree(location, height, bark, needles):
    x, y = location
    bpy.ops.mesh.primitive_cylinder_add(radius=0.12, depth=0.6, location=(x, y, 0.3), vertices=12)
    trunk = bpy.context.object
    trunk.data.materials.append(bark)
    parts = [trunk]
    for i, scale in enumerate((1.0, 0.75, 0.5)):
        z = 0.5 + i * height * 0.25
        bpy.ops.mesh.primitive_cone_add(radius1=height * 0.3 * scale, depth=height * 0.45,
                                        location=(x, y, z + height * 0.22), vertices=24)
        cone = bpy.context.object
        cone.data.materials.append(needles)
        parts.append(cone)
    return parts


SNOW = dict(depth=0.12, spacing=0.06, voxel_size=0.02)  # m


def build_scene():
    scene = common.new_scene()
    ground_mat = common.material("Frozen Ground", (0.25, 0.22, 0.18), roughness=0.9)
    bpy.ops.mesh.primitive_plane_add(size=13.0)
    ground = bpy.context.object
    ground.name = "Ground"
    ground.data.materials.append(ground_mat)
    paint = common.material("Car Paint", (0.55, 0.04, 0.03), roughness=0.3)
    glass = common.material("Glass", (0.05, 0.07, 0.08), roughness=0.05)
    rubber = common.material("Rubber", (0.02, 0.02, 0.02), roughness=0.8)
    bark = common.material("Bark", (0.12, 0.07, 0.04), roughness=0.9)
    needles = common.material("Needles", (0.03, 0.12, 0.05), roughness=0.8)
    targets = [ground] + car(paint, glass, rubber)
    for location, height in (((-4.5, 3.5), 5.0), ((3.8, 4.2), 6.0), ((-0.8, 5.5), 4.5)):
        targets += tree(location, height, bark, needles)
    common.nishita_sky(scene, sun_elevation_deg=25.0, sun_rotation_deg=200.0)
    common.sun(elevation_deg=25.0, rotation_deg=200.0, irradiance=4.0)
    common.camera(location=(8.5, -8.0, 3.6), look_at=(0.0, 0.5, 0.9), lens=40)
    return scene, targets


def add_car_snow(targets):
    """The sample's snow layer on `targets` (the benches measure the same snow)."""
    return common.add_snow(targets, **SNOW)


def main():
    common.snow_bake_render(__file__, __doc__, build_scene, **SNOW)


if __name__ == "__main__":
    main()
