"""Firn's data on Blender objects: obj.firn."""

import math

import bpy

from .bake import state as bake_state
from .common.core import firncore
from .material import nodes as materials, optics
from .snow_layer import proxy

# Defined once, used by the operator (redo panel) and by the settings kept on each snow object. Lengths are in
# Blender units (unit="LENGTH": shown and typed in the scene's units, Unit Scale applied); the operator turns them
# into metres for the core, which checks their range in metres (hence no hard maximum here).
SNOW_LAYER_PROPERTIES = {
    "depth": bpy.props.FloatProperty(
        name="Depth", description="Snow depth on open level ground", subtype="DISTANCE", unit="LENGTH",
        default=0.1, min=1e-6, soft_min=0.001, soft_max=2.0, precision=3),
    "max_slope": bpy.props.FloatProperty(
        name="Maximum Slope", description="Steeper surfaces stay bare; snow thins over the last 15 degrees",
        subtype="ANGLE", default=math.radians(60.0), min=math.radians(1.0), max=math.radians(90.0)),
    "spacing": bpy.props.FloatProperty(
        name="Spacing", description="Distance between landing sites: small gives smooth snow, large gives uneven snow",
        subtype="DISTANCE", unit="LENGTH", default=0.05, min=1e-6, soft_min=0.002, soft_max=1.0, precision=3),
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
    "level_of_detail": bpy.props.EnumProperty(
        name="Level of Detail", description="Voxels sized by the scene camera's pixel footprint: fine near the "
        "camera, coarser with distance, one snow object per band of distances (docs/large-scenes.md)",
        items=(("AUTO", "Automatic", "Levels of detail when the snow would exceed the voxel budget at one voxel size "
                "and the scene has a perspective camera"),
               ("ON", "On", "Levels of detail from the scene camera"),
               ("OFF", "Off", "One voxel size everywhere")),
        default="AUTO"),
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
    # Masks (snow_layer/masks.py)
    "only_selected_faces": bpy.props.BoolProperty(
        name="Selected Faces Only", description="Snow only on the faces selected in Edit Mode (the others still "
        "shelter)", default=False),
    "vertex_group": bpy.props.StringProperty(
        name="Vertex Group", description="Vertex group whose 0-1 weight scales the snow depth (none: full depth)"),
    "weight_attribute": bpy.props.StringProperty(
        name="Weight Attribute", description="Float point attribute whose 0-1 value scales the snow depth"),
}


class FIRN_SnowLayerSettings(bpy.types.PropertyGroup):
    __annotations__ = dict(SNOW_LAYER_PROPERTIES)


class FIRN_SnowTarget(bpy.types.PropertyGroup):
    object: bpy.props.PointerProperty(type=bpy.types.Object, name="Target")

# Add Snow Spray (issue 14, docs/spray.md): the emitter choice, then the core's settings under the core's names
# (CORE_SPRAY_SETTINGS go to firncore.SpraySettings as they are). Lengths are metres whatever the Unit Scale: a lump's
# size belongs to the snow, not to the scene (as the grain radius).
_SPRAY = firncore.SpraySettings()
EMITTER_ITEMS = (
    ("LOWEST_FACE", "Lowest Face", "The face whose centre is lowest at the first frame: a ski's sole, a board's base"),
    ("VERTEX_GROUP", "Vertex Group", "The rectangle around a vertex group's vertices (a wheel's contact patch)"),
    ("FACE", "Face", "The face of the given index"),
)
CORE_SPRAY_SETTINGS = ("rate", "spread_angle", "throw_speed", "lump_radius", "lump_density", "balls_per_lump",
                       "break_rate", "track_thickness", "compaction_depth", "substeps", "deposit", "cut_tracks",
                       "voxel_size", "seed")
SPRAY_PROPERTIES = {
    "emitter": bpy.props.EnumProperty(
        name="Emitter", description="Which part of each selected object throws snow", items=EMITTER_ITEMS,
        default="LOWEST_FACE"),
    "vertex_group": bpy.props.StringProperty(
        name="Vertex Group", description="Vertex group of every selected object that throws snow (its vertices' "
        "bounding rectangle in their plane)"),
    "face_index": bpy.props.IntProperty(
        name="Face Index", description="Index of the face that throws snow, in every selected object", default=0,
        min=0),
    "rate": bpy.props.FloatProperty(
        name="Rate (1/m³)", description="Lumps thrown per m² of emitter per metre it travels through the snow",
        default=_SPRAY.rate, min=0.0, soft_max=200000.0),
    "spread_angle": bpy.props.FloatProperty(
        name="Spread", description="Half-angle of the cone around straight up that lumps are thrown in",
        subtype="ANGLE", default=_SPRAY.spread_angle, min=0.0, max=math.pi / 2),
    "throw_speed": bpy.props.FloatProperty(
        name="Throw Speed", description="Speed of the throw as a fraction of the emitter's local speed",
        default=_SPRAY.throw_speed, min=0.0, soft_max=2.0),
    "lump_radius": bpy.props.FloatProperty(
        name="Lump Radius", description="Mean equivalent radius of a thrown lump in metres, whatever the Unit Scale",
        default=_SPRAY.lump_radius, min=1e-4, soft_max=0.05, precision=4, step=0.01),
    "lump_density": bpy.props.FloatProperty(
        name="Lump Density (kg/m³)", description="Density of a lump: packed snow thrown by a ski is 150-400",
        default=_SPRAY.lump_density, min=10.0, max=917.0),
    "balls_per_lump": bpy.props.IntProperty(
        name="Balls per Lump", description="Metaballs a new lump is made of (a lump is not a sphere)",
        default=_SPRAY.balls_per_lump, min=1, max=8),
    "break_rate": bpy.props.FloatProperty(
        name="Break Rate (1/s)", description="Chance per second that a flying lump splits in two",
        default=_SPRAY.break_rate, min=0.0, soft_max=10.0),
    "track_thickness": bpy.props.FloatProperty(
        name="Track Depth", description="How far under its rectangle an emitter cuts the snow, in metres",
        default=_SPRAY.track_thickness, min=0.0, soft_max=0.2, precision=3, step=0.1),
    "compaction_depth": bpy.props.FloatProperty(
        name="Compaction Depth", description="The layer under a track that takes the snow pushed out of it, "
        "in metres", default=_SPRAY.compaction_depth, min=0.0, soft_max=0.5, precision=3, step=0.1),
    "substeps": bpy.props.IntProperty(
        name="Sub-Steps", description="Sub-steps per frame", default=_SPRAY.substeps, min=1, soft_max=32),
    "deposit": bpy.props.BoolProperty(
        name="Deposit", description="Lumps that come to rest stay where they lie (off: they vanish into the snow)",
        default=_SPRAY.deposit),
    "cut_tracks": bpy.props.BoolProperty(
        name="Cut Tracks", description="Emitters cut tracks in the snow (a second volume sequence)",
        default=_SPRAY.cut_tracks),
    "voxel_size": bpy.props.FloatProperty(
        name="Voxel Size", description="Voxel of the spray's grids in metres (0: the snow's); at most about the "
        "Lump Radius to see lumps", default=_SPRAY.voxel_size, min=0.0, soft_max=0.05, precision=4, step=0.01),
    "seed": bpy.props.IntProperty(name="Seed", description="Same scene and seed, same spray", default=0, min=0),
}
SPRAY_ROLE_ITEMS = (
    ("NONE", "None", "Not made by Add Snow Spray"),
    ("SPRAY", "Spray", "The thrown snow: spray_####.vdb"),
    ("TRACKS", "Tracks", "The snow with the emitters' tracks: snow_####.vdb, shown instead of the snow it came from"),
    ("LIGHT", "Lit", "A snow layer's light baked frame by frame (Bake Light Sequence): lit_####.vdb, shown instead "
     "of the snow it came from"),
)


class FIRN_SpraySettings(bpy.types.PropertyGroup):
    """What a spray sequence was made from, kept on its Volume objects: Bake Sequence makes it again (longer,
    resumed) from these."""
    __annotations__ = dict(
        SPRAY_PROPERTIES,
        role=bpy.props.EnumProperty(name="Role", items=SPRAY_ROLE_ITEMS, default="NONE"),
        source=bpy.props.PointerProperty(type=bpy.types.Object, name="Snow",
                                         description="The snow layer the emitters move through"),
        emitters=bpy.props.CollectionProperty(type=FIRN_SnowTarget, name="Emitters"),
        frame_start=bpy.props.IntProperty(name="Start", description="First frame of the sequence (the snow as it "
                                          "was)", default=1),
        frame_end=bpy.props.IntProperty(name="End", description="Last frame simulated", default=1),
        summary=bpy.props.StringProperty(name="Summary", description="What the last simulation did"),
    )

# The CUSTOM fields start where the PHYSICAL defaults lead (clean snow, 100 um grains, 250 kg/m^3).
_DEFAULT_GRAIN_RADIUS = 100e-6  # m
_DEFAULT_DENSITY = 250.0  # kg/m^3
_DEFAULT_G = 0.845  # Kokhanovsky & Zege (2004), irregular grains
_DEFAULT_OPTICS = optics.physical_default(_DEFAULT_GRAIN_RADIUS, _DEFAULT_DENSITY, _DEFAULT_G)


def _refresh_material(self, context):
    """Every optics setting updates the snow's material, and its viewport proxy's, live."""
    materials.refresh_snow_material(self.id_data)
    proxy.refresh_preview(self.id_data, context.scene if context else bpy.context.scene)


def _refresh_structure(self, context):
    """Render mode, sub-balls and glints rebuild the snow's material and its rendered surface."""
    materials.ensure_snow_material(self.id_data)
    proxy.apply_render_surface(self.id_data, context.scene if context else bpy.context.scene)


def _rebuild_material(self, _context):
    """Scatter Thin Snow changes the snow material's form, not the bake."""
    if materials.snow_material(self.id_data) is not None:
        materials.ensure_snow_material(self.id_data)


RENDER_MODE_ITEMS = (
    ("OPAQUE", "Opaque", "The snow's surface as an opaque diffuse surface of the snow's white-sky albedo "
     "(Nishita et al. 1997, Fig. 6 a)"),
    ("SINGLE", "Single Scattering", "Light scattered once in the snow, attenuated on its way in and out "
     "(Fig. 6 b): camera rays scatter, every other ray only sees the extinction"),
    ("BAKED", "Multiple Scattering", "All orders of scattering (Fig. 6 c, d): the bake when there is one, else "
     "Cycles' brute-force volume path tracing of the same optics (slow)"),
)


def _apply_display(self, _context):
    proxy.apply_display(self.id_data)


def _get_bake_state(self):
    return next(number for key, *_rest, number in bake_state.STATES if key == bake_state.state(self.id_data))


BAKE_QUALITY_ITEMS = (
    ("DRAFT", "Draft", "Fewer sky and shadow rays and light-traced photons, a looser solve: quick previews"),
    ("FINAL", "Final", "The full-accuracy solve: for renders"),
    ("REFERENCE", "Reference", "Surface voxels by brute-force Monte Carlo: slow, for checking and small scenes"),
)


def _get_grain_radius_um(self):
    return self.grain_radius * 1e6


def _set_grain_radius_um(self, value):
    self.grain_radius = value * 1e-6


def active_snow(context):
    """The context's object (the active one, or the one the Properties editor shows) if it is Firn snow."""
    obj = context.object
    return obj if obj is not None and obj.type == "VOLUME" and obj.firn.is_snow else None


def is_spray(obj):
    """A Volume sequence made from a snow layer: Add Snow Spray's thrown or tracked snow, or the layer lit frame by
    frame (Bake Light Sequence)."""
    return obj is not None and obj.type == "VOLUME" and obj.firn.spray.role != "NONE"


def is_lit_sequence(obj):
    """A snow layer's light baked frame by frame (Bake Light Sequence, bake/sequence.py)."""
    return is_spray(obj) and obj.firn.spray.role == "LIGHT"


def active_snow_layer(context):
    """The context's snow if it is a snow layer (made by Add Snow Layer or baked), not a spray sequence."""
    snow = active_snow(context)
    return snow if snow is not None and not is_spray(snow) else None


# The snow's optics (Snow Material panel): what a preset stores and what a spray copies from its snow.
OPTICS_SETTINGS = ("optics_mode", "grain_radius", "impurity_black_carbon", "impurity_dust", "liquid_water",
                   "absorption_enhancement", "anisotropy", "extinction_per_density", "albedo")


class FIRN_ObjectSettings(bpy.types.PropertyGroup):
    is_snow: bpy.props.BoolProperty(
        name="Is Snow",
        description="This volume object holds Firn snow",
        default=False,
    )
    is_proxy: bpy.props.BoolProperty(
        name="Is Snow Proxy",
        description="This mesh is a snow object's viewport proxy: never rendered, never holds or stops snow",
        default=False,
    )
    is_grains: bpy.props.BoolProperty(
        name="Is Grain Snow",
        description="This object holds Firn's ice grains (Add Grain Snow): one point per grain",
        default=False,
    )
    display: bpy.props.EnumProperty(
        name="Display", description="How the snow shows in the viewport (Cycles always renders the volume)",
        items=proxy.DISPLAY_ITEMS, default="SURFACE", update=_apply_display)
    layer: bpy.props.PointerProperty(type=FIRN_SnowLayerSettings, name="Snow Layer")
    spray: bpy.props.PointerProperty(type=FIRN_SpraySettings, name="Snow Spray")
    targets: bpy.props.CollectionProperty(type=FIRN_SnowTarget, name="Targets")
    metaballs: bpy.props.PointerProperty(
        type=bpy.types.Object, name="Metaballs", description="Point mesh of the snow's metaballs (edit, then rebuild)")
    voxel_size: bpy.props.FloatProperty(
        name="Voxel Size", description="Voxel size of the snow volume in metres (whatever the Unit Scale)",
        default=0.0, min=0.0)
    lod_level: bpy.props.IntProperty(
        name="Level of Detail", description="The band of distances this snow holds (0: nearest the camera, each "
        "level doubles the voxel size); -1: one voxel size everywhere", default=-1, min=-1)

    # --- optics: how the snow's density grid becomes light transport (docs/optics.md) ---
    optics_mode: bpy.props.EnumProperty(
        name="Optics",
        description="Where the snow's optical coefficients come from",
        items=(
            ("PHYSICAL", "Physical", "From grain size, impurities and liquid water (Kokhanovsky & Zege 2004, "
             "Warren & Brandt 2008 ice)"),
            ("CUSTOM", "Custom", "Extinction per density, single-scattering albedo and anisotropy given directly"),
        ),
        default="PHYSICAL",
        update=_refresh_material,
    )
    grain_radius: bpy.props.FloatProperty(
        name="Grain Radius",
        description="Optical (effective) radius of the ice grains, 3 / (917 kg/m³ × specific surface area): "
        "fresh powder 0.05 mm, settled 0.1-0.15 mm, old or wet snow 0.5-1 mm. In metres whatever the Unit Scale: "
        "a grain's size belongs to the snow, not to the scene",
        default=_DEFAULT_GRAIN_RADIUS,
        min=1e-6,
        max=0.01,
        soft_min=20e-6,
        soft_max=3e-3,
        step=0.001,
        precision=6,
        update=_refresh_material,
    )
    impurity_black_carbon: bpy.props.FloatProperty(
        name="Black Carbon (ng/g)",
        description="Soot in the snow, nanograms per gram of snow: Antarctic < 1, remote 2-20, "
        "rural 20-100, urban and roadside 100-10000",
        default=0.0,
        min=0.0,
        max=100000.0,
        soft_max=5000.0,
        precision=1,
        update=_refresh_material,
    )
    impurity_dust: bpy.props.FloatProperty(
        name="Dust (µg/g)",
        description="Mineral dust in the snow, micrograms per gram of snow: clean < 10, "
        "after dust events 100-5000 (orange-brown snow)",
        default=0.0,
        min=0.0,
        max=100000.0,
        soft_max=5000.0,
        precision=1,
        update=_refresh_material,
    )
    liquid_water: bpy.props.FloatProperty(
        name="Liquid Water",
        description="Volume fraction of the snow that is liquid water: dry 0, moist < 0.03, wet 0.03-0.08, "
        "very wet 0.08-0.15 (ICSSG). It must weigh less than the snow's mean density",
        subtype="FACTOR",
        default=0.0,
        min=0.0,
        max=0.5,
        soft_max=0.15,
        precision=3,
        update=_refresh_material,
    )
    absorption_enhancement: bpy.props.FloatProperty(
        name="Absorption Enhancement B",
        description="How much the grains' shape lengthens light paths inside ice (Kokhanovsky & Zege 2004): "
        "1.6 irregular grains (measured in snow, Libois et al. 2014), about 1.25 spheres",
        default=1.6,
        min=0.5,
        max=5.0,
        soft_min=1.0,
        soft_max=2.0,
        update=_refresh_material,
    )
    anisotropy: bpy.props.FloatProperty(
        name="Anisotropy g",
        description="Asymmetry of the phase function (Henyey-Greenstein g): 0.845 irregular grains "
        "(Kokhanovsky & Zege 2004), 0.87-0.89 spheres; Nishita et al. 1997 used 0.93",
        default=_DEFAULT_G,
        min=-0.99,
        max=0.99,
        soft_min=0.0,
        precision=3,
        update=_refresh_material,
    )
    extinction_per_density: bpy.props.FloatProperty(
        name="Extinction per Density (m²/kg)",
        description="Custom optics: extinction coefficient per unit density, sigma_t (1/m) = this × density "
        "grid (kg/m³). Snow: 3 / (2 × 917 × grain radius), 1.5-30 m²/kg",
        default=_DEFAULT_OPTICS.extinction_per_density,
        min=0.0,
        soft_max=100.0,
        precision=4,
        update=_refresh_material,
    )
    albedo: bpy.props.FloatVectorProperty(
        name="Albedo",
        description="Custom optics: single-scattering albedo per channel (linear Rec.709). Real snow is "
        "0.9999-0.9999999: 0.99 already renders grey",
        subtype="COLOR",
        size=3,
        default=_DEFAULT_OPTICS.albedo,
        min=0.0,
        max=1.0,
        precision=6,
        update=_refresh_material,
    )
    mean_density: bpy.props.FloatProperty(
        name="Mean Density (kg/m³)",
        description="Mean density of the snow's density grid, set by the snow layer generator: the density at "
        "which derived values are shown and liquid water is converted",
        default=_DEFAULT_DENSITY,
        min=1.0,
        max=917.0,
        soft_min=30.0,
        soft_max=600.0,
        update=_refresh_material,
    )

    # --- small-scale structure (docs/structure.md) ---
    render_mode: bpy.props.EnumProperty(
        name="Render Mode", description="How Cycles renders the snow", items=RENDER_MODE_ITEMS, default="BAKED",
        update=_refresh_structure)
    sub_balls: bpy.props.BoolProperty(
        name="Sub-Balls", description="Grains far smaller than a voxel in the shallow snow (Nishita's sub-balls): "
        "the density gathers into tiny metaballs, its mean kept, so a bake still applies", default=False,
        update=_refresh_structure)
    sub_ball_radius: bpy.props.FloatProperty(
        name="Grain Radius", description="Mean radius of the sub-balls in metres, whatever the Unit Scale",
        default=0.5e-3, min=1e-5, max=0.05, soft_max=5e-3, precision=5, step=0.01, update=_refresh_structure)
    sub_ball_variation: bpy.props.FloatProperty(
        name="Size Variation", description="Sub-ball radius r (1 ± this), uniform", subtype="FACTOR",
        default=0.3, min=0.0, max=0.95, update=_refresh_structure)
    sub_ball_depth: bpy.props.FloatProperty(
        name="Depth", description="Optical depths (at the mean density) below the surface where the sub-balls "
        "fade out; deeper, light has forgotten the grains", default=3.0, min=0.1, soft_max=20.0,
        update=_refresh_structure)
    sub_ball_strength: bpy.props.FloatProperty(
        name="Strength", description="0: smooth snow; 1: all the shallow snow's mass in the sub-balls",
        subtype="FACTOR", default=1.0, min=0.0, max=1.0, update=_refresh_structure)
    sub_ball_resolve: bpy.props.BoolProperty(
        name="Resolve Grains", description="Step through the snow at the grain scale so close-ups show every "
        "grain (slow: Cycles' volume steps shrink from the voxel to the grain radius)", default=False,
        update=_refresh_structure)
    glints: bpy.props.BoolProperty(
        name="Glints", description="Randomly oriented ice facets at the surface that mirror the sun: the sparkle "
        "of fresh snow", default=False, update=_refresh_structure)
    glint_density: bpy.props.FloatProperty(
        name="Facets per m²", description="Facets per square metre of snow surface (at most 1 / (4 r²)); "
        "of these only about Ω_sun / 25 mirror the sun towards the camera", default=5e7, min=1.0, soft_max=1e8,
        precision=0, update=_refresh_structure)
    glint_size: bpy.props.FloatProperty(
        name="Facet Radius", description="Radius of a facet in metres, whatever the Unit Scale",
        default=0.05e-3, min=1e-5, max=0.05, soft_max=3e-3, precision=5, step=0.01, update=_refresh_structure)
    glint_roughness: bpy.props.FloatProperty(
        name="Facet Roughness", description="0: perfect mirrors, each glint the sun's own brightness on a tiny "
        "area; rougher facets glint more often, each dimmer (the same light in all)", subtype="FACTOR",
        default=0.0, min=0.0, max=0.5, update=_refresh_structure)

    # --- bake (issue "Bake Scattering"; docs/user-guide.md) ---
    bake_quality: bpy.props.EnumProperty(
        name="Quality", description="How carefully Bake Scattering computes the light in the snow",
        items=BAKE_QUALITY_ITEMS, default="FINAL")
    bake_seed: bpy.props.IntProperty(
        name="Seed", description="Seed of the bake's random rays: same scene and seed, same bake", default=0, min=0)
    bake_fingerprint: bpy.props.StringProperty(
        name="Bake Fingerprint", description="What the last bake was made from (set by Bake Scattering)")
    bake_extinction_per_density: bpy.props.FloatProperty(
        name="Baked Extinction per Density (m²/kg)",
        description="The extinction per density the bake was made with; the baked material uses it until the next "
        "bake", default=0.0, min=0.0)
    bake_albedo: bpy.props.FloatVectorProperty(
        name="Baked Albedo", description="The single-scattering albedo the bake was made with; the snow Cycles "
        "scatters (Scatter Thin Snow) uses it until the next bake", size=3, default=(0.0, 0.0, 0.0), min=0.0,
        max=1.0)
    bake_anisotropy: bpy.props.FloatProperty(
        name="Baked Anisotropy", description="The phase function's g the bake was made with; the snow Cycles "
        "scatters (Scatter Thin Snow) uses it until the next bake", default=0.0, min=-1.0, max=1.0)
    scatter_thin: bpy.props.BoolProperty(
        name="Scatter Thin Snow", description="Cycles path-traces the light in the snow the bake finds optically "
        "thin (thin layers, spray lumps, the rims of small lumps) instead of drawing the bake there: more accurate "
        "(per-pixel error against a reference at 1024 samples: spray lumps 7.9 → 4.5 %, dense spray 17 → 12 %, "
        "a forward-scattering ball 8.0 → 5.9 %, a thin layer 7.5 → 7.1 %, 4.1 % at 4096), noisier and 1.5-2.7× "
        "Cycles' time; needs Volume Bounces of at least 16 (Bake Scattering sets them) and a few hundred samples "
        "(about 1000 on a thin layer). Changing it needs no re-bake", default=True, update=_rebuild_material)
    bake_summary: bpy.props.StringProperty(name="Bake Summary", description="What the last bake used")
    bake_state: bpy.props.EnumProperty(
        name="Bake", description="Whether the snow is baked and the bake still matches the scene",
        items=bake_state.STATES, get=_get_bake_state)

    # --- views for the panel ---
    grain_radius_um: bpy.props.FloatProperty(
        name="Grain Radius (µm)",
        description="The grain radius in micrometres: fresh powder 50, settled 100-150, old or wet snow 500-1000",
        get=_get_grain_radius_um,
        set=_set_grain_radius_um,
        min=1.0,
        max=10000.0,
        soft_min=20.0,
        soft_max=3000.0,
        precision=1,
    )


classes = (FIRN_SnowLayerSettings, FIRN_SnowTarget, FIRN_SpraySettings, FIRN_ObjectSettings)


def register_extras():
    bpy.types.Object.firn = bpy.props.PointerProperty(type=FIRN_ObjectSettings)


def unregister_extras():
    del bpy.types.Object.firn
