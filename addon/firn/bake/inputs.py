"""What lights and shadows a snow object, read from Blender for the bake (main thread, but for the functions
that say "any thread"). No physics here.

- Suns: Blender Sun lamps (direction towards the sun, irradiance = Strength × Color in W/m², Angle).
- Lamps: Point and Spot (intensity Power / 4π × Color in W/sr, Radius; a Spot's Size and Blend) and Area lamps
  (radiance Power / (4 × area) × Color in W/m²/sr, shape and size): Cycles 3.4's emission, measured in
  tests/blender/test_lamps.py. A lamp whose Volume Scatter ray visibility is off does not light the snow.
- Sky: the scene's World. A plain Background colour × strength is read directly. A Nishita Sky Texture →
  Background → World Output, nothing else, is computed by the core from the node's settings (NishitaWorld,
  cpp/firn/transport/nishita_sky.h) in the bake's worker: its sky map and its disc as a sun. Anything else (HDRI,
  any other node world) is rendered by Cycles (bake/world_probe.py, off the main thread when the bake runs from
  the UI). Either way the sky becomes a small equirectangular radiance map (W/m²/sr) in the convention of
  cpp/firn/transport/lights.h, and a Nishita sun disc becomes a sun: a half-degree disc is far smaller than a
  map pixel.
- Occluders: every rendered mesh-like object or collection instance that casts shadows (not snow), with what it
  instances (particles, Geometry Nodes), split by object, instance and material, each part with its diffuse
  albedo.

Everything is given in the snow object's own frame, the space of its grids: Cycles renders a VDB volume in
object space (a uniform scale leaves the optical path unchanged), so the core bakes there. Firn snow's grids are
in world metres and its transform scales metres to Blender units (identity at Unit Scale 1), so for it this is
world space in metres.
"""

import hashlib
import math
import zlib
from dataclasses import dataclass, field

import bpy
import numpy as np
from mathutils import Vector

from ..common import scene_geometry
from ..common.core import firncore
from ..common.errors import UserError
from . import world_probe

DEFAULT_ALBEDO = (0.8, 0.8, 0.8)  # surfaces without a material: Blender's default grey


@dataclass(frozen=True)
class Sun:
    name: str
    direction: tuple  # unit vector towards the sun, in the snow's frame
    irradiance: tuple  # W/m² per RGB channel on a plane facing the sun
    angular_diameter: float  # rad


@dataclass(frozen=True)
class Lamp:
    """A Point, Spot or Area lamp in the snow's frame (cpp/firn/transport/lamps.h)."""
    name: str
    shape: str  # POINT, SPOT, RECTANGLE, ELLIPSE
    position: tuple  # m
    emission: tuple  # W/sr (POINT, SPOT) or W/m²/sr (RECTANGLE, ELLIPSE) per RGB channel
    axis: tuple  # unit: where it shines
    tangent: tuple  # unit: an area lamp's size X direction
    radius: float = 0.0  # m
    spot_angle: float = math.pi  # rad, full
    spot_blend: float = 0.0
    size: tuple = (1.0, 1.0)  # m


@dataclass
class Sky:
    radiance: tuple = (0.0, 0.0, 0.0)  # W/m²/sr per channel; scales `map` when there is one
    map: np.ndarray = None  # (height, width, 3) float32 W/m²/sr, rows bottom (nadir) to top (zenith)
    description: str = "black"


@dataclass
class Occluder:
    name: str
    vertices: np.ndarray  # (N, 3) float32, m, in the snow's frame
    triangles: np.ndarray  # (M, 3) uint32
    albedo: tuple  # diffuse, linear RGB in [0, 1]


@dataclass
class BakeInputs:
    suns: list
    sky: Sky  # None while the world is still to be rendered or computed (add_world_light)
    occluders: list
    frame: "Frame"
    warnings: list = field(default_factory=list)
    lamps: list = field(default_factory=list)  # [Lamp]


class Frame:
    """The snow object's frame: world (metres) → object space for points and directions."""

    def __init__(self, obj, metres_per_unit=1.0):
        matrix = np.array(obj.matrix_world, np.float64)
        linear = matrix[:3, :3]
        scale = np.cbrt(np.linalg.det(linear))
        rotation = linear / scale if scale > 0.0 else linear
        if scale <= 0.0 or not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-5):
            raise UserError(
                f"'{obj.name}' has a non-uniform, negative or zero scale: Cycles stretches the optics of such "
                "volumes. Baking needs rotation, uniform scale and translation only (Firn snow keeps a transform "
                "that only scales its metres to Blender units: 1 / Unit Scale)")
        self.rotation = rotation  # object → world, for directions
        # Points come in world metres (scene_geometry); matrix_world maps object space to Blender units.
        self.world_to_object = np.linalg.inv(matrix) @ np.diag([1.0 / metres_per_unit] * 3 + [1.0])
        self.is_identity = np.allclose(self.world_to_object, np.eye(4), atol=1e-9)

    def length(self, metres):
        """A length in the snow's frame."""
        return metres * float(np.cbrt(np.linalg.det(self.world_to_object[:3, :3])))

    def direction(self, world_direction):
        local = self.rotation.T @ np.asarray(world_direction, np.float64)
        return tuple(local / np.linalg.norm(local))

    def points(self, world_points):
        if self.is_identity:
            return world_points
        m = self.world_to_object
        return (world_points.astype(np.float64) @ m[:3, :3].T + m[:3, 3]).astype(np.float32)


# --- which objects take part ---------------------------------------------------------------------------------

def rendered_objects(view_layer):
    """Objects the view layer renders: in an included, rendering collection and not hidden from renders."""
    found = {}

    def visit(layer_collection):
        if layer_collection.exclude or layer_collection.collection.hide_render:
            return
        for obj in layer_collection.collection.objects:
            if not obj.hide_render:
                found[obj.name] = obj
        for child in layer_collection.children:
            visit(child)

    visit(view_layer.layer_collection)
    return list(found.values())


def lamp_objects(view_layer):
    return [obj for obj in rendered_objects(view_layer) if obj.type == "LIGHT"]


def occluder_objects(view_layer):
    """Rendered objects that cast shadows in Cycles, mesh-like ones and collection instances (their instances
    come with them: scene_geometry); snow volumes are never occluders."""
    return [obj for obj in rendered_objects(view_layer)
            if scene_geometry.makes_geometry(obj) and obj.visible_shadow]


# --- suns and lamps -------------------------------------------------------------------------------------------

def _sun(obj, frame):
    light = obj.data
    # A lamp shines along its local -Z axis; the core wants the direction towards the sun.
    towards = obj.matrix_world.to_3x3() @ Vector((0.0, 0.0, 1.0))
    if towards.length < 1e-12:
        return None  # a zero-scaled lamp lights nothing
    if light.angle > math.pi / 2:
        raise UserError(f"Sun '{obj.name}' has an Angle of {math.degrees(light.angle):.0f}°: "
                        "Firn bakes suns of up to 90°")
    return Sun(obj.name, frame.direction(towards.normalized()), tuple(light.energy * c for c in light.color),
               light.angle)


def _lamp(obj, frame, metres_per_unit):
    """A Point, Spot or Area lamp as Cycles 3.4 renders it: its transform's rotation, its scale for an area's
    size (not for a sphere's radius), and its location."""
    light = obj.data
    matrix = obj.matrix_world.to_3x3()
    u, v, w = (matrix.col[k] for k in range(3))
    if min(u.length, v.length, w.length) < 1e-12:
        return None  # a zero-scaled lamp lights nothing
    position = frame.points(np.array([obj.matrix_world.translation], np.float64) * metres_per_unit)[0]
    placed = {"position": tuple(float(x) for x in position), "axis": frame.direction(-w.normalized()),
              "tangent": frame.direction(u.normalized())}
    colour = light.color
    if light.type in {"POINT", "SPOT"}:
        emission = tuple(light.energy / (4.0 * math.pi) * c for c in colour)
        radius = frame.length(light.shadow_soft_size * metres_per_unit)
        spot = {"spot_angle": light.spot_size, "spot_blend": light.spot_blend} if light.type == "SPOT" else {}
        return Lamp(obj.name, light.type, emission=emission, radius=radius, **placed, **spot)
    square = light.shape in {"SQUARE", "DISK"}
    size = (frame.length(light.size * u.length * metres_per_unit),
            frame.length((light.size if square else light.size_y) * v.length * metres_per_unit))
    ellipse = light.shape in {"DISK", "ELLIPSE"}
    area = size[0] * size[1] * (math.pi / 4.0 if ellipse else 1.0)
    emission = tuple(light.energy / (4.0 * area) * c for c in colour)
    return Lamp(obj.name, "ELLIPSE" if ellipse else "RECTANGLE", emission=emission, size=size, **placed)


def gather_lights(lamps, frame, metres_per_unit=1.0):
    """([Sun], [Lamp]) for the given lamp objects; dark lamps and lamps that do not light volumes (Volume
    Scatter ray visibility off) are left out."""
    suns, others = [], []
    for obj in lamps:
        if obj.data.energy <= 0.0 or not obj.visible_volume_scatter:
            continue
        if obj.data.type == "SUN":
            light = _sun(obj, frame)
            suns += [light] if light else []
        else:
            light = _lamp(obj, frame, metres_per_unit)
            others += [light] if light else []
    return suns, others


# --- sky ------------------------------------------------------------------------------------------------------

def _world_surface_link(world):
    output = world.node_tree.get_output_node("CYCLES")
    if output is None or not output.inputs["Surface"].is_linked:
        return None
    return output.inputs["Surface"].links[0]


def uniform_world_radiance(world):
    """RGB radiance (W/m²/sr) of a world that is the same in every direction, read from its settings;
    None when it has to be rendered."""
    if world is None:
        return (0.0, 0.0, 0.0)
    if not world.use_nodes or world.node_tree is None:
        return tuple(world.color)
    link = _world_surface_link(world)
    if link is None:
        return (0.0, 0.0, 0.0)  # a node world without a surface renders black
    node = link.from_node
    if (node.type != "BACKGROUND" or node.mute or link.is_muted
            or node.inputs["Color"].is_linked or node.inputs["Strength"].is_linked):
        return None
    strength = node.inputs["Strength"].default_value
    return tuple(strength * c for c in node.inputs["Color"].default_value[:3])


def _sky_sun_nodes(world):
    """Nishita Sky Textures of the world's own tree that draw a sun disc."""
    if world is None or not world.use_nodes or world.node_tree is None:
        return []
    return [node for node in world.node_tree.nodes
            if node.type == "TEX_SKY" and node.sky_type == "NISHITA" and node.sun_disc and not node.mute]


def sky_sun_direction(node):
    """World direction towards a Nishita sky's sun (Cycles: rotation 0 puts it at +Y, turning towards +X)."""
    e, r = node.sun_elevation, node.sun_rotation
    return Vector((math.sin(r) * math.cos(e), math.cos(r) * math.cos(e), math.sin(e)))


def sun_irradiance(radiance, field_of_view):
    """Irradiance (W/m², per channel) on a plane facing the view from a square pinhole image of radiance:
    E = sum L cos(theta) dOmega, with dOmega cos(theta) = dA / (1 + x² + y²)² on the image plane at distance 1."""
    n = radiance.shape[0]
    half = math.tan(field_of_view / 2.0)
    centres = (np.arange(n) + 0.5) / n * 2.0 * half - half
    x, y = np.meshgrid(centres, centres)
    weight = (2.0 * half / n) ** 2 / (1.0 + x * x + y * y) ** 2
    return (radiance * weight[:, :, None]).sum(axis=(0, 1))


def _measured_sky_suns(world):
    """(Nishita nodes whose sun disc is measured apart: [(node name, direction towards the sun in the world, its
    angular diameter in rad)], warnings about the others)."""
    measured, warnings = [], []
    for node in _sky_sun_nodes(world):
        if node.inputs["Vector"].is_linked:
            warnings.append(f"The sun disc of the mapped sky texture '{node.name}' stays in the sky map (blurred): "
                            "unlink its Vector input or use a Sun lamp for sharp sunlight")
            continue
        measured.append((node.name, tuple(sky_sun_direction(node)), node.sun_size))
    return measured, warnings


def plan_sky(scene):
    """(Sky, warnings) of a world read from its settings, or (None, warnings) when it must be rendered or
    computed (world_request, then add_world_light)."""
    world = scene.world
    if world is not None and not world.cycles_visibility.scatter:
        return Sky(description="world hidden from volume scattering"), [
            f"World '{world.name}' is hidden from volume scattering rays (Ray Visibility): it does not light the snow"]
    radiance = uniform_world_radiance(world)
    if radiance is not None:
        return Sky(radiance=tuple(radiance), description="uniform"), []
    return None, _measured_sky_suns(world)[1]


# --- a Nishita sky, computed by the core -----------------------------------------------------------------------

SKY_MAP_SAMPLES = 2  # per pixel axis: the core's map averages 2 × 2 directions per pixel, as a box filter
_NISHITA_SETTINGS = ("sun_elevation", "sun_rotation", "sun_size", "sun_intensity", "sun_disc", "altitude",
                     "air_density", "dust_density", "ozone_density")
_IDENTITY_MAPPING = {"translation": (0.0, 0.0, 0.0), "rotation": (0.0, 0.0, 0.0), "scale": (1.0, 1.0, 1.0),
                     "mapping_x": "X", "mapping_y": "Y", "mapping_z": "Z", "use_min": False, "use_max": False}


@dataclass
class NishitaWorld:
    """A world that is one Nishita Sky Texture → Background → World Output: the core computes its sky map and
    sun from the node's settings (light, any thread), no render. Maps are kept per orientation."""
    world: str
    node: str
    parameters: dict  # firncore.NishitaSky's settings
    maps: dict = field(default_factory=dict)
    status = "Computing the sky"

    def prepare(self, cancelled):
        """Nothing to render: the core computes the light in light(). True: ready."""
        return True

    def light(self, frame):
        """(Sky, [Sun]) in `frame`, computed by the core (any thread; without the GIL)."""
        try:
            sky = firncore.NishitaSky(**self.parameters)
            key = _rotation_key(frame)
            if key not in self.maps:
                self.maps[key] = sky.map(frame.rotation, *world_probe.SKY_MAP_SIZE, samples=SKY_MAP_SAMPLES)
            sun = sky.sun()
        except ValueError as error:
            raise UserError(f"World '{self.world}': {error}") from error
        sky_map = self.maps[key]
        suns = [] if sun is None else [Sun(f"{self.world}: {self.node}", frame.direction(sun.direction),
                                           tuple(sun.irradiance), sun.angular_diameter)]
        height, width = sky_map.shape[:2]
        return Sky(radiance=(1.0, 1.0, 1.0), map=sky_map, description=f"Nishita {width}×{height}"), suns

    def discard(self):
        """Nothing to remove (a RenderedWorld removes its files)."""


def _unmapped(node):
    mapping = node.texture_mapping
    return all((tuple(value) if hasattr(value, "__len__") and not isinstance(value, str) else value) == expected
               for value, expected in ((getattr(mapping, key), expected)
                                       for key, expected in _IDENTITY_MAPPING.items()))


def _nishita_node(world):
    """(Sky Texture node, Background strength) when the world's surface is exactly a Nishita Sky Texture's
    Color → Background (Strength not linked, not negative) → World Output, unmapped and unmuted, with no
    volume; None for any other world."""
    if world is None or not world.use_nodes or world.node_tree is None:
        return None
    link = _world_surface_link(world)
    if link is None or world.node_tree.get_output_node("CYCLES").inputs["Volume"].is_linked:
        return None
    background = link.from_node
    if (link.is_muted or background.type != "BACKGROUND" or background.mute
            or background.inputs["Strength"].is_linked or not background.inputs["Color"].is_linked):
        return None
    colour = background.inputs["Color"].links[0]
    node, strength = colour.from_node, background.inputs["Strength"].default_value
    if (colour.is_muted or node.type != "TEX_SKY" or node.sky_type != "NISHITA" or node.mute
            or node.inputs["Vector"].is_linked or not _unmapped(node) or strength < 0.0):
        return None
    return node, strength


def nishita_parameters(world):
    """firncore.NishitaSky's settings (angles in rad, altitude in m, the Background's strength) of a world that
    is exactly a Nishita sky (_nishita_node); None for any other world (it is rendered instead)."""
    found = _nishita_node(world)
    return None if found is None else _node_parameters(*found)


def _node_parameters(node, strength):
    return dict({key: getattr(node, key) for key in _NISHITA_SETTINGS}, strength=strength)


def _nishita_world(world):
    found = _nishita_node(world)
    if found is None:
        return None
    node, strength = found
    return NishitaWorld(world.name, node.name, _node_parameters(node, strength))


# --- any other world, rendered by Cycles ----------------------------------------------------------------------

def world_request(scene, frames):
    """Main thread: what the scene's world needs to become light in each Frame: a NishitaWorld (the settings
    only), else a RenderedWorld (one map per distinct orientation). Cheap: the world is only saved; prepare()
    renders it, off the main thread if called from a worker; light(frame) then gives (Sky, [Sun])."""
    nishita = _nishita_world(scene.world)
    if nishita is not None:
        return nishita
    rotations = {_rotation_key(frame): frame.rotation for frame in frames}
    try:
        return RenderedWorld(world_probe.request(scene.world, scene.frame_current, list(rotations.values()),
                                                 _measured_sky_suns(scene.world)[0]))
    except world_probe.RenderError as error:
        raise UserError(f"Could not render the world for the bake: {error}") from error


def _rotation_key(frame):
    return tuple(np.round(frame.rotation, 6).ravel())


@dataclass
class RenderedWorld:
    """Any other world: rendered by Cycles (world_probe: in place on the main thread, else by a child Blender)
    before its light is read."""
    request: world_probe.Request
    rendering: world_probe.Rendering = None
    status = "Rendering the world"

    def prepare(self, cancelled):
        """Renders the world and removes its files; False once `cancelled()` turns true."""
        try:
            self.rendering = world_probe.render(self.request, cancelled)
        except world_probe.RenderError as error:
            raise UserError(f"Could not render the world for the bake: {error}") from error
        return self.rendering is not None

    def light(self, frame):
        """(Sky, [Sun]) in `frame` from the rendering (numpy only: any thread)."""
        request, rendering = self.request, self.rendering
        keys = [tuple(np.round(np.asarray(r), 6).ravel()) for r in request.rotations]
        sky_map = rendering.maps[keys.index(_rotation_key(frame))]
        if not np.all(np.isfinite(sky_map)):
            raise UserError(f"World '{request.world}' renders non-finite radiance")
        sky_map = np.maximum(sky_map, 0.0)  # node worlds can go negative; radiance cannot
        height, width = sky_map.shape[:2]
        suns = []
        for (name, direction, diameter), (with_disc, without_disc) in zip(request.suns, rendering.discs):
            # The disc alone: the sky with it minus the sky without it, integrated over the close-up.
            field_of_view = world_probe.disc_field_of_view(diameter)
            irradiance = np.maximum(sun_irradiance(with_disc - without_disc, field_of_view), 0.0)
            if irradiance.max() > 0.0:
                suns.append(Sun(f"{request.world}: {name}", frame.direction(direction),
                                tuple(float(e) for e in irradiance), diameter))
        return Sky(radiance=(1.0, 1.0, 1.0), map=sky_map, description=f"map {width}×{height}"), suns

    def discard(self):
        self.request.discard()


def gather_sky(scene, frame):
    """(Sky, [Sun] from sky textures, warnings) of the scene's world in `frame`, rendered here if need be (main
    thread)."""
    sky, warnings = plan_sky(scene)
    if sky is not None:
        return sky, [], warnings
    world = world_request(scene, [frame])
    world.prepare(cancelled=lambda: False)
    return (*world.light(frame), warnings)


# --- occluders ------------------------------------------------------------------------------------------------

def _surface_node(material):
    if not material.use_nodes or material.node_tree is None:
        return None
    output = material.node_tree.get_output_node("CYCLES")
    if output is None or not output.inputs["Surface"].is_linked:
        return None
    return output.inputs["Surface"].links[0].from_node


def diffuse_albedo(material):
    """Diffuse albedo (linear RGB): a plain Principled Base Color or Diffuse BSDF Color, else the material's
    viewport colour; Blender's 0.8 grey without a material."""
    if material is None:
        return DEFAULT_ALBEDO
    node = _surface_node(material)
    sockets = {"BSDF_PRINCIPLED": "Base Color", "BSDF_DIFFUSE": "Color"}
    if node is not None and node.type in sockets and not node.mute:
        socket = node.inputs[sockets[node.type]]
        if not socket.is_linked:
            return tuple(min(max(c, 0.0), 1.0) for c in socket.default_value[:3])
    return tuple(min(max(c, 0.0), 1.0) for c in material.diffuse_color[:3])


def gather_occluders(objects, depsgraph, frame):
    """One Occluder per object or instance and material, modifiers applied."""
    occluders = []
    for name, vertices, triangles, material in scene_geometry.world_triangles_by_material(objects, depsgraph):
        name = name if material is None else f"{name} [{material.name}]"
        occluders.append(Occluder(name, frame.points(vertices), triangles, diffuse_albedo(material)))
    return occluders


# --- everything -----------------------------------------------------------------------------------------------

def gather(context, snow, occluders=gather_occluders):
    """BakeInputs of one snow object. A world that is not a plain colour is left to compute or render (`sky`
    None, see plan_sky): bake/operators.py does it off the main thread. `occluders(objects, depsgraph, frame)` gathers
    the occluders (spray/light.py shares the ones that stand still over a frame range)."""
    depsgraph = context.evaluated_depsgraph_get()  # first: it also brings every matrix_world up to date
    frame = Frame(snow, scene_geometry.metres_per_unit(context.scene))
    view_layer = context.view_layer
    suns, lamps = gather_lights(lamp_objects(view_layer), frame, scene_geometry.metres_per_unit(context.scene))
    sky, warnings = plan_sky(context.scene)
    return BakeInputs(suns, sky, occluders(occluder_objects(view_layer), depsgraph, frame), frame, warnings, lamps)


def add_world_light(inputs, world):
    """Completes BakeInputs gathered with the world left to compute or render (a NishitaWorld, or a RenderedWorld
    once prepared); any thread."""
    inputs.sky, sky_suns = world.light(inputs.frame)
    inputs.suns = inputs.suns + sky_suns


# --- what the bake depends on, cheap enough to check at every redraw ------------------------------------------

def digest(*parts):
    return hashlib.sha1(repr(parts).encode()).hexdigest()[:16]


def rounded(values):
    return tuple(float(f"{v:.7g}") for v in values)


_UI_ONLY = {"rna_type", "name", "label", "location", "width", "width_hidden", "height", "dimensions", "select",
            "hide", "show_options", "show_preview", "show_texture", "use_custom_color", "color", "parent",
            "bl_idname", "bl_label", "bl_description", "bl_icon", "bl_static_type", "bl_width_default",
            "bl_width_min", "bl_width_max", "bl_height_default", "bl_height_min", "bl_height_max", "type",
            "is_active_output", "internal_links", "inputs", "outputs"}


def _rna_values(struct, depth=0, seen=None):
    """The settings of a node (or any RNA struct) as plain values, recursing into node groups and
    texture-mapping structs; images by file path."""
    seen = set() if seen is None else seen
    values = []
    for prop in struct.bl_rna.properties:
        key = prop.identifier
        if key in _UI_ONLY:
            continue
        value = getattr(struct, key, None)
        if prop.type in {"BOOLEAN", "INT", "FLOAT", "ENUM", "STRING"}:
            values.append((key, tuple(value) if hasattr(value, "__len__") and not isinstance(value, str)
                           else value))
        elif prop.type == "POINTER" and value is not None:
            if isinstance(value, bpy.types.Image):
                values.append((key, value.filepath, value.source))  # not .size: 0 x 0 until loaded
            elif isinstance(value, bpy.types.NodeTree) and value.name not in seen:
                seen.add(value.name)
                values.append((key, _tree_signature(value, seen)))
            elif not isinstance(value, bpy.types.ID) and depth < 2:
                values.append((key, _rna_values(value, depth + 1, seen)))
    return tuple(values)


def _tree_signature(tree, seen):
    nodes = []
    for node in sorted(tree.nodes, key=lambda n: n.name):
        inputs = tuple((s.identifier, s.is_linked, tuple(s.default_value) if hasattr(s, "default_value")
                        and hasattr(s.default_value, "__len__") else getattr(s, "default_value", None))
                       for s in node.inputs)
        nodes.append((node.name, node.bl_idname, node.mute, inputs, _rna_values(node, seen=seen)))
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier,
                    l.is_muted) for l in tree.links)
    return tuple(nodes), tuple(links)


def world_signature(world):
    if world is None:
        return None
    tree = _tree_signature(world.node_tree, set()) if world.use_nodes and world.node_tree else None
    return world.name, tuple(world.color), world.use_nodes, world.cycles_visibility.scatter, tree


def _positions_digest(positions):
    """CRC-32 of float32 positions with each float's 4 lowest mantissa bits cleared (a relative 2e-6), so float
    noise does not flip it; a CRC catches any single changed float."""
    positions = positions + np.float32(0.0)  # -0.0 becomes 0.0
    return zlib.crc32(np.bitwise_and(positions.view(np.uint32), np.uint32(0xFFFFFFF0)))


def geometry_digest(obj, depsgraph):
    """Digest of the evaluated object's shape: its vertex positions (object space, modifiers applied; the
    transform is digested apart) and its vertex and face counts, so that moving one vertex changes it. Cheap:
    about 4 ms for a million triangles (to_mesh() and a SHA-1 would take 200 ms: a mesh's evaluated data is read
    in place). An object without a surface of its own (a collection instance) digests its instances' shapes."""
    if not scene_geometry.is_mesh_like(obj):
        return tuple((name, _positions_digest(vertices), len(triangles)) for name, vertices, triangles, *_rest
                     in scene_geometry.evaluated_parts([obj], depsgraph))
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.data if obj.type == "MESH" else evaluated.to_mesh()  # a mesh's evaluated data: no copy
    try:
        if mesh is None:
            return None
        positions = np.empty(len(mesh.vertices) * 3, np.float32)
        mesh.vertices.foreach_get("co", positions)
        return _positions_digest(positions), len(mesh.vertices), len(mesh.polygons), len(mesh.loops)
    finally:
        if obj.type != "MESH":
            evaluated.to_mesh_clear()


def _occluder_record(obj, depsgraph):
    data = obj.data
    modifiers = tuple((m.name, m.type, m.show_render) for m in getattr(obj, "modifiers", ()))
    albedo = tuple(diffuse_albedo(slot.material) for slot in obj.material_slots)
    return (rounded(v for row in obj.matrix_world for v in row), data.name if data else None,
            geometry_digest(obj, depsgraph), modifiers, albedo)


def _lamp_record(lamp):
    return tuple(rounded(v) if isinstance(v, tuple) else round(v, 7) if isinstance(v, float) else v
                 for v in vars(lamp).values())


def signature(context, snow):
    """{component: digest} of what lights and shadows `snow`, without rendering anything; "occluders" is
    {object name: digest}, so a change can name the object. A changed digest means the bake no longer matches
    the scene."""
    view_layer = context.view_layer
    depsgraph = context.evaluated_depsgraph_get()
    try:
        metres_per_unit = scene_geometry.metres_per_unit(context.scene)
        suns, lamps = gather_lights(lamp_objects(view_layer), Frame(snow, metres_per_unit), metres_per_unit)
        lights = tuple((s.name, rounded(s.direction), rounded(s.irradiance), round(s.angular_diameter, 7))
                       for s in suns), tuple(_lamp_record(lamp) for lamp in lamps)
    except UserError as error:
        lights = str(error)
    return {
        "lights": digest(lights),
        "sky": digest(world_signature(context.scene.world)),
        "occluders": {obj.name: digest(_occluder_record(obj, depsgraph)) for obj in occluder_objects(view_layer)},
    }
