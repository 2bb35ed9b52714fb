"""The add-on registers, unregisters and re-registers cleanly."""

import addon_utils
import bpy

import firn


def _registered_firn_classes():
    names = []
    for base in (bpy.types.Operator, bpy.types.Panel, bpy.types.PropertyGroup, bpy.types.Menu):
        names += [cls.__name__ for cls in base.__subclasses__() if cls.__module__.startswith("firn")
                  and getattr(cls, "is_registered", False)]
    return sorted(names)


def test_enable_disable_enable():
    before = _registered_firn_classes()
    assert before, "no Firn classes registered"
    handlers_before = {name: len(getattr(bpy.app.handlers, name)) for name in ("save_pre", "save_post", "load_post")}

    addon_utils.disable("firn", default_set=True)
    assert _registered_firn_classes() == []
    assert not hasattr(bpy.types.Object, "firn")

    addon_utils.enable("firn", default_set=True)
    assert _registered_firn_classes() == before
    assert {name: len(getattr(bpy.app.handlers, name)) for name in handlers_before} == handlers_before


def test_version_agrees_everywhere():
    from firn.common.core import firncore

    assert firncore.__version__ == ".".join(map(str, firn.bl_info["version"]))


def test_naming_conventions():
    for name in _registered_firn_classes():
        assert name.startswith("FIRN_"), name
    assert hasattr(bpy.ops, "firn")


def test_stale_module_is_refused():
    import pytest

    from firn.common import core

    with pytest.raises(ImportError, match="compiled module is version"):
        core.check_version((99, 0, 0))


def test_preferences_exist():
    prefs = bpy.context.preferences.addons["firn"].preferences
    assert prefs.thread_count == 0
    prefs.thread_count = 1
    prefs.thread_count = 0
