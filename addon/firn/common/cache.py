"""Where snow volumes live on disk, and keeping them next to the .blend when it is saved.

Saved file: //firn_cache/<blend name>/<object>.vdb (relative, so the folder travels with the .blend).
Unsaved file: a temporary folder of this Blender session; the files move next to the .blend on first save.
A folder set in the add-on preferences overrides both.
"""

import os
import shutil
import tempfile

import bpy
from bpy.app.handlers import persistent

from . import preferences

_SESSION_FOLDER = os.path.join(tempfile.gettempdir(), f"firn_cache_{os.getpid()}")


def _blend_cache_folder():
    """The cache folder of the saved .blend, as a '//' relative path."""
    name = os.path.splitext(bpy.path.basename(bpy.data.filepath))[0]
    return f"//firn_cache/{bpy.path.clean_name(name)}"


def folder():
    """The folder new snow files go to (absolute)."""
    prefs = preferences.get()
    if prefs and prefs.cache_folder:
        return bpy.path.abspath(prefs.cache_folder)
    if bpy.data.filepath:
        return bpy.path.abspath(_blend_cache_folder())
    return _SESSION_FOLDER


def snow_file(object_name):
    """(absolute path, path to store in the Volume) for an object's snow."""
    file_name = bpy.path.clean_name(object_name) + ".vdb"
    absolute = os.path.join(folder(), file_name)
    prefs = preferences.get()
    if bpy.data.filepath and not (prefs and prefs.cache_folder):
        return absolute, f"{_blend_cache_folder()}/{file_name}"
    return absolute, absolute


def _snow_volumes():
    return [obj.data for obj in bpy.data.objects if obj.type == "VOLUME" and obj.firn.is_snow]


@persistent
def _move_session_files_on_save(*_args):
    """After the first save of a file, its snow moves from the session folder next to the .blend."""
    for volume in _snow_volumes():
        source = os.path.normpath(bpy.path.abspath(volume.filepath))  # saving made it relative: '//../..'
        if not source.startswith(_SESSION_FOLDER) or not os.path.exists(source):
            continue
        target, stored = snow_file(os.path.splitext(os.path.basename(source))[0])
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.move(source, target)
        volume.filepath = stored


@persistent
def _find_moved_files_on_load(*_args):
    """A file saved before its snow moved still names the session folder: look next to the .blend."""
    if not bpy.data.filepath:
        return
    for volume in _snow_volumes():
        if os.path.exists(bpy.path.abspath(volume.filepath)):
            continue
        stored = f"{_blend_cache_folder()}/{os.path.basename(volume.filepath)}"
        if os.path.exists(bpy.path.abspath(stored)):
            volume.filepath = stored


def register_extras():
    bpy.app.handlers.save_post.append(_move_session_files_on_save)
    bpy.app.handlers.load_post.append(_find_moved_files_on_load)


def unregister_extras():
    bpy.app.handlers.save_post.remove(_move_session_files_on_save)
    bpy.app.handlers.load_post.remove(_find_moved_files_on_load)


classes = ()
