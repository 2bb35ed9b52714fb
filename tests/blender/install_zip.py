"""The user's install path: Preferences > Add-ons > Install, scripted, into a factory-settings Blender.

blender -b --factory-startup --python install_zip.py -- ZIP SCRIPTS_DIR (BLENDER_USER_SCRIPTS=SCRIPTS_DIR)
"""

import shutil
import sys

import addon_utils
import bpy

zip_path, scripts_dir = sys.argv[sys.argv.index("--") + 1:][:2]
shutil.rmtree(scripts_dir + "/addons/firn", ignore_errors=True)

result = bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
assert result == {"FINISHED"}, result
module = addon_utils.enable("firn", default_set=True)
assert module is not None, "firn did not enable from the zip"
assert module.__file__.startswith(scripts_dir), module.__file__
bpy.ops.firn.add_snow_layer.get_rna_type()  # KeyError if the operator is not registered
addon_utils.disable("firn", default_set=True)
print("zip install: OK", module.bl_info["version"])
