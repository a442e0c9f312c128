"""Hostile mesh files: every bad OBJ or PLY gets a `SceneError` naming the file (and for OBJ
the line), never a trimesh or NumPy exception; a fuzz test mutates valid files.

Valid PLY files are written by trimesh's exporter (an independent writer), OBJ by hand.
CI runs a bounded number of fuzz examples; `RADIOMETRIA_FUZZ_EXAMPLES=5000 pytest -m fuzz`
runs a longer search.
"""

import re
import struct
import time

import numpy as np
import pytest
import trimesh
from hypothesis import given, strategies as st

from radiometria.render import SceneError, load_mesh, load_scene

from ..helpers import fuzz_settings, mutate_bytes

TET = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
TET_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
TET_F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
PLY_HEAD = (
    "ply\nformat {fmt} 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\n"
    "property float z\nelement face {nf}\nproperty list uchar int vertex_indices\nend_header\n"
)


def _ply_binary(nv, nf, body: bytes) -> bytes:
    return PLY_HEAD.format(fmt="binary_little_endian", nv=nv, nf=nf).encode() + body


def _tet_ply(encoding: str) -> bytes:
    return trimesh.Trimesh(TET_V, TET_F, process=False).export(file_type="ply", encoding=encoding)


# (file name, content, a regular expression the message must match after the file name)
HOSTILE = [
    ("empty.obj", b"", r"the file is empty"),
    ("garbage.obj", bytes(range(256)) * 4, r"binary data \(a NUL byte at offset 0\)"),
    ("garbage.ply", b"\x00\xff\xfe" * 50, r"not a PLY file"),
    ("truncated.obj", TET[:30].encode(), r"line 4: vertex 4 has 2 coordinates, expected 3"),
    ("letters.obj", TET.replace("v 1 0 0", "v 1x 0 0").encode(), r"line 2: .*unreadable"),
    ("nan.obj", TET.replace("v 1 0 0", "v nan 0 0").encode(), r"line 2: .*non-finite"),
    ("inf.obj", TET.replace("v 0 1 0", "v 0 1e999 0").encode(), r"line 3: .*non-finite"),
    ("index9.obj", (TET + "f 1 2 9\n").encode(), r"line 9: face index 9 is outside"),
    ("index-9.obj", (TET + "f -1 -2 -9\n").encode(), r"line 9: face index -9 is outside"),
    ("index0.obj", (TET + "f 0 1 2\n").encode(), r"line 9: face index 0 is outside.*start at 1"),
    ("points.obj", b"v 0 0 0\nv 1 0 0\n", r"holds no triangles"),
    ("mesh.xyz", b"v 0 0 0\n", r"unsupported mesh file type '.xyz'"),
    (
        "terabyte.ply",
        _ply_binary(10**12, 1, b"\0" * 100),
        r"header line 3 declares 1,000,000,000,000 'vertex' elements.*100 bytes after",
    ),
    (
        "terabyte_ascii.ply",
        PLY_HEAD.format(fmt="ascii", nv=3, nf=10**11).encode() + b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
        r"header line 7 declares 100,000,000,000 'face' elements",
    ),
    ("truncated.ply", _ply_binary(3, 1, b"\0" * 20), r"need at least 36 bytes.*20 bytes after"),
    ("no_end.ply", b"ply\nformat ascii 1.0\nelement vertex 3\n", r"no 'end_header' line"),
    ("bad_type.ply", _ply_binary(3, 1, b"").replace(b"float x", b"quad x"), r"header line 4"),
    (
        "index7.ply",
        _ply_binary(3, 1, b"\0" * 36 + b"\x03" + struct.pack("<3i", 7, 7, 7)),
        r"triangle 0 \(0-based\) \[7, 7, 7\] indexes a vertex outside \[0, 3\)",
    ),
    (
        "nan.ply",
        _ply_binary(3, 1, struct.pack("<9f", 0, 0, 0, np.nan, 0, 0, 0, 1, 0) + b"\3" + b"\0" * 12),
        r"vertex 1 \(0-based, in file order\) has a non-finite coordinate",
    ),
]  # fmt: skip


@pytest.mark.parametrize("name,content,message", HOSTILE, ids=[h[0] for h in HOSTILE])
def test_load_mesh_names_file_and_problem(tmp_path, name, content, message):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(SceneError) as info:
        load_mesh(path)
    text = str(info.value)
    assert text.startswith(f"{path}: "), text
    assert re.search(message, text), text


def test_load_mesh_reads_trimesh_written_ply(tmp_path):
    for encoding in ("ascii", "binary"):
        path = tmp_path / f"tet_{encoding}.ply"
        path.write_bytes(_tet_ply(encoding))
        mesh = load_mesh(path)
        np.testing.assert_array_equal(np.asarray(mesh.vertices), TET_V)
        np.testing.assert_array_equal(np.asarray(mesh.faces), TET_F)


def test_scene_names_scene_line_and_mesh_file(tmp_path):
    (tmp_path / "bad.obj").write_text(TET + "f 1 2 9\n")
    scene = tmp_path / "scene.xml"
    scene.write_text(
        '<scene version="3.0.0">\n'
        '  <shape type="obj">\n    <string name="filename" value="bad.obj"/>\n  </shape>\n'
        "</scene>\n"
    )
    with pytest.raises(SceneError, match=r"scene\.xml:2: .*bad\.obj: line 9: face index 9"):
        load_scene(scene)


def test_degenerate_triangle_on_an_emitter_is_refused(tmp_path):
    (tmp_path / "flat.obj").write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n")
    scene = tmp_path / "scene.xml"
    scene.write_text(
        '<scene version="3.0.0">\n  <shape type="obj" id="lamp">\n'
        '    <string name="filename" value="flat.obj"/>\n'
        '    <emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter>\n'
        "  </shape>\n</scene>\n"
    )
    with pytest.raises(SceneError, match=r"scene\.xml:2: shape 'lamp'.*triangle 0.*zero area"):
        load_scene(scene)


# -- fuzzing ---------------------------------------------------------------------------------

FUZZ = fuzz_settings(40)
TOKENS = [b"0", b"-1", b"9", b"-9", b"nan", b"inf", b"1e999", b"x", b"", b"\xff\xfe", b"\x00",
          b"f", b"v", b"4294967295", b"-2147483648", b"1/2/3", b"\n", b"end_header\n",
          b"element vertex 99999999999\n", b"property list uint int vertex_indices\n",
          b"format ascii 1.0\n", b"binary_big_endian", b"uchar", b"double"]  # fmt: skip
BYTE_MUTATION = st.tuples(
    st.sampled_from(["delete", "duplicate", "insert", "flip", "truncate", "swap_tokens"]),
    st.integers(min_value=0, max_value=10**6),
    st.integers(min_value=0, max_value=64),
    st.one_of(st.sampled_from(TOKENS), st.binary(max_size=8)),
)


SOURCES = {
    "tet.obj": TET.encode(),
    "tet_ascii.ply": _tet_ply("ascii"),
    "tet_binary.ply": _tet_ply("binary"),
}


@pytest.mark.fuzz
@FUZZ
@given(
    source=st.sampled_from(sorted(SOURCES)),
    mutations=st.lists(BYTE_MUTATION, min_size=1, max_size=4),
)
def test_mutated_mesh_loads_or_raises_scene_error(tmp_path_factory, source, mutations):
    path = tmp_path_factory.mktemp("fuzz") / source
    path.write_bytes(mutate_bytes(SOURCES[source], mutations))
    start = time.monotonic()
    try:
        mesh = load_mesh(path)
    except SceneError as e:
        assert str(e).startswith(f"{path}: "), e
    else:
        v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
        assert np.isfinite(v).all() and f.size and f.min() >= 0 and f.max() < len(v)
    assert time.monotonic() - start < 10.0, "loading a small mutated mesh took over 10 s"
