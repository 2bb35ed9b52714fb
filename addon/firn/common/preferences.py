"""Add-on preferences: where caches go and how many threads the core may use."""

import bpy

from .core import firncore


def _addon_name():
    return __package__.partition(".")[0]  # the add-on's top package ("firn"), whatever folder holds this file


def get():
    """The add-on's preferences, or None while it is not enabled (e.g. in a bare unit test)."""
    addon = bpy.context.preferences.addons.get(_addon_name())
    return addon.preferences if addon else None


def _apply_thread_count(self, _context):
    firncore.set_thread_count(self.thread_count)


class FIRN_AddonPreferences(bpy.types.AddonPreferences):
    bl_idname = _addon_name()

    cache_folder: bpy.props.StringProperty(
        name="Cache Folder",
        description="Folder for snow volumes of every file. Empty: a firn_cache folder next to the .blend file "
        "(a temporary folder until the file is saved)",
        subtype="DIR_PATH",
        default="",
    )
    thread_count: bpy.props.IntProperty(
        name="Threads",
        description="Threads the Firn core may use for generation and baking (0: all cores)",
        min=0,
        max=1024,
        default=0,
        update=_apply_thread_count,
    )

    voxel_budget_millions: bpy.props.FloatProperty(
        name="Voxel Budget (millions)",
        description="Largest snow volume Firn builds, in millions of voxels (about 16 bytes each while building); "
        "a larger snow asks for a larger voxel size",
        min=0.1,
        max=10000.0,
        default=50.0,
    )

    def draw(self, _context):
        layout = self.layout
        layout.prop(self, "cache_folder")
        layout.prop(self, "thread_count")
        layout.prop(self, "voxel_budget_millions")
        layout.label(text=f"Core version {firncore.__version__}, {firncore.hardware_threads()} hardware threads")


classes = (FIRN_AddonPreferences,)


def register_extras():
    prefs = get()
    if prefs:
        firncore.set_thread_count(prefs.thread_count)


def unregister_extras():
    firncore.set_thread_count(0)
