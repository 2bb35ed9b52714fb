"""Where snow volumes live on disk, and keeping them next to the .blend when it is saved.

Saved file: //firn_cache/<blend name>/<object>.vdb (relative, so the folder travels with the .blend).
Unsaved file: a temporary folder of this Blender session; the files move next to the .blend on first save.
A folder set in the add-on preferences overrides both.

Failures (docs/reliability.md): a folder that cannot be written is found before any work starts, a write that fails
half way (full disk) is reported by the core, which leaves the previous file as it was. A snow file that is missing
or damaged is said so in the panels; a damaged one is set aside on load (the Volume points at no file), because
Blender 3.4 aborts on reading some truncated VDB files.
"""

import os
import shutil
import tempfile

import bpy
from bpy.app.handlers import persistent

from . import preferences
from .core import firncore
from .errors import UserError
from .jobs import idle_hooks, running_jobs

_SESSION_FOLDER = os.path.join(tempfile.gettempdir(), f"firn_cache_{os.getpid()}")
DAMAGED_KEY = "firn_damaged_file"  # Volume custom property: the path of a file set aside as unreadable
WRITE_ADVICE = ("Free some disk space, make the folder writable, or set a Cache Folder in Preferences > Add-ons > "
                "Firn")


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


def _entry(name):
    """(absolute path, path to store in a Volume) of a file or folder `name` in the cache folder."""
    absolute = os.path.join(folder(), name)
    return absolute, stored_path(absolute)


def stored_path(absolute):
    """The path to store in a Volume for the file or folder at `absolute`, as the file stands now: relative to the
    saved .blend ('//', as Blender stores paths) unless a Cache Folder is set. Jobs take it when they end, not when
    they start: the user may have saved the file elsewhere since (Save As), and a path relative to the old .blend
    would name a file that is not there."""
    prefs = preferences.get()
    if not bpy.data.filepath or (prefs and prefs.cache_folder):
        return absolute
    try:
        relative = os.path.relpath(absolute, os.path.dirname(bpy.data.filepath))
    except ValueError:  # another drive (Windows): no relative path leads there
        return absolute
    return "//" + relative.replace(os.sep, "/")  # as Blender stores relative paths, on every system


def snow_file(object_name):
    """(absolute path, path to store in the Volume) for an object's snow."""
    return _entry(bpy.path.clean_name(object_name) + ".vdb")


def spray_folder(object_name):
    """(absolute path, path to store) of the folder of a spray sequence's files (docs/spray.md): the spray's
    Volume and its tracked snow's play files from it."""
    return _entry(bpy.path.clean_name(object_name))


def stored_file(volume, folder_name):
    """The path to store in `volume` for its file in the cache entry `folder_name` (a file's own name: its
    folder is the cache folder; a sequence's folder: its files are in it)."""
    base = os.path.basename(volume.filepath)
    return f"{_entry(folder_name)[1]}/{base}" if volume.is_sequence else _entry(base)[1]


def check_writable(path):
    """UserError, before any work, when the folder of `path` cannot take a new file (read-only, not a folder)."""
    folder = os.path.dirname(path)
    try:
        os.makedirs(folder, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):  # unnamed: leaves nothing behind
            pass
    except OSError as error:
        raise UserError(f"Cannot write snow files to {folder} ({error.strerror or error}); nothing was changed. "
                        f"{WRITE_ADVICE}") from error


def core_write(write, *args):
    """write(*args): a core call that writes a snow file (atomically). Its OSError (full disk, folder gone)
    becomes a UserError that says nothing changed and what to do. A firncore.ReadError (a file the call reads is
    damaged) is not the write's fault: it goes to the caller, which knows what was read."""
    try:
        return write(*args)
    except firncore.ReadError:
        raise
    except OSError as error:
        raise UserError(f"{error}; nothing was changed. {WRITE_ADVICE}") from error


def unreadable(path):
    """Why the core cannot read the VDB file at `path`, or None. Cheap, for every snow file at load: the header
    and grid descriptors, every grid checked to lie within the file (a truncated file fails). Damage inside the
    voxels is found by the core's full read when the file is used (bake, Clear Bake)."""
    try:
        firncore.grid_names(path)
    except (OSError, ValueError, RuntimeError) as error:
        return str(error)
    return None


def volume_path(volume):
    return bpy.path.abspath(volume.filepath, library=volume.library)


def sequence_folder(volume):
    """The folder (absolute) of a Volume sequence's files: its spray folder (docs/spray.md)."""
    return os.path.dirname(volume_path(volume))


def file_problem(volume):
    """What is wrong with a snow Volume's file, in a few words, or None; cheap enough for panels."""
    if volume.get(DAMAGED_KEY):
        return f"Snow file damaged: {volume[DAMAGED_KEY]}"
    if volume.packed_file is None and not os.path.isfile(volume_path(volume)):
        return f"Snow file missing: {volume_path(volume)}"
    return None


def file_fixed(volume):
    """A new file was written for the Volume: forget that its old one was set aside."""
    if DAMAGED_KEY in volume:
        del volume[DAMAGED_KEY]


def reload_grids(volume):
    """Reads a Volume's grids again after Firn rewrote its file. Blender's evaluated copies keep the grids they
    loaded for as long as the file path stays the same (unloaded and loaded again, the old grids come back and
    render until the .blend is reopened), so the path is cleared while each live view layer is evaluated, then
    set back."""
    path = volume.filepath
    volume.filepath = ""  # unloads the Volume and tells its evaluated copies that their file changed
    for view_layer in _live_view_layers():
        view_layer.update()
    volume.filepath = path
    volume.grids.load()


def _live_view_layers():
    """The view layers with an evaluated scene: the context's and those shown in windows."""
    layers = [bpy.context.view_layer] + [window.view_layer for window in bpy.context.window_manager.windows]
    return list({layer.as_pointer(): layer for layer in layers if layer is not None}.values())


def _snow_volumes():
    return [obj.data for obj in bpy.data.objects if obj.type == "VOLUME" and obj.firn.is_snow]


@persistent
def _move_session_files_on_save(*_args):
    """After the first save of a file, its snow moves from the session folder next to the .blend; while a Firn job
    runs, once the last one has ended (it reads and writes files there: the user may save while it runs)."""
    if running_jobs() or not bpy.data.filepath:
        return
    for volume in _snow_volumes():
        source = os.path.normpath(bpy.path.abspath(volume.filepath))  # saving made it relative: '//../..'
        if not source.startswith(_SESSION_FOLDER):
            continue
        if volume.is_sequence:  # a spray sequence: its folder moves (the spray and its tracked snow share it)
            source = os.path.dirname(source)
        name = os.path.basename(source)
        target = _entry(name)[0]
        if os.path.exists(source):
            if volume.is_sequence and os.path.isdir(target):
                shutil.rmtree(target)  # an older sequence of that name: this one replaces it
            os.makedirs(os.path.dirname(target), exist_ok=True)
            shutil.move(source, target)
        if os.path.exists(target):
            volume.filepath = stored_file(volume, name)


@persistent
def _find_moved_files_on_load(*_args):
    """A file saved before its snow moved still names the session folder: look next to the .blend."""
    if not bpy.data.filepath:
        return
    for volume in _snow_volumes():
        if os.path.exists(bpy.path.abspath(volume.filepath)):
            continue
        path = bpy.path.abspath(volume.filepath)
        parts = (os.path.basename(os.path.dirname(path)),) if volume.is_sequence else ()
        stored = "/".join((_blend_cache_folder(), *parts, os.path.basename(path)))
        if os.path.exists(bpy.path.abspath(stored)):
            volume.filepath = stored


@persistent
def _set_aside_damaged_files_on_load(*_args):
    """A snow file the core cannot read (truncated, overwritten) would abort Blender when it loads the grids:
    point its Volume at no file and remember the path, for the panels and Regenerate."""
    for volume in _snow_volumes():
        path = volume_path(volume)
        if volume.packed_file is not None or not os.path.isfile(path):
            continue
        reason = unreadable(path)
        if reason is not None:
            print(f"Firn: {reason}: set aside, Regenerate the snow")
            volume[DAMAGED_KEY] = path
            volume.filepath = ""


def register_extras():
    bpy.app.handlers.save_post.append(_move_session_files_on_save)
    idle_hooks.append(_move_session_files_on_save)
    bpy.app.handlers.load_post.append(_find_moved_files_on_load)
    bpy.app.handlers.load_post.append(_set_aside_damaged_files_on_load)


def unregister_extras():
    bpy.app.handlers.save_post.remove(_move_session_files_on_save)
    idle_hooks.remove(_move_session_files_on_save)
    bpy.app.handlers.load_post.remove(_find_moved_files_on_load)
    bpy.app.handlers.load_post.remove(_set_aside_damaged_files_on_load)


classes = ()
