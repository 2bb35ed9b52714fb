"""The snow's viewport proxy: its surface as a shaded mesh for Solid and Material Preview; rendered by Cycles
only as the snow's surface in render mode OPAQUE or with glints (apply_render_surface).

The core meshes the `surface` level set three quarters of a voxel outside its zero crossing, where the snow's
density ends (firncore.snow_surface_mesh, OpenVDB's volume-to-mesh within a triangle budget), in world metres; the proxy is a child of the snow Volume, whose transform turns metres into
Blender units, so it sits exactly where the volume is drawn. While the proxy shows, the Volume is drawn as its
bounds: Blender then never uploads the dense 3-D texture for the viewport, and Cycles still renders the volume.
"""

import bpy
import numpy as np

from ..common import placement, scene_geometry
from ..common.core import firncore
from ..material import nodes as materials, preview

MAX_TRIANGLES = 150_000  # the proxy's budget: drawn at interactive rates, a few MB in the .blend
# Where the proxy lies, in voxels outside the level set's zero crossing: where the density's one-voxel ramp has
# all but ended, so glints on the proxy are not dimmed by the snow's outer half-voxel (material/preview.py).
OUTSIDE_VOXELS = 0.75
ADAPTIVITY = 0.0  # even triangles shade evenly; OpenVDB's adaptive merging costs more time than coarser voxels

DISPLAY_ITEMS = (
    ("SURFACE", "Surface", "A shaded mesh of the snow's surface in the viewport (Cycles renders the volume)"),
    ("VOLUME", "Volume", "The volume itself in the viewport (slow to draw for large snow)"),
    ("BOUNDS", "Bounds", "Only the snow's bounding box in the viewport"),
)


def mesh_settings(voxel_size):
    """The proxy's meshing of snow of voxels `voxel_size` m: firncore.snow_surface_mesh's settings (generate_snow_layer
    takes them as proxy_mesh, to mesh the new snow from memory while its file is written)."""
    return {"adaptivity": ADAPTIVITY, "max_triangles": MAX_TRIANGLES, "isovalue": OUTSIDE_VOXELS * voxel_size}


def mesh_arrays(path, voxel_size, progress=None):
    """Worker thread: the proxy's (vertices m, triangles) from the snow's VDB file of voxels `voxel_size` m; no bpy
    here."""
    return firncore.snow_surface_mesh(path, progress=progress, **mesh_settings(voxel_size))


# A far band renders as its proxy (snow_layer/operators.py, levels of detail): meshed at the band's own voxels, flat
# regions merged (OpenVDB's adaptivity), within a budget large enough that the layer, often under two voxels
# thick there, is never sampled on coarser voxels (which would open holes in it).
FAR_SURFACE_ADAPTIVITY = 0.5
FAR_SURFACE_MAX_TRIANGLES = 4_000_000


def far_surface_arrays(path, voxel_size, progress=None):
    """Worker thread: a far band's rendered surface (vertices m, triangles) from its VDB file; no bpy here."""
    return firncore.snow_surface_mesh(path, adaptivity=FAR_SURFACE_ADAPTIVITY, max_triangles=FAR_SURFACE_MAX_TRIANGLES,
                                      isovalue=OUTSIDE_VOXELS * voxel_size, progress=progress)


def new_mesh(name, vertices, triangles, smooth=False):
    """A Blender mesh of (vertices (N, 3), triangles (M, 3)) arrays."""
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", np.ascontiguousarray(vertices, np.float32).ravel())
    mesh.loops.add(triangles.size)
    mesh.loops.foreach_set("vertex_index", triangles.ravel().astype(np.int32))
    mesh.polygons.add(len(triangles))
    mesh.polygons.foreach_set("loop_start", np.arange(0, triangles.size, 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(len(triangles), 3, np.int32))
    if smooth:
        mesh.polygons.foreach_set("use_smooth", np.ones(len(triangles), bool))
    mesh.update(calc_edges=True)  # a valid mesh: every loop names its edge
    return mesh


def proxy_of(snow):
    """The snow's proxy object, or None."""
    return next((child for child in snow.children if child.firn.is_proxy), None)


def store_proxy(snow, arrays, metres):
    """Makes the snow's proxy from the core's arrays (world m), replacing any earlier one; call after the snow's
    transform is set. Its material shows the snow's optics."""
    remove_proxy(snow)
    vertices, triangles = arrays
    mesh = new_mesh(f"{snow.name} Proxy", vertices, triangles, smooth=True)
    proxy = bpy.data.objects.new(mesh.name, mesh)
    proxy.firn.is_proxy = True
    placement.follow(proxy, snow)  # metres in the snow's space: where the volume is drawn
    proxy.hide_select = True  # click the snow's bounds to select the snow
    for collection in snow.users_collection:
        collection.objects.link(proxy)
    preview.ensure_preview_material(snow, mesh, metres)
    _set_rendered(proxy, *_render_surface(snow))
    show_bake(snow)
    apply_display(snow)
    return proxy


_RAYS = ("camera", "glossy", "diffuse", "transmission", "volume_scatter", "shadow")


def _set_rendered(proxy, rendered, opaque=False):
    """Rendered viewport (Cycles) renders what the viewport shows: unless the proxy is the snow's rendered surface,
    no ray may see it. Over the volume it carries only glints, which camera and mirror rays see: every other ray
    passes it unchanged (its shadow is the facets' Fresnel share, under 1 % of the light), so only these two test it."""
    proxy.hide_render = not rendered
    seen = _RAYS if opaque else _RAYS[:2]
    for ray in _RAYS:
        setattr(proxy, f"visible_{ray}", rendered and ray in seen)


def apply_render_surface(snow, scene=None):
    """The proxy renders as the snow's surface when the snow is opaque or has glints (its material's Cycles
    output, material/preview.py), and is invisible to Cycles otherwise."""
    proxy = proxy_of(snow) if snow.type == "VOLUME" else None
    if proxy is None:
        return
    _set_rendered(proxy, *_render_surface(snow))
    refresh_preview(snow, scene or bpy.context.scene)


def _render_surface(snow):
    """(whether the proxy renders, whether as opaque snow)."""
    opaque = snow.firn.render_mode == "OPAQUE"
    return opaque or snow.firn.glints, opaque


def remove_proxy(snow):
    proxy = proxy_of(snow)
    if proxy is not None:
        mesh = proxy.data
        bpy.data.objects.remove(proxy)
        if mesh.users == 0:
            bpy.data.meshes.remove(mesh)


def refresh_preview(snow, scene):
    """After an optics change: the proxy's material shows the new optics."""
    proxy = proxy_of(snow) if snow.type == "VOLUME" else None
    if proxy is not None and proxy.data.materials and preview.is_preview_material(proxy.data.materials[0]):
        preview.refresh_preview_material(proxy.data.materials[0], snow.firn, scene_geometry.metres_per_unit(scene))


def vertex_positions(snow):
    """Main thread: the proxy's vertices (N, 3) float32, in the grids' metres, or None without a proxy."""
    proxy = proxy_of(snow)
    if proxy is None:
        return None
    points = np.empty(len(proxy.data.vertices) * 3, np.float32)
    proxy.data.vertices.foreach_get("co", points)
    return points.reshape(-1, 3)


def baked_colours(path, points):
    """Any thread (no bpy): the baked source function's mean over directions at the proxy's vertices, the means of its
    two lobes firn_source + firn_source_peak (docs/vdb-contract.md) in the file at `path`."""
    if points is None:
        return None
    return (firncore.sample_color_grid(path, "firn_source", points)
            + firncore.sample_color_grid(path, "firn_source_peak", points))


def show_bake(snow, colours=None):
    """After Bake Scattering or Clear Bake: the proxy shows the snow's baked colours (`colours` per vertex, sampled
    by the bake's worker; read here when not given) while the snow has a bake in its file, else its optics."""
    proxy = proxy_of(snow)
    if proxy is None or not proxy.data.materials or not preview.is_preview_material(proxy.data.materials[0]):
        return
    mesh, material = proxy.data, proxy.data.materials[0]
    if preview.BAKED_ATTRIBUTE in mesh.attributes:
        mesh.attributes.remove(mesh.attributes[preview.BAKED_ATTRIBUTE])
    baked = bool(snow.firn.bake_fingerprint) and materials.has_baked_grids(snow.data)
    if baked:
        if colours is None or len(colours) != len(mesh.vertices):
            colours = baked_colours(bpy.path.abspath(snow.data.filepath), vertex_positions(snow))
        rgba = np.ones((len(colours), 4), np.float32)
        rgba[:, :3] = colours
        attribute = mesh.attributes.new(preview.BAKED_ATTRIBUTE, "FLOAT_COLOR", "POINT")
        attribute.data.foreach_set("color", rgba.ravel())
    preview.show_baked(material, baked)
    apply_display(snow)  # the snow's material may have been rebuilt


def apply_display(snow):
    """Shows the snow in the viewport as its Display setting says (obj.firn.display). EEVEE renders a volume's
    material whatever the object's display type (in view-aligned slices: the streaks the proxy replaces), so
    unless the volume itself is to be seen the snow material's output is for Cycles alone."""
    display = snow.firn.display
    snow.display_type = "TEXTURED" if display == "VOLUME" else "BOUNDS"
    proxy = proxy_of(snow)
    if proxy is not None:
        proxy.hide_viewport = display != "SURFACE"
    material = materials.snow_material(snow)
    output = material.node_tree.nodes.get("Firn Output") if material and material.node_tree else None
    if output is not None:
        output.target = "ALL" if display == "VOLUME" else "CYCLES"
