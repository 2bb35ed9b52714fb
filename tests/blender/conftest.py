import bpy
import pytest


@pytest.fixture
def clean_scene():
    """Factory-empty scene for each test."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    import addon_utils

    addon_utils.enable("firn", default_set=True)
    yield bpy.context.scene
