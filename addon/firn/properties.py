"""Firn's data on Blender objects: obj.firn."""

import math

import bpy

from .bake import state as bake_state
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
    ("DRAFT", "Draft", "Fewer sky and shadow rays, a looser solve: quick previews"),
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
    targets: bpy.props.CollectionProperty(type=FIRN_SnowTarget, name="Targets")
    metaballs: bpy.props.PointerProperty(
        type=bpy.types.Object, name="Metaballs", description="Point mesh of the snow's metaballs (edit, then rebuild)")
    voxel_size: bpy.props.FloatProperty(
        name="Voxel Size", description="Voxel size of the snow volume in metres (whatever the Unit Scale)",
        default=0.0, min=0.0)

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


classes = (FIRN_SnowLayerSettings, FIRN_SnowTarget, FIRN_ObjectSettings)


def register_extras():
    bpy.types.Object.firn = bpy.props.PointerProperty(type=FIRN_ObjectSettings)


def unregister_extras():
    del bpy.types.Object.firn
