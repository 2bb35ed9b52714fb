"""The snow's material, in the forms below; one Firn material per snow object.

Optics (before baking): Cycles' Principled Volume driven by the density grid and the object's optics:
sigma_t = density grid × extinction per density into Density, the single-scattering albedo into Color and g
into Anisotropy. With Absorption Color black, Cycles' Principled Volume has extinction = Density and scattering
= Density × Color, so Color is exactly the single-scattering albedo (intern/cycles/kernel/svm/closure.h,
svm_node_principled_volume). Rendering it is brute-force volume path tracing: slow and biased for real snow.

Baked (after Bake Scattering, docs/vdb-contract.md "Rendering baked snow"): no scattering at all. Volume
Absorption with sigma_t = k × density (Color black: Cycles absorbs (1 - Color) × Density) plus Emission
sigma_t × S(w), S(w) per channel two Henyey-Greenstein lobes: the broad one of mean firn_source and first moment
along (firn_source_x, firn_source_y, firn_source_z), the peaked one of mean firn_source_peak and one axis and k for
all channels from firn_source_peak_l1 (_view_dependent_source), w = Geometry > Incoming turned into the
object's frame (the grids' space; identity for Firn snow). An absorbing, emitting
volume renders its emission exactly in Cycles at any step size, and every ray sees it: camera rays (the snow's
look) and the indirect rays of nearby surfaces (bounce light from the snow). The bake fixes the optics it was
made with: k is the baked one (obj.firn.bake_extinction_per_density) until the next bake.

Baked with thin snow scattered (BAKED_SCATTER, when the bake wrote a `firn_scatter` grid and Scatter Thin Snow is
on; docs/vdb-contract.md "Thin snow"): the baked form fed sigma_t (1 - share) plus the Principled Volume of sigma_t
share with the bake's omega and g, share = min(1, the grid's scattered density / the density). Cycles path-traces
the light where the bake finds the snow optically thin (docs/benchmarks.md, thin-ring and thin-cycles): more
accurate there, noisier, and it needs volume bounces (bake/operators.py scatter_render_settings).

Single scattering (render mode SINGLE, Nishita et al. 1997 Fig. 6 b): camera rays meet the Principled Volume
(they scatter once and see the lamps and the world directly), every other ray (shadow rays, the ray after the
scatter) only Volume Absorption of the whole extinction, so no light scatters twice. Opaque (OPAQUE): the volume
renders nothing and the snow's surface does (snow_layer/proxy.py). Sub-balls (material/structure.py) multiply
the density by their factor before it becomes extinction, in every form.
"""

import functools
import os

import bpy

from ..common import cache
from ..common.core import firncore
from ..spray import files as spray_files
from . import optics, structure

_TAG = "firn_snow"  # ID property marking the materials Firn manages
_BAKED_TAG = "firn_baked"  # ... and those showing a bake
_FORM_TAG = "firn_form"  # the form a material was built in (a key of _FORMS), "+grains" with sub-balls
_OPTICS_NODES = ("Firn Density", "Firn Extinction", "Firn Volume", "Firn Output")
_BAKED_NODES = ("Firn Density", "Firn Extinction", "Firn Absorption", "Firn Emission", "Firn Source",
                "Firn Source X", "Firn Source Y", "Firn Source Z", "Firn Incoming", "Firn Lobe", "Firn Source Peak",
                "Firn Source Peak L1", "Firn Peak", "Firn Lobes", "Firn Output")
_BAKED_SCATTER_NODES = _BAKED_NODES + ("Firn Scatter", "Firn Volume", "Firn Mixed")
_BRANCHES = ("", " Grains")  # the node names' suffixes: without and with sub-balls
_SINGLE_NODES = ("Firn Density", "Firn Extinction", "Firn Volume", "Firn Absorption", "Firn Single", "Firn Output")
BAKED_GRIDS = firncore.BAKED_GRID_NAMES  # the core's names (docs/vdb-contract.md), not a copy of them
SCATTER_GRID = firncore.SCATTER_GRID_NAME  # the density Cycles scatters, in a baked file where some voxel scatters


def is_snow_material(material):
    return material is not None and material.get(_TAG) == 1


def is_baked_material(material):
    return is_snow_material(material) and material.get(_BAKED_TAG) == 1


def snow_material(obj):
    """The object's Firn snow material, or None (e.g. the user gave it a material of their own)."""
    slot = _snow_slot(obj)
    return slot.material if slot else None


def has_baked_grids(volume):
    """Whether the Volume's file holds the baked grids (loads the grid list if Blender has not yet). A sequence's
    grids are listed only once a frame is evaluated: its first file is read instead (its frames hold the same
    grids: spray/light.py)."""
    if volume.is_sequence:
        try:
            return set(BAKED_GRIDS) <= _file_grid_names(cache.volume_path(volume))
        except (OSError, ValueError):
            return False
    if not volume.grids.is_loaded:
        volume.grids.load()
    return set(BAKED_GRIDS) <= {grid.name for grid in volume.grids}


def has_scatter_grid(volume):
    """Whether the Volume's file (a sequence: any of its frames' files) holds the firn_scatter grid."""
    if volume.is_sequence:
        try:
            paths = spray_files.sequence_paths(cache.volume_path(volume), volume.frame_start, volume.frame_duration)
            return any(SCATTER_GRID in _file_grid_names(path) for path in paths)
        except (OSError, ValueError):
            return False
    if not volume.grids.is_loaded:
        volume.grids.load()
    return SCATTER_GRID in {grid.name for grid in volume.grids}


def _file_grid_names(path):
    """The grid names in a file, read again only when the file changes (panels ask on every redraw)."""
    stat = os.stat(path)
    return _grid_names(path, stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=1024)  # a spray's frames
def _grid_names(path, _mtime_ns, _size):
    return frozenset(firncore.grid_names(path))


def material_form(obj):
    """How the snow renders now: its render mode, with BAKED meaning the bake while its grids are in the file
    (BAKED_SCATTER where the bake found thin snow for Cycles to scatter and Scatter Thin Snow is on) and
    brute-force path tracing of the optics (OPTICS) until then."""
    mode = obj.firn.render_mode
    if mode != "BAKED":
        return mode
    if not shows_bake(obj):
        return "OPTICS"
    return "BAKED_SCATTER" if obj.firn.scatter_thin and has_scatter_grid(obj.data) else "BAKED"


def shows_bake(obj):
    """Whether the snow's bake is in its file (BAKED or BAKED_SCATTER in render mode BAKED). Cheap enough for a
    panel's redraw, which material_form's scatter check (a spray's every frame file) is not."""
    return bool(obj.firn.bake_fingerprint) and obj.type == "VOLUME" and has_baked_grids(obj.data)


def ensure_snow_material(obj):
    """Gives a snow object its Firn material (created in the first slot if it has none), built in the form that
    fits it now (material_form, with or without sub-balls), and writes its values. Returns the material."""
    if _snow_slot(obj) is None:
        material = bpy.data.materials.new(f"Firn Snow ({obj.name})")
        material[_TAG] = 1
        if not obj.material_slots:
            obj.data.materials.append(None)
        slot = obj.material_slots[0]
        # Linked to the object, not its data: optics belong to the object, and linked duplicates share data.
        slot.link = "OBJECT"
        slot.material = material
    material = _own_material(_snow_slot(obj))
    form = material_form(obj)
    key = form + ("+grains" if obj.firn.sub_balls and form != "OPAQUE" else "")
    names, build = _FORMS[form]
    nodes = material.node_tree.nodes if material.use_nodes and material.node_tree else ()
    if material.get(_FORM_TAG) != key or not all(name in nodes for name in names):
        material.use_nodes = True
        build(material.node_tree, obj.firn.sub_balls)
        material[_FORM_TAG] = key
        if form in _BAKED_FORMS:
            material[_BAKED_TAG] = 1
        elif _BAKED_TAG in material:
            del material[_BAKED_TAG]
    if hasattr(material, "cycles"):
        resolve = obj.firn.sub_balls and obj.firn.sub_ball_resolve and obj.firn.voxel_size > 0.0
        step = obj.firn.sub_ball_radius / obj.firn.voxel_size if resolve else 1.0
        # Cycles steps voxel size x this through the volume. A voxel per step in BAKED_SCATTER too: a quarter would
        # quadruple the steps through all the snow for its few thin voxels (docs/benchmarks.md, thin-material).
        material.cycles.volume_step_rate = min(1.0, step)
    _write_values(obj, material, form)
    return material


def refresh_snow_material(obj):
    """Writes the object's current optics into its Firn material; invalid settings leave it unchanged, and so
    does a bake (it keeps the optics it was made with until the next bake)."""
    slot = _snow_slot(obj)
    if slot is None:
        return
    material = slot.material
    form = material.get(_FORM_TAG, "").split("+")[0]
    if form in _FORMS and material.node_tree and all(name in material.node_tree.nodes for name in _FORMS[form][0]):
        _write_values(obj, _own_material(slot), form)
    else:
        ensure_snow_material(obj)  # made by an earlier Firn, or its nodes were edited away


def _write_values(obj, material, form):
    nodes = material.node_tree.nodes
    if form in _BAKED_FORMS:
        extinction_per_density = obj.firn.bake_extinction_per_density
        _write_volume_optics(nodes, obj.firn.bake_albedo, obj.firn.bake_anisotropy)  # BAKED_SCATTER's
    elif form in ("OPTICS", "SINGLE"):
        try:
            volume = optics.volume_optics(obj.firn)
        except ValueError:
            return  # the Snow Material panel shows why
        extinction_per_density = volume.extinction_per_density
        _write_volume_optics(nodes, volume.albedo, volume.g)
    else:
        return
    for suffix in _BRANCHES:
        if f"Firn Extinction{suffix}" in nodes:
            nodes[f"Firn Extinction{suffix}"].inputs[1].default_value = extinction_per_density
    grains = nodes.get("Firn Sub-Balls")
    if grains is not None:
        try:
            values = structure.sub_ball_inputs(obj.firn, extinction_per_density * obj.firn.mean_density)
        except ValueError:
            return  # the Snow Structure panel shows why
        structure.set_inputs(grains, values)
        nodes["Firn Shallow Depth"].inputs[1].default_value = values["Fade End"]


def _write_volume_optics(nodes, albedo, g):
    """omega and g into the Principled Volumes (Color is omega: Absorption Color black)."""
    for suffix in _BRANCHES:
        if f"Firn Volume{suffix}" in nodes:
            nodes[f"Firn Volume{suffix}"].inputs["Color"].default_value = (*albedo, 1.0)
            nodes[f"Firn Volume{suffix}"].inputs["Anisotropy"].default_value = g


def _snow_slot(obj):
    for slot in obj.material_slots:
        if is_snow_material(slot.material):
            return slot
    return None


def _own_material(slot):
    """The slot's material, copied first when another object uses it too (a duplicate): optics and bakes
    belong to one object."""
    material = slot.material
    if material.users > 1 + int(material.use_fake_user):
        material = material.copy()
        slot.material = material
    return material


def _new_node(nodes, kind, name, label, location):
    node = nodes.new(kind)
    node.name, node.label, node.location = name, label, location
    return node


def _extinction(nodes, links, density, suffix, y):
    """density (kg/m³) × k (m²/kg) = sigma_t (1/m): the 'Firn Extinction' node's output (k set by _write_values)."""
    extinction = _new_node(nodes, "ShaderNodeMath", f"Firn Extinction{suffix}", "σt (1/m) = density × m²/kg",
                           (-350, y))
    extinction.operation = "MULTIPLY"
    links.new(density, extinction.inputs[0])
    return extinction.outputs["Value"]


def _sub_balls(nodes, links, density, y):
    """(density × the sub-balls' factor, 1 where they may differ from 1: snow down to their fade's end). Depth
    below the surface = -'surface' (m); positions are the object's coordinates, metres for Firn snow."""
    surface = _new_node(nodes, "ShaderNodeAttribute", "Firn Surface", "surface (m)", (-1200, y))
    surface.attribute_type, surface.attribute_name = "GEOMETRY", "surface"
    depth = _new_node(nodes, "ShaderNodeMath", "Firn Depth", "depth (m)", (-1000, y))
    depth.operation = "MULTIPLY"
    depth.inputs[1].default_value = -1.0
    links.new(surface.outputs["Fac"], depth.inputs[0])
    coordinates = _new_node(nodes, "ShaderNodeTexCoord", "Firn Coordinates", "", (-1000, y + 200))
    grains = _new_node(nodes, "ShaderNodeGroup", "Firn Sub-Balls", "Sub-Balls", (-800, y))
    grains.node_tree = structure.sub_ball_group()
    links.new(coordinates.outputs["Object"], grains.inputs["Position"])
    links.new(depth.outputs["Value"], grains.inputs["Depth"])
    grain_density = _new_node(nodes, "ShaderNodeMath", "Firn Grain Density", "density × sub-balls", (-550, y))
    grain_density.operation = "MULTIPLY"
    links.new(density, grain_density.inputs[0])
    links.new(grains.outputs["Factor"], grain_density.inputs[1])
    has_snow = _new_node(nodes, "ShaderNodeMath", "Firn Has Snow", "density > 0", (-800, y - 200))
    has_snow.operation = "GREATER_THAN"
    links.new(density, has_snow.inputs[0])
    shallow_depth = _new_node(nodes, "ShaderNodeMath", "Firn Shallow Depth", "depth < fade end", (-800, y - 350))
    shallow_depth.operation = "LESS_THAN"
    links.new(depth.outputs["Value"], shallow_depth.inputs[0])
    shallow = _new_node(nodes, "ShaderNodeMath", "Firn Shallow", "where sub-balls are", (-550, y - 250))
    shallow.operation = "MULTIPLY"
    links.new(has_snow.outputs["Value"], shallow.inputs[0])
    links.new(shallow_depth.outputs["Value"], shallow.inputs[1])
    return grain_density.outputs["Value"], shallow.outputs["Value"]


def _build(tree, sub_balls, shade, shared=None, camera_only=False):
    """A volume material: shade(nodes, links, sigma_t socket, name suffix, shared) -> shader socket, fed sigma_t
    from the density. With sub-balls it is built twice, the second from the grains' density, and a Mix Shader
    chooses by 'Firn Shallow': Cycles skips a mix's unused side, so the grains' texture costs only where they are.
    `camera_only`: only camera rays see the grains (baked light: they keep its mean, so other rays need not)."""
    nodes, links = tree.nodes, tree.links
    nodes.clear()
    context = shared(nodes, links) if shared else None
    density = _new_node(nodes, "ShaderNodeAttribute", "Firn Density", "Density (kg/m³)", (-600, 300))
    density.attribute_type, density.attribute_name = "GEOMETRY", "density"
    shader = shade(nodes, links, _extinction(nodes, links, density.outputs["Fac"], "", 300), "", context)
    if sub_balls:
        grain_density, shallow = _sub_balls(nodes, links, density.outputs["Fac"], 900)
        if camera_only:
            path = _new_node(nodes, "ShaderNodeLightPath", "Firn Grain Rays", "", (-550, 1300))
            seen = _new_node(nodes, "ShaderNodeMath", "Firn Shallow Camera", "shallow, camera rays", (-350, 1300))
            seen.operation = "MULTIPLY"
            links.new(shallow, seen.inputs[0])
            links.new(path.outputs["Is Camera Ray"], seen.inputs[1])
            shallow = seen.outputs["Value"]
        grains = shade(nodes, links, _extinction(nodes, links, grain_density, " Grains", 700), " Grains", context)
        mix = _new_node(nodes, "ShaderNodeMixShader", "Firn Grain Mix", "sub-balls where they are", (400, 300))
        links.new(shallow, mix.inputs["Fac"])
        links.new(shader, mix.inputs[1])
        links.new(grains, mix.inputs[2])
        shader = mix.outputs["Shader"]
    output = _new_node(nodes, "ShaderNodeOutputMaterial", "Firn Output", "", (600, 300))
    links.new(shader, output.inputs["Volume"])


def _principled(nodes, links, sigma_t, suffix, _context=None):
    volume = _new_node(nodes, "ShaderNodeVolumePrincipled", f"Firn Volume{suffix}", "Snow", (-100, 0))
    volume.inputs["Density Attribute"].default_value = ""  # the density arrives through the link only
    volume.inputs["Absorption Color"].default_value = (0.0, 0.0, 0.0, 1.0)  # Color = single-scattering albedo
    links.new(sigma_t, volume.inputs["Density"])
    return volume.outputs["Volume"]


def _absorption(nodes, links, sigma_t, suffix):
    absorption = _new_node(nodes, "ShaderNodeVolumeAbsorption", f"Firn Absorption{suffix}", "Absorption σt",
                           (-100, 300))
    absorption.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)  # absorbs (1 - Color) × Density = σt
    links.new(sigma_t, absorption.inputs["Density"])
    return absorption.outputs["Volume"]


def _single(nodes, links, sigma_t, suffix, _context=None):
    """Camera rays scatter (Principled Volume); every other ray only attenuates (Absorption of all of sigma_t)."""
    path = _new_node(nodes, "ShaderNodeLightPath", f"Firn Light Path{suffix}", "", (-100, 500))
    single = _new_node(nodes, "ShaderNodeMixShader", f"Firn Single{suffix}",
                       "camera rays scatter, others only attenuate", (200, 0))
    links.new(path.outputs["Is Camera Ray"], single.inputs["Fac"])
    links.new(_absorption(nodes, links, sigma_t, suffix), single.inputs[1])
    links.new(_principled(nodes, links, sigma_t, suffix), single.inputs[2])
    return single.outputs["Shader"]


def _operation(nodes, links, node_type, output, name, operation, operands, location):
    """A Math or Vector Math node on sockets or constants (a float or a tuple); returns its output socket."""
    node = _new_node(nodes, node_type, name, "", location)
    node.operation = operation
    for socket, value in zip(node.inputs, operands):
        if value is None:
            continue
        if isinstance(value, (float, tuple)):
            socket.default_value = value
        else:
            links.new(value, socket)
    return node.outputs[output]


def _vector_math(nodes, links, name, operation, a, b=None, location=(0, 0)):
    """A Vector Math node on sockets or constant vectors; returns its Vector output."""
    return _operation(nodes, links, "ShaderNodeVectorMath", "Vector", name, operation, (a, b), location)


def _math(nodes, links, name, operation, a, b=None, location=(0, 0)):
    """A Math node on sockets or constant values; returns its Value output."""
    return _operation(nodes, links, "ShaderNodeMath", "Value", name, operation, (a, b), location)


def _per_channel_sqrt(nodes, links, name, vector, location):
    """sqrt of each of the three components (Vector Math has no square root)."""
    x, y = location
    split = _new_node(nodes, "ShaderNodeSeparateXYZ", f"{name} Split", "", (x, y))
    join = _new_node(nodes, "ShaderNodeCombineXYZ", f"{name} Join", "", (x + 400, y))
    links.new(vector, split.inputs["Vector"])
    for index, axis in enumerate("XYZ"):
        root = _new_node(nodes, "ShaderNodeMath", f"{name} {axis}", "", (x + 200, y - 150 * index))
        root.operation = "SQRT"
        links.new(split.outputs[axis], root.inputs[0])
        links.new(root.outputs["Value"], join.inputs[axis])
    return join.outputs["Vector"]


def _peak_lobe(nodes, links, w):
    """The peaked lobe (docs/vdb-contract.md): p0 = firn_source_peak (RGB), p1 = firn_source_peak_l1, one k and axis
    for the three channels, k = min(|p1| / (3 mean(p0)), 0.95), S = p0 (1 - k²) / (1 + k² - 2 k cos)^1.5 with
    k cos = k (p1 . w) / |p1| (Cycles' divisions give 0 for a zero divisor: k = 0 where p0 = 0 or p1 = 0)."""
    p0 = _new_node(nodes, "ShaderNodeAttribute", "Firn Source Peak", "firn_source_peak", (-1800, -1800))
    p0.attribute_type, p0.attribute_name = "GEOMETRY", "firn_source_peak"
    p1 = _new_node(nodes, "ShaderNodeAttribute", "Firn Source Peak L1", "firn_source_peak_l1", (-1800, -2000))
    p1.attribute_type, p1.attribute_name = "GEOMETRY", "firn_source_peak_l1"
    mean = _new_node(nodes, "ShaderNodeVectorMath", "Firn Peak Three Mean", "3 mean(p0)", (-1600, -1800))
    mean.operation = "DOT_PRODUCT"
    links.new(p0.outputs["Vector"], mean.inputs[0])
    mean.inputs[1].default_value = (1.0, 1.0, 1.0)
    length = _new_node(nodes, "ShaderNodeVectorMath", "Firn Peak Length", "|p1|", (-1600, -2000))
    length.operation = "LENGTH"
    links.new(p1.outputs["Vector"], length.inputs[0])
    along = _new_node(nodes, "ShaderNodeVectorMath", "Firn Peak Along", "p1 . w", (-1600, -2200))
    along.operation = "DOT_PRODUCT"
    links.new(p1.outputs["Vector"], along.inputs[0])
    links.new(w, along.inputs[1])
    ratio = _math(nodes, links, "Firn Peak Ratio", "DIVIDE", length.outputs["Value"], mean.outputs["Value"],
                  (-1400, -1900))
    k = _math(nodes, links, "Firn Peak k", "MINIMUM",
              _math(nodes, links, "Firn Peak Positive", "MAXIMUM", ratio, 0.0, (-1200, -1900)),
              float(firncore.LOBE_MAX_ANISOTROPY), (-1000, -1900))
    k_cos = _math(nodes, links, "Firn Peak k cos", "DIVIDE",
                  _math(nodes, links, "Firn Peak k p1 w", "MULTIPLY", k, along.outputs["Value"], (-800, -2100)),
                  length.outputs["Value"], (-600, -2100))
    k2 = _math(nodes, links, "Firn Peak k2", "MULTIPLY", k, k, (-800, -1900))
    d = _math(nodes, links, "Firn Peak d", "SUBTRACT", _math(nodes, links, "Firn Peak 1 + k2", "ADD", 1.0, k2,
                                                              (-600, -1900)),
              _math(nodes, links, "Firn Peak 2 k cos", "MULTIPLY", k_cos, 2.0, (-400, -2100)), (-200, -1900))
    d15 = _math(nodes, links, "Firn Peak d^1.5", "MULTIPLY", d,
                _math(nodes, links, "Firn Peak Root", "SQRT", d, location=(0, -2100)), (200, -1900))
    hg = _math(nodes, links, "Firn Peak Shape", "DIVIDE",
               _math(nodes, links, "Firn Peak 1 - k2", "SUBTRACT", 1.0, k2, (0, -1800)), d15, (400, -1900))
    peak = _new_node(nodes, "ShaderNodeVectorMath", "Firn Peak", "p0 × shape", (600, -1800))
    peak.operation = "SCALE"
    links.new(p0.outputs["Vector"], peak.inputs[0])
    links.new(hg, peak.inputs["Scale"])
    return peak.outputs["Vector"]


def _view_dependent_source(nodes, links):
    """S(w) per RGB channel, two Henyey-Greenstein lobes (docs/vdb-contract.md). The broad one: l0 = firn_source,
    l1 = (firn_source_x, firn_source_y, firn_source_z), k = min(|l1| / (3 l0), 0.95), S = l0 (1 - k²) /
    (1 + k² - 2 k cos)^1.5 with k cos = k (l1 . w) / |l1|; w the direction towards the viewer in the grids' frame
    (World → Object, unit length). The three channels are the components of the Vector Math nodes' vectors
    (element-wise operations; Cycles' divisions give 0 for a zero divisor: k = 0 where l0 = 0 or l1 = 0). Plus the
    peaked one (_peak_lobe)."""
    incoming = _new_node(nodes, "ShaderNodeNewGeometry", "Firn Incoming", "w (world)", (-2600, -300))
    to_object = _new_node(nodes, "ShaderNodeVectorTransform", "Firn Incoming Object", "w (object)", (-2400, -300))
    to_object.vector_type, to_object.convert_from, to_object.convert_to = "VECTOR", "WORLD", "OBJECT"
    unit = _new_node(nodes, "ShaderNodeVectorMath", "Firn Incoming Unit", "", (-2200, -300))
    unit.operation = "NORMALIZE"
    components = _new_node(nodes, "ShaderNodeSeparateXYZ", "Firn Incoming XYZ", "", (-2000, -300))
    links.new(incoming.outputs["Incoming"], to_object.inputs["Vector"])
    links.new(to_object.outputs["Vector"], unit.inputs[0])
    links.new(unit.outputs["Vector"], components.inputs["Vector"])
    source = _new_node(nodes, "ShaderNodeAttribute", "Firn Source", "firn_source", (-1800, 0))
    source.attribute_type, source.attribute_name = "GEOMETRY", "firn_source"
    l0 = source.outputs["Vector"]
    along = squared = None  # per channel: l1 . w and |l1|²
    for index, axis in enumerate("XYZ"):
        y = -200 - 200 * index
        term = _new_node(nodes, "ShaderNodeAttribute", f"Firn Source {axis}", f"firn_source_{axis.lower()}",
                         (-1800, y))
        term.attribute_type, term.attribute_name = "GEOMETRY", f"firn_source_{axis.lower()}"
        scaled = _new_node(nodes, "ShaderNodeVectorMath", f"Firn Term {axis}", f"× w.{axis.lower()}", (-1600, y))
        scaled.operation = "SCALE"
        links.new(term.outputs["Vector"], scaled.inputs[0])
        links.new(components.outputs[axis], scaled.inputs["Scale"])
        square = _vector_math(nodes, links, f"Firn Square {axis}", "MULTIPLY", term.outputs["Vector"],
                              term.outputs["Vector"], (-1600, y - 800))
        if along is None:
            along, squared = scaled.outputs["Vector"], square
        else:
            along = _vector_math(nodes, links, f"Firn Sum {axis}", "ADD", along, scaled.outputs["Vector"], (-1400, y))
            squared = _vector_math(nodes, links, f"Firn Square Sum {axis}", "ADD", squared, square, (-1400, y - 800))
    length = _per_channel_sqrt(nodes, links, "Firn Length", squared, (-1200, -1200))
    ratio = _vector_math(nodes, links, "Firn Lobe Ratio", "DIVIDE", length,
                         _vector_math(nodes, links, "Firn Three l0", "SCALE", l0, location=(-1000, -100)),
                         (-800, -600))
    nodes["Firn Three l0"].inputs["Scale"].default_value = 3.0
    k = _vector_math(nodes, links, "Firn Lobe k", "MINIMUM",
                     _vector_math(nodes, links, "Firn Lobe Positive", "MAXIMUM", ratio, (0.0, 0.0, 0.0), (-600, -600)),
                     (firncore.LOBE_MAX_ANISOTROPY,) * 3, (-400, -600))
    k_cos = _vector_math(nodes, links, "Firn Lobe k cos", "DIVIDE",
                         _vector_math(nodes, links, "Firn Lobe k l1 w", "MULTIPLY", k, along, (-200, -500)), length,
                         (0, -500))
    k2 = _vector_math(nodes, links, "Firn Lobe k2", "MULTIPLY", k, k, (-200, -700))
    numerator = _vector_math(nodes, links, "Firn Lobe Numerator", "MULTIPLY", l0,
                             _vector_math(nodes, links, "Firn Lobe 1 - k2", "SUBTRACT", (1.0, 1.0, 1.0), k2, (0, -800)),
                             (200, -800))
    d = _vector_math(nodes, links, "Firn Lobe d", "MULTIPLY_ADD", k_cos, (-2.0, -2.0, -2.0), (200, -600))
    links.new(_vector_math(nodes, links, "Firn Lobe 1 + k2", "ADD", (1.0, 1.0, 1.0), k2, (0, -700)),
              nodes["Firn Lobe d"].inputs[2])
    d15 = _vector_math(nodes, links, "Firn Lobe d^1.5", "MULTIPLY", d,
                       _per_channel_sqrt(nodes, links, "Firn Lobe Root", d, (400, -900)), (1000, -700))
    broad = _vector_math(nodes, links, "Firn Lobe", "DIVIDE", numerator, d15, (1200, -600))
    return _vector_math(nodes, links, "Firn Lobes", "ADD", broad, _peak_lobe(nodes, links, unit.outputs["Vector"]),
                        (1400, -600))


def _baked(nodes, links, sigma_t, suffix, source):
    """Absorption sigma_t + Emission sigma_t S(w): the baked light."""
    emission = _new_node(nodes, "ShaderNodeEmission", f"Firn Emission{suffix}", "Emission σt S(w)", (-100, 0))
    links.new(source, emission.inputs["Color"])
    links.new(sigma_t, emission.inputs["Strength"])
    shader = _new_node(nodes, "ShaderNodeAddShader", f"Firn Shader{suffix}", "", (100, 150))
    links.new(_absorption(nodes, links, sigma_t, suffix), shader.inputs[0])
    links.new(emission.outputs["Emission"], shader.inputs[1])
    return shader.outputs["Shader"]


def _baked_scatter(nodes, links, sigma_t, suffix, source):
    """The thin snow scattered by Cycles itself (docs/vdb-contract.md, "Thin snow"): share = min(1, the firn_scatter
    grid's scattered density / the density; Cycles' Divide reads 0 over 0), the Principled Volume of sigma_t share
    (Color omega, Anisotropy g: the bake's, set by _write_values) plus the baked light of sigma_t (1 - share). Where
    the grid is 0 (absent too) it is the baked material."""
    y = -2400 if suffix else -300
    scatter = _new_node(nodes, "ShaderNodeAttribute", f"Firn Scatter{suffix}", SCATTER_GRID, (-1000, y))
    scatter.attribute_type, scatter.attribute_name = "GEOMETRY", SCATTER_GRID
    per_density = _math(nodes, links, f"Firn Scatter Per Density{suffix}", "DIVIDE", scatter.outputs["Fac"],
                        nodes["Firn Density"].outputs["Fac"], (-800, y))
    share = _math(nodes, links, f"Firn Share{suffix}", "MINIMUM", per_density, 1.0, (-600, y))
    scattered = _math(nodes, links, f"Firn Scattered{suffix}", "MULTIPLY", sigma_t, share, (-350, y))
    kept = _math(nodes, links, f"Firn Kept{suffix}", "MULTIPLY", sigma_t,
                 _math(nodes, links, f"Firn Not Scattered{suffix}", "SUBTRACT", 1.0, share, (-600, y - 200)),
                 (-350, y - 200))
    mixed = _new_node(nodes, "ShaderNodeAddShader", f"Firn Mixed{suffix}", "scattered + baked", (300, y))
    links.new(_principled(nodes, links, scattered, suffix), mixed.inputs[0])
    links.new(_baked(nodes, links, kept, suffix, source), mixed.inputs[1])
    return mixed.outputs["Shader"]


def _build_optics(tree, sub_balls):
    _build(tree, sub_balls, _principled)


def _build_single(tree, sub_balls):
    _build(tree, sub_balls, _single)


def _build_baked(tree, sub_balls):
    _build(tree, sub_balls, _baked, _view_dependent_source, camera_only=True)


def _build_baked_scatter(tree, sub_balls):
    _build(tree, sub_balls, _baked_scatter, _view_dependent_source, camera_only=True)


def _build_opaque(tree, _sub_balls):
    """No volume: the snow's surface renders it (snow_layer/proxy.py apply_render_surface)."""
    tree.nodes.clear()
    _new_node(tree.nodes, "ShaderNodeOutputMaterial", "Firn Output", "", (200, 0))


_FORMS = {  # form: (the nodes it must have, its builder)
    "OPTICS": (_OPTICS_NODES, _build_optics),
    "SINGLE": (_SINGLE_NODES, _build_single),
    "BAKED": (_BAKED_NODES, _build_baked),
    "BAKED_SCATTER": (_BAKED_SCATTER_NODES, _build_baked_scatter),
    "OPAQUE": (("Firn Output",), _build_opaque),
}
_BAKED_FORMS = ("BAKED", "BAKED_SCATTER")  # the forms that render a bake
