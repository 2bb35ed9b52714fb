"""Firn's data on Blender objects: obj.firn."""

import math

import bpy

# Defined once, used by the operator (redo panel) and by the settings kept on each snow object.
SNOW_LAYER_PROPERTIES = {
    "depth": bpy.props.FloatProperty(
        name="Depth", description="Snow depth on open level ground", subtype="DISTANCE", unit="LENGTH",
        default=0.1, min=0.001, max=20.0, soft_max=2.0, precision=3),
    "max_slope": bpy.props.FloatProperty(
        name="Maximum Slope", description="Steeper surfaces stay bare; snow thins over the last 15 degrees",
        subtype="ANGLE", default=math.radians(60.0), min=math.radians(1.0), max=math.radians(90.0)),
    "spacing": bpy.props.FloatProperty(
        name="Spacing", description="Distance between landing sites: small gives smooth snow, large gives uneven snow",
        subtype="DISTANCE", unit="LENGTH", default=0.05, min=0.002, max=10.0, soft_max=1.0, precision=3),
    "randomness": bpy.props.FloatProperty(
        name="Randomness", description="Jitter of the depth and of the metaball radii", subtype="FACTOR",
        default=0.25, min=0.0, max=1.0),
    "smoothness": bpy.props.FloatProperty(
        name="Smoothness", description="Overlap of the metaballs: 0 shows lumps, 1 is smooth", subtype="FACTOR",
        default=0.5, min=0.0, max=1.0),
    "direction": bpy.props.FloatVectorProperty(
        name="Snowfall Direction", description="The way snow falls; tilt it to model wind", subtype="DIRECTION",
        size=3, default=(0.0, 0.0, -1.0)),
    "spread": bpy.props.FloatProperty(
        name="Spread", description="Half-angle of the cone snow falls from: softens sheltered edges",
        subtype="ANGLE", default=math.radians(15.0), min=0.0, max=math.radians(89.0)),
    "compaction": bpy.props.FloatProperty(
        name="Compaction", description="How fast density rises with depth: 0 uniform, 1 dense right below the top",
        subtype="FACTOR", default=0.5, min=0.0, max=1.0),
    "density_top": bpy.props.FloatProperty(
        name="Top Density", description="Snow density at the surface in kg/m³ (fresh snow 50-150)",
        default=120.0, min=10.0, max=917.0),
    "density_bottom": bpy.props.FloatProperty(
        name="Bottom Density", description="Snow density approached at depth in kg/m³ (settled snow 200-400)",
        default=350.0, min=10.0, max=917.0),
    "seed": bpy.props.IntProperty(name="Seed", description="Same seed, same snow", default=0, min=0),
    "voxel_size": bpy.props.FloatProperty(
        name="Voxel Size", description="Resolution of the snow volume (0: automatic, 12 voxels through the depth)",
        subtype="DISTANCE", unit="LENGTH", default=0.0, min=0.0, soft_max=0.1, precision=4),
    "occluders": bpy.props.EnumProperty(
        name="Occluders", description="What shelters the targets from snowfall",
        items=(("VISIBLE", "Visible Objects", "Every visible object shelters the targets"),
               ("COLLECTION", "Collection", "Only the objects of a collection shelter the targets")),
        default="VISIBLE"),
    "occluder_collection": bpy.props.StringProperty(
        name="Occluder Collection", description="Collection whose objects shelter the targets"),
    "surface_mesh": bpy.props.BoolProperty(
        name="Surface Mesh", description="Also make a mesh of the snow surface (viewport, EEVEE, modelling)",
        default=False),
}


class FIRN_SnowLayerSettings(bpy.types.PropertyGroup):
    __annotations__ = dict(SNOW_LAYER_PROPERTIES)


class FIRN_SnowTarget(bpy.types.PropertyGroup):
    object: bpy.props.PointerProperty(type=bpy.types.Object, name="Target")


class FIRN_ObjectSettings(bpy.types.PropertyGroup):
    is_snow: bpy.props.BoolProperty(
        name="Is Snow",
        description="This volume object holds Firn snow",
        default=False,
    )
    layer: bpy.props.PointerProperty(type=FIRN_SnowLayerSettings, name="Snow Layer")
    targets: bpy.props.CollectionProperty(type=FIRN_SnowTarget, name="Targets")
    metaballs: bpy.props.PointerProperty(
        type=bpy.types.Object, name="Metaballs", description="Point mesh of the snow's metaballs (edit, then rebuild)")
    mean_density: bpy.props.FloatProperty(
        name="Mean Density", description="Mean snow density inside the volume, kg/m³", default=250.0, min=0.0)
    voxel_size: bpy.props.FloatProperty(
        name="Voxel Size", description="Voxel size of the snow volume", subtype="DISTANCE", unit="LENGTH",
        default=0.0, min=0.0)


classes = (FIRN_SnowLayerSettings, FIRN_SnowTarget, FIRN_ObjectSettings)


def register_extras():
    bpy.types.Object.firn = bpy.props.PointerProperty(type=FIRN_ObjectSettings)


def unregister_extras():
    del bpy.types.Object.firn
