"""The compiled core, loaded once, with a check that it belongs to this add-on."""

try:
    from .. import firncore
except ImportError as error:  # built for another Python, or not built at all
    raise ImportError(
        "Firn's compiled module (firncore) could not be loaded: "
        f"{error}. Install the add-on zip built for this Blender "
        "(firn-<version>-linux-x86_64.zip, Python 3.11) with its Debian libraries "
        "(libopenvdb10.0, libembree3-3, libtbb12)."
    ) from error


def version_string(version):
    return ".".join(str(part) for part in version)


def check_version(addon_version):
    """Refuses a compiled module of another version than the add-on's Python code."""
    expected = version_string(addon_version)
    if firncore.__version__ != expected:
        raise ImportError(
            f"Firn's compiled module is version {firncore.__version__}, but the add-on is {expected}. "
            "Reinstall the add-on from a single firn zip (remove the old one first)."
        )
