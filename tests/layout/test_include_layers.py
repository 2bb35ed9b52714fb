"""The core's folders are layers: a file includes only from its own folder and from the layers below it.

    util  <-  geometry  <-  optics, snow  <-  transport, grains, spray, structure  <-  io

Folders on the same layer are siblings and do not include each other (optics and snow are independent; grains
and the future spray build on snow and optics as transport does). The Python bindings (cpp/python/) sit above
every layer. docs/architecture.md draws the same picture.
"""

import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
CORE = ROOT / "cpp" / "firn"
GENERATED = {"firn/util/version.h"} | {f"firn/optics/data/{csv.stem}.h" for csv in (ROOT / "cpp" / "data").glob("*.csv")}

LAYERS = (("util",), ("geometry",), ("optics", "snow"), ("transport", "grains", "spray", "structure"), ("io",))
RANK = {folder: rank for rank, folders in enumerate(LAYERS) for folder in folders}
INCLUDE = re.compile(r'^\s*#\s*include\s+"(firn/[^"]+)"', re.M)


def core_files():
    return sorted(p for p in CORE.rglob("*") if p.is_file())


def violation(from_folder, included):
    """Why `from_folder` may not include `included` ("firn/<folder>/<file>"), or None if it may."""
    parts = included.split("/")
    if len(parts) < 3:
        return f"{included} does not name a concept folder (firn/<folder>/<file>)"
    to_folder = parts[1]
    if to_folder not in RANK:
        return f"{included}: folder '{to_folder}' is not a layer of the core"
    if to_folder != from_folder and RANK[to_folder] >= RANK[from_folder]:
        return f"{from_folder}/ may not include {included} ({to_folder}/ is not below {from_folder}/)"
    return None


def test_every_core_file_is_in_a_layer_folder():
    for path in core_files():
        rel = path.relative_to(CORE)
        assert len(rel.parts) == 2 and rel.parts[0] in RANK, f"cpp/firn/{rel} is outside the layer folders"


def test_includes_point_down_the_layers():
    problems = []
    for path in core_files():
        folder = path.relative_to(CORE).parts[0]
        for included in INCLUDE.findall(path.read_text()):
            why = violation(folder, included)
            if why is None and included not in GENERATED and not (ROOT / "cpp" / included).is_file():
                why = f"{included} does not exist"
            if why:
                problems.append(f"cpp/firn/{path.relative_to(CORE)}: {why}")
    assert not problems, "\n".join(problems)


def test_bindings_mirror_the_folders():
    """cpp/python/bind_<folder>.cpp exists only for core folders."""
    for path in (ROOT / "cpp" / "python").glob("bind_*.cpp"):
        assert path.stem[len("bind_"):] in RANK, f"{path.name} names no core folder"


@pytest.mark.parametrize("from_folder, included, allowed", [
    ("transport", "firn/util/error.h", True),
    ("transport", "firn/transport/medium.h", True),
    ("snow", "firn/optics/kz04.h", False),          # siblings
    ("optics", "firn/snow/snow_layer.h", False),    # siblings
    ("geometry", "firn/transport/scene.h", False),  # upward
    ("transport", "firn/io/vdb_io.h", False),       # upward
    ("util", "firn/error.h", False),                # no folder
    ("snow", "firn/lod/band.h", False),             # unknown folder
])
def test_the_rule_itself(from_folder, included, allowed):
    assert (violation(from_folder, included) is None) == allowed
