"""Mitsuba's `serialized` mesh files (issue 12): read as Mitsuba 3 reads them, and hostile
files refused with the file named, before any large allocation."""

import zlib

import numpy as np
import pytest

from radiometria.render._scenes._description import SceneError
from radiometria.render._scenes._serialized import read_serialized

from ._mitsuba import mitsuba
from .test_shapes import write_serialized

TRI = (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float),
       np.array([[0, 1, 2], [0, 3, 1]]), None, None)  # fmt: skip
NORMALS = np.array([[0, 0, 1], [0, 0.6, 0.8], [0.6, 0, 0.8], [1, 0, 0]], float)
UVS = np.array([[0, 0], [1, 0], [0, 1], [0.5, 0.5]], float)


@pytest.mark.parametrize("version", [3, 4])
@pytest.mark.parametrize("index", [0, 1])
def test_serialized_matches_mitsubas_reader(tmp_path, version, index):
    """Positions, faces, normals and uvs of each mesh of a two-mesh file (versions 3 and 4)
    equal what Mitsuba 3 loads from it."""
    mi = mitsuba()
    path = tmp_path / "m.serialized"
    write_serialized(path, [TRI, (TRI[0] * 2, TRI[1], NORMALS, UVS)], version=version)
    mesh, _ = read_serialized(path, "", index)
    ref = mi.load_dict({"type": "serialized", "filename": str(path), "shape_index": index})
    np.testing.assert_allclose(
        mesh.vertices, np.array(ref.vertex_positions_buffer()).reshape(-1, 3)
    )
    np.testing.assert_array_equal(mesh.faces, np.array(ref.faces_buffer()).reshape(-1, 3))
    if index == 1:
        np.testing.assert_allclose(
            mesh.normals, np.array(ref.vertex_normals_buffer()).reshape(-1, 3), atol=1e-6
        )
        np.testing.assert_allclose(mesh.uvs, np.array(ref.vertex_texcoords_buffer()).reshape(-1, 2))
    else:
        assert mesh.normals is None and mesh.uvs is None


def _body(nv: int, nf: int, flags: int = 0x1000) -> bytes:
    return np.uint32(flags).tobytes() + b"m\x00" + np.array([nv, nf], "<u8").tobytes()


def _file(stream: bytes, *, tag=0x041C, version=4, compress=True) -> bytes:
    head = np.array([tag, version], "<u2").tobytes()
    return head + (zlib.compress(stream) if compress else stream)


GOOD = _body(3, 1) + np.zeros(9, "<f4").tobytes() + np.array([0, 1, 2], "<u4").tobytes()
HOSTILE = [
    ("empty", b"", r"not a Mitsuba serialized file"),
    ("tag", _file(GOOD, tag=0x1234), r"format tag 0x1234"),
    ("version", _file(GOOD, version=9), r"version 9"),
    ("garbage", _file(b"\x00" * 64, compress=False), r"corrupt zlib stream"),
    ("truncated", _file(GOOD)[:-6], r"ends inside|corrupt zlib"),
    ("absurd counts", _file(_body(10**12, 10**12)), r"10\^12|1,000,000,000,000 vertices"),
    ("zero", _file(_body(0, 1)), r"0 vertices"),
    ("index", _file(_body(3, 1) + np.zeros(9, "<f4").tobytes()
                    + np.array([0, 1, 7], "<u4").tobytes()), r"indexes a vertex outside"),
    ("nan", _file(_body(3, 1) + np.full(9, np.nan, "<f4").tobytes()
                  + np.array([0, 1, 2], "<u4").tobytes()), r"non-finite position"),
    ("short name", _file(np.uint32(0x1000).tobytes() + b"abc"), r"mesh name"),
]  # fmt: skip


@pytest.mark.parametrize("name,data,message", HOSTILE, ids=[h[0] for h in HOSTILE])
def test_hostile_serialized_files_name_the_file(tmp_path, name, data, message):
    path = tmp_path / "bad.serialized"
    path.write_bytes(data)
    with pytest.raises(SceneError, match=message) as info:
        read_serialized(path, "scene.xml:3: ")
    assert str(info.value).startswith(f"scene.xml:3: {path}: "), info.value


def test_shape_index_out_of_range_and_bad_dictionary(tmp_path):
    path = tmp_path / "m.serialized"
    write_serialized(path, [TRI])
    with pytest.raises(SceneError, match=r"'shape_index' 3 is out of range.*0 to 0"):
        read_serialized(path, "", 3)
    data = bytearray(path.read_bytes())
    data[-4:] = np.uint32(10**9).tobytes()  # a count the file cannot hold
    path.write_bytes(bytes(data))
    with pytest.raises(SceneError, match=r"dictionary is corrupt"):
        read_serialized(path, "", 1)
    with pytest.raises(FileNotFoundError, match="nope.serialized"):
        read_serialized(tmp_path / "nope.serialized", "", 0)
