"""Fuzzing the scene loaders: a mutated scene file loads, or fails with the loader's own error.

Hypothesis mutates valid scene files (deleting, duplicating and swapping elements and
attributes, corrupting numbers, names, types and references) and asserts that loading either
succeeds or raises `SceneError` (a `ValueError`) or `FileNotFoundError` (a mesh the mutated
file names does not exist) with the file named, never another exception. CI runs a bounded
number of examples; `RADIOMETRIA_FUZZ_EXAMPLES=5000 pytest -m fuzz` runs a longer search.
"""

import json
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from hypothesis import given, strategies as st

import radiometria.render as rr
from radiometria.render import SceneError, load_scene

from ..helpers import fuzz_settings
from .test_loaders import SCENE, TET

FUZZ = fuzz_settings(60)
pytestmark = pytest.mark.fuzz

# Values that stress the parsers: numbers out of range, non-numbers, references, names.
CORRUPT = st.one_of(
    st.sampled_from(
        [
            "",
            "-1",
            "0",
            "nan",
            "inf",
            "-inf",
            "1e999",
            "1, 2",
            "1 2 3 4 5",
            "#zz00zz",
            "$spp",
            "$missing",
            "gray",
            "nosuch",
            "diffuse",
            "path",
            "obj",
            "../../etc/passwd",
            "tet.obj",
            "true",
            "maybe",
            "0x10",
            "1:2",
            "400:0.5, 300:0.1",
            "-90",
            "1e-300",
        ]
    ),  # fmt: skip
    # XML 1.0 cannot hold control characters at all: the garbled-bytes test covers those.
    st.text(st.characters(blacklist_categories=("Cs", "Cc")), max_size=12),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)
KNOWN_TAGS = ["float", "integer", "rgb", "spectrum", "string", "boolean", "point", "vector",
              "transform", "bsdf", "shape", "emitter", "sensor", "film", "rfilter", "ref",
              "sampler", "integrator", "lookat", "matrix", "scale", "rotate", "translate",
              "default", "medium", "texture", "include"]  # fmt: skip
MUTATION = st.tuples(
    st.sampled_from(["delete", "duplicate", "swap", "drop_attr", "set_attr", "retag"]),
    st.integers(min_value=0, max_value=10_000),
    st.integers(min_value=0, max_value=10_000),
    CORRUPT,
    st.sampled_from(KNOWN_TAGS),
)


def _mutate(root: ET.Element, mutations) -> None:
    for kind, i, j, value, tag in mutations:
        nodes = list(root.iter())
        parents = {c: p for p in nodes for c in p}
        node = nodes[i % len(nodes)]
        parent = parents.get(node)
        if kind == "delete" and parent is not None:
            parent.remove(node)
        elif kind == "duplicate" and parent is not None:
            parent.insert(list(parent).index(node), ET.fromstring(ET.tostring(node)))
        elif kind == "swap" and parent is not None and len(parent) > 1:
            siblings = list(parent)
            a, b = siblings.index(node), j % len(siblings)
            siblings[a], siblings[b] = siblings[b], siblings[a]
            for child in list(parent):
                parent.remove(child)
            parent.extend(siblings)
        elif kind == "drop_attr" and node.attrib:
            node.attrib.pop(sorted(node.attrib)[j % len(node.attrib)])
        elif kind == "set_attr":
            keys = sorted(node.attrib) or ["value"]
            node.set(keys[j % len(keys)], value)
        elif kind == "retag" and parent is not None:
            node.tag = tag


def _load_or_own_error(path: Path) -> None:
    try:
        load_scene(path)
    except SceneError as e:
        assert path.name in str(e), f"the error does not name the file: {e}"
    except FileNotFoundError as e:
        assert "not found" in str(e), e


@FUZZ
@given(mutations=st.lists(MUTATION, min_size=1, max_size=4))
def test_mutated_mitsuba_xml_loads_or_raises_scene_error(mutations):
    root = ET.fromstring(SCENE)
    _mutate(root, mutations)
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "tet.obj").write_text(TET)
        path = Path(tmp) / "scene.xml"
        path.write_text(ET.tostring(root, encoding="unicode"))
        _load_or_own_error(path)


@FUZZ
@given(data=st.binary(max_size=300), keep=st.integers(min_value=0, max_value=len(SCENE)))
def test_truncated_or_garbled_xml_raises_scene_error(data, keep):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scene.xml"
        path.write_bytes(SCENE.encode()[:keep] + data)
        _load_or_own_error(path)


def _json_paths(value, prefix=()):
    """Every (path, leaf) of a JSON document."""
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _json_paths(v, (*prefix, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _json_paths(v, (*prefix, i))
    yield prefix, value


JSON_VALUES = st.one_of(
    st.none(), st.booleans(), st.integers(), st.floats(allow_nan=False), st.text(max_size=8),
    st.lists(st.floats(allow_nan=False, allow_infinity=False), max_size=4),
    st.dictionaries(st.text(max_size=4), st.integers(), max_size=2),
)  # fmt: skip


@FUZZ
@given(
    edits=st.lists(
        st.tuples(st.integers(min_value=0), st.sampled_from(["delete", "set"]), JSON_VALUES),
        min_size=1,
        max_size=4,
    )
)
def test_mutated_json_scene_loads_or_raises_scene_error(edits):
    data = json.loads((Path(rr.__file__).parent / "data" / "cornell_box.json").read_text())
    for index, kind, value in edits:
        paths = [p for p, _ in _json_paths(data) if p]
        path = paths[index % len(paths)]
        parent = data
        for key in path[:-1]:
            parent = parent[key]
        if kind == "delete":
            del parent[path[-1]]
        else:
            parent[path[-1]] = value
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "box.json"
        path.write_text(json.dumps(data))
        _load_or_own_error(path)
