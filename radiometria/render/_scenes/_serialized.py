"""Mitsuba's `serialized` mesh files (thesis ch. 8).

A `.serialized` file (Mitsuba 0.4 and later; `Jakob2022`, plugin `serialized`) holds one or
more meshes. Each starts with an uncompressed little-endian header, the uint16 format tag
0x041C and the uint16 version (3 or 4), followed by one zlib stream that holds: uint32 flags
(0x0001 vertex normals, 0x0002 texture coordinates, 0x0008 vertex colours, 0x0010 face
normals, 0x1000 single precision, 0x2000 double precision), in version 4 the mesh's name as a
NUL-terminated UTF-8 string, the uint64 vertex and triangle counts, the positions, the
normals, the uvs and the colours (each present as the flags say, float32 or float64, vertex
after vertex) and the uint32 triangle indices. The file ends with a dictionary: the offset of
every mesh (uint64 in version 4, uint32 in version 3) and the uint32 number of meshes; it is
read only for a `shape_index` other than 0, as Mitsuba does.

Hostile input: the header, the dictionary and every offset are checked against the file; the
counts are checked against the largest output a zlib stream of that size can inflate to
(zlib's ratio is at most 1032:1) before anything is allocated; the stream is inflated in
bounded pieces, so a truncated or corrupt one is an error naming the file, never a huge
allocation; positions must be finite and indices must lie among the vertices.
"""

import struct
import zlib
from pathlib import Path

import numpy as np

from ._description import SceneError
from ._shapes import ShapeMesh

__all__ = ["read_serialized"]

FORMAT_TAG = 0x041C
_HAS_NORMALS, _HAS_UVS, _HAS_COLORS = 0x0001, 0x0002, 0x0008
_SINGLE, _DOUBLE = 0x1000, 0x2000
_ZLIB_MAX_RATIO = 1032  # deflate cannot expand a byte into more than ~1032 bytes
_MAX_NAME = 1 << 16


def _inflate(z, data: bytes, n: int, err, what: str) -> bytes:
    """Exactly `n` more bytes of the zlib stream, or an error naming `what` was cut short."""
    out, chunk = b"", data
    while len(out) < n:  # bounded pieces; an empty piece means the stream has ended
        piece = z.decompress(chunk, n - len(out))
        chunk = z.unconsumed_tail
        if not piece:
            break
        out += piece
    if len(out) < n:
        raise err(f"the compressed stream ends inside {what} (truncated or corrupt file).")
    return out


def read_serialized(path, where: str = "", shape_index: int = 0) -> tuple[ShapeMesh, str]:
    """The mesh `shape_index` of a Mitsuba `.serialized` file, and its name.

    **Arguments:**

    - `path`: the file. Positions are in the file's length unit.
    - `where`: prefix of every message (the scene file and line that names the mesh).
    - `shape_index`: which mesh of the file (0: the first). [1]

    **Returns:**

    `(ShapeMesh, name)`: positions, faces, the file's vertex normals (`None` when it has
    none) and uvs (`None` when it has none), float64; the name stored in the mesh (version 4)
    or `"file@index"`.

    **Raises:**

    `FileNotFoundError` for a missing file; `SceneError` naming the file for a wrong format
    tag or version, a `shape_index` outside the file's meshes, a bad dictionary or offset, a
    corrupt or truncated zlib stream, counts the stream cannot hold, a non-finite position
    or a triangle index outside the vertices.

    !!! note "Thesis"
        Ch. 8 (scene geometry); Mitsuba's serialized format (`Jakob2022`).
    """
    path = Path(path)

    def err(msg: str) -> SceneError:
        return SceneError(f"{where}{path}: {msg}")

    if not path.is_file():
        raise FileNotFoundError(f"{where}mesh file not found: {path}")
    data = path.read_bytes()
    if len(data) < 4:
        raise err(f"not a Mitsuba serialized file ({len(data)} bytes; expected a 4-byte header).")
    tag, version = struct.unpack_from("<HH", data, 0)
    if tag != FORMAT_TAG:
        raise err(f"not a Mitsuba serialized file (format tag 0x{tag:04X}, expected 0x041C).")
    if version not in (3, 4):
        raise err(f"unsupported serialized format version {version} (valid: 3, 4).")
    if not isinstance(shape_index, int) or shape_index < 0:
        raise err(f"'shape_index' must be an integer >= 0, got {shape_index!r}.")
    start = 4
    end = len(data)
    if shape_index > 0:
        count = struct.unpack_from("<I", data, len(data) - 4)[0]
        size = 8 if version == 4 else 4
        dict_start = len(data) - 4 - size * count
        if count == 0 or dict_start < 4:
            raise err(f"the end-of-file dictionary is corrupt (it claims {count:,} meshes in a "
                      f"file of {len(data):,} bytes).")  # fmt: skip
        if shape_index >= count:
            raise err(f"'shape_index' {shape_index} is out of range: the file holds {count} "
                      f"meshes (valid: 0 to {count - 1}).")  # fmt: skip
        offsets = np.frombuffer(data, "<u8" if size == 8 else "<u4", count, dict_start)
        offset = int(offsets[shape_index])
        if not 0 <= offset <= dict_start - 4:
            raise err(f"mesh {shape_index} starts at offset {offset:,}, outside the file's "
                      f"{dict_start:,} bytes of meshes.")  # fmt: skip
        if struct.unpack_from("<HH", data, offset) != (tag, version):
            raise err(f"mesh {shape_index} at offset {offset:,} has no serialized header.")
        start, end = offset + 4, dict_start
    compressed = data[start:end]
    z = zlib.decompressobj()
    try:
        head = _inflate(z, compressed, 4, err, "the flags")
        flags = struct.unpack("<I", head)[0]
        name = f"{path.name}@{shape_index}"
        if version == 4:
            raw = b""
            while True:  # the name, byte by byte, bounded
                ch = _inflate(z, z.unconsumed_tail, 1, err, "the mesh name")
                if ch == b"\x00":
                    break
                raw += ch
                if len(raw) > _MAX_NAME:
                    raise err(f"the mesh name is longer than {_MAX_NAME} bytes (corrupt file).")
            name = raw.decode("utf-8", errors="replace") or name
        nv, nf = struct.unpack("<QQ", _inflate(z, z.unconsumed_tail, 16, err, "the counts"))
        if flags & _DOUBLE and flags & _SINGLE:
            raise err(f"flags 0x{flags:04X} say both single and double precision.")
        fsize = 8 if flags & _DOUBLE else 4
        per_vertex = 3 + 3 * bool(flags & _HAS_NORMALS) + 2 * bool(flags & _HAS_UVS)
        per_vertex += 3 * bool(flags & _HAS_COLORS)
        need = nv * per_vertex * fsize + nf * 3 * 4
        bound = _ZLIB_MAX_RATIO * len(compressed) + 64
        if nv == 0 or nf == 0 or need > bound or nv >= 1 << 32:
            raise err(
                f"mesh {shape_index} declares {nv:,} vertices and {nf:,} triangles, which need "
                f"{need:,} bytes, but its {len(compressed):,} compressed bytes inflate to at "
                f"most {bound:,} (truncated file, or an absurd count)."
                if nv and nf else f"mesh {shape_index} has {nv} vertices and {nf} triangles."
            )  # fmt: skip
        body = _inflate(z, z.unconsumed_tail, need, err, "the vertex and index arrays")
    except zlib.error as e:
        raise err(f"corrupt zlib stream in mesh {shape_index} ({e}).") from None
    dt = "<f8" if fsize == 8 else "<f4"
    pos = 0

    def take(n: int, dtype: str, cols: int) -> np.ndarray:
        nonlocal pos
        a = np.frombuffer(body, dtype, n * cols, pos).reshape(n, cols)
        pos += a.nbytes
        return a.astype(np.float64 if dtype != "<u4" else np.int64)

    v = take(nv, dt, 3)
    normals = take(nv, dt, 3) if flags & _HAS_NORMALS else None
    uvs = take(nv, dt, 2) if flags & _HAS_UVS else None
    colors = take(nv, dt, 3) if flags & _HAS_COLORS else None
    f = take(nf, "<u4", 3)
    finite = np.isfinite(v).all(axis=1)
    if not finite.all():
        k = int(np.argmin(finite))
        raise err(f"vertex {k} of mesh {shape_index} has a non-finite position {v[k].tolist()}.")
    bad = (f >= nv).any(axis=1)
    if bad.any():
        k = int(np.argmax(bad))
        raise err(f"triangle {k} of mesh {shape_index} {f[k].tolist()} indexes a vertex outside "
                  f"[0, {nv:,}).")  # fmt: skip
    if normals is not None and not np.isfinite(normals).all():
        raise err(f"mesh {shape_index} has a non-finite vertex normal.")
    if colors is not None and not np.isfinite(colors).all():
        raise err(f"mesh {shape_index} has a non-finite vertex colour.")
    attributes = {} if colors is None else {"vertex_color": colors}  # Mitsuba's name
    return ShapeMesh(v, f, normals, uvs, attributes), name
