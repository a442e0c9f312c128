"""Triangle mesh files (OBJ, PLY, STL, OFF, glTF) read through trimesh (thesis ch. 8).

trimesh parses the files; this module guards it against hostile input. Before trimesh sees a
PLY file its header is parsed here, and a header whose element counts cannot fit in the file's
size (a truncated file, or one that claims 10^12 vertices) is refused before anything is
allocated. OBJ face indices of 0 (OBJ counts from 1, and NumPy would wrap 0 - 1 to the last
vertex) are refused. After reading, every vertex must be finite and every face index must lie
in range; a failure names the file and, for OBJ, the line. Anything trimesh itself raises
becomes a `SceneError` naming the file.
"""

import math
import re
from pathlib import Path

import numpy as np

from .._geometry._mesh import TriangleMesh
from ._description import SceneError

__all__ = ["load_mesh", "read_mesh"]

MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".gltf", ".glb")
PLY_MAX_HEADER_BYTES = 1 << 20  # a PLY header longer than 1 MiB is not a mesh header
# Byte sizes of the PLY scalar types (both spellings of the PLY 1.0 specification).
_PLY_SIZES = {
    "char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2, "int16": 2,
    "uint16": 2, "int": 4, "uint": 4, "int32": 4, "uint32": 4, "float": 4, "float32": 4,
    "double": 8, "float64": 8,
}  # fmt: skip
_OBJ_ZERO_INDEX = re.compile(rb"^[ \t]*f[ \t][^\n]*?(?<=[ \t])0(?=[/ \t\r\n]|$)", re.M)
_BOMS = (b"\xef\xbb\xbf", b"\xff\xfe", b"\xfe\xff")


def _err(where: str, path: Path, what: str) -> SceneError:
    return SceneError(f"{where}{path}: {what}")


def _check_ply_header(where: str, path: Path, size: int) -> None:
    """Parse a PLY header and refuse element counts that the file's size cannot hold."""
    with open(path, "rb") as fh:
        head = fh.read(min(size, PLY_MAX_HEADER_BYTES))
    if not head.startswith(b"ply"):
        raise _err(where, path, f"not a PLY file (it starts with {head[:8]!r}, expected b'ply').")
    m = re.search(rb"^end_header\r?\n", head, re.M)
    if m is None:
        raise _err(
            where, path, "the PLY header has no 'end_header' line "
            f"{'in its first 1 MiB' if size > PLY_MAX_HEADER_BYTES else '(truncated file?)'}."
        )  # fmt: skip
    try:
        lines = head[: m.start()].decode("ascii").splitlines()
    except UnicodeDecodeError as e:
        raise _err(
            where, path, f"the PLY header has a non-ASCII byte at offset {e.start}."
        ) from None
    body = size - m.end()
    fmt = None
    elements: list[list] = []  # [name, count, line, fixed bytes per row, minimum ascii bytes]
    for n, line in enumerate(lines, start=1):
        tok = line.split()
        if not tok or tok[0] in ("ply", "comment", "obj_info"):
            continue
        bad = f"header line {n} {line.strip()[:80]!r}"
        if tok[0] == "format":
            if len(tok) != 3 or tok[1] not in (
                "ascii",
                "binary_little_endian",
                "binary_big_endian",
            ):
                raise _err(where, path, f"{bad}: expected 'format ascii|binary_little_endian|"
                      "binary_big_endian 1.0'.")  # fmt: skip
            fmt = tok[1]
        elif tok[0] == "element":
            if len(tok) != 3 or not tok[2].isdigit():
                raise _err(
                    where, path, f"{bad}: expected 'element <name> <count>' with a count >= 0."
                )
            elements.append([tok[1], int(tok[2]), n, 0, 0])
        elif tok[0] == "property":
            if not elements:
                raise _err(where, path, f"{bad}: a property before any element.")
            if len(tok) == 5 and tok[1] == "list":
                if tok[2] not in _PLY_SIZES or tok[3] not in _PLY_SIZES:
                    raise _err(
                        where, path, f"{bad}: unknown list types (valid: {sorted(_PLY_SIZES)})."
                    )
                size_bytes = _PLY_SIZES[tok[2]]  # an empty list still stores its count
            elif len(tok) == 3 and tok[1] in _PLY_SIZES:
                size_bytes = _PLY_SIZES[tok[1]]
            else:
                raise _err(
                    where, path, f"{bad}: expected 'property <type> <name>' or 'property "
                    f"list <count type> <index type> <name>' (types: {sorted(_PLY_SIZES)})."
                )  # fmt: skip
            elements[-1][3] += size_bytes
            elements[-1][4] += 2  # ascii: at least one digit and one separator per value
        else:
            raise _err(where, path, f"{bad}: unknown header keyword {tok[0]!r}.")
    if fmt is None:
        raise _err(where, path, "the PLY header has no 'format' line.")
    need = 0
    for e, (name, count, line, fixed, ascii_min) in enumerate(elements):
        before = " with the elements before them" if e else ""
        row = fixed if fmt != "ascii" else ascii_min
        need += count * row
        if need > body + 1:  # +1: the last ascii row may lack its newline
            raise _err(
                where, path, f"header line {line} declares {count:,} '{name}' elements, which "
                f"need at least {need:,} bytes{before}, but the file has {body:,} bytes after "
                "its header (truncated file, or an absurd count)."
            )  # fmt: skip


def _obj_problem(data: bytes, n_vertices: int | None) -> str | None:
    """Locate the first bad line of an OBJ file: a vertex with a non-finite or unreadable
    coordinate, or a face index that is 0 or outside the vertices. Used on the error path."""
    count = 0
    text = data.decode("utf-8", errors="replace")
    for n, line in enumerate(text.splitlines(), start=1):
        tok = line.split()
        if not tok:
            continue
        if tok[0] == "v":
            count += 1
            try:
                xyz = [float(t) for t in tok[1:4]]
            except ValueError:
                return f"line {n}: vertex {count} has an unreadable coordinate in {line[:80]!r}."
            if len(xyz) < 3:
                return f"line {n}: vertex {count} has {len(xyz)} coordinates, expected 3."
            if not all(map(math.isfinite, xyz)):
                return f"line {n}: vertex {count} has a non-finite coordinate {xyz}."
        elif tok[0] == "f":
            total = count if n_vertices is None else max(count, n_vertices)
            for t in tok[1:]:
                head = t.split("/")[0]
                try:
                    i = int(head)
                except ValueError:
                    return f"line {n}: face index {head!r} is not an integer."
                j = i if i > 0 else count + 1 + i  # negative indices count back from here
                if i == 0 or not 1 <= j <= total:
                    return (
                        f"line {n}: face index {i} is outside the vertices "
                        f"(valid: 1 to {total}, or -1 to -{count} counting back; OBJ "
                        "indices start at 1)."
                    )
    return None


def _attribute(a, n: int, cols: int) -> np.ndarray | None:
    """A per-vertex attribute array of the loaders, or `None` when absent or misshapen."""
    if a is None:
        return None
    a = np.asarray(a, dtype=np.float64)
    return a.reshape(n, cols) if a.size == n * cols else None


# PLY properties that are a mesh's geometry, not one of its attributes.
_PLY_GEOMETRY = frozenset(
    {"x", "y", "z", "nx", "ny", "nz", "u", "v", "s", "t", "texture_u", "texture_v",
     "vertex_indices", "vertex_index", "texcoord"}
)  # fmt: skip
# Suffix families of a multi-channel attribute's properties, in channel order.
_PLY_SUFFIXES = (("r", "g", "b", "a"), ("x", "y", "z", "w"), ("u", "v"))


def _ply_attributes(raw, n_vertices: int, n_faces: int) -> dict[str, np.ndarray]:
    """Mitsuba's mesh attributes of a PLY file's elements (trimesh's `_ply_raw`):
    `vertex_<name>` `(v, d)` and `face_<name>` `(f, d)` float64.

    As Mitsuba's PLY reader: the properties `r g b` (or `red green blue`) are the attribute
    `color`; properties `<name>_0`, `<name>_1`, ... (or `_r _g _b`, `_x _y _z`, `_u _v`) are
    the channels of `<name>`; other properties are not attributes. Integer `color` channels
    (8-bit vertex colours of scanners and MeshLab) are divided by their type's maximum, so
    that colours lie in [0, 1] (Mitsuba reads them unscaled and warns). An element whose row
    count differs from the mesh's (polygons split into triangles, vertices split at uv seams)
    gives no attributes."""
    out: dict[str, np.ndarray] = {}
    for element, n in (("vertex", n_vertices), ("face", n_faces)):
        el = (raw or {}).get(element)
        if not el or el.get("data") is None:
            continue
        data = el["data"]
        names = list(data.dtype.names if isinstance(data, np.ndarray) else data.keys())
        groups: dict[str, list[tuple[str, str]]] = {}
        for name in names:
            if name in _PLY_GEOMETRY:
                continue
            if name in ("r", "g", "b", "red", "green", "blue"):
                groups.setdefault("color", []).append((name[0], name))
                continue
            prefix, sep, suffix = name.rpartition("_")
            if sep and prefix and (suffix.isdigit() or any(suffix in f for f in _PLY_SUFFIXES)):
                groups.setdefault(prefix, []).append((suffix, name))
        for prefix, channels in groups.items():
            order = next((f for f in _PLY_SUFFIXES if all(c in f for c, _ in channels)), None)
            rank = [order.index(c) if order else int(c, 36) for c, _ in channels]
            columns = []
            for _, (_, name) in sorted(zip(rank, channels, strict=True)):
                col = np.asarray(data[name])
                scale = 1.0
                if prefix == "color" and np.issubdtype(col.dtype, np.integer):
                    scale = float(np.iinfo(col.dtype).max)
                columns.append(col.astype(np.float64).reshape(-1) / scale)
            a = np.stack(columns, axis=1)
            if len(a) == n:
                out[f"{element}_{prefix}"] = a
    return out


def _load(path: Path, suffix: str):
    """Vertices, faces, vertex normals and uvs (`None` when the file has none) and mesh
    attributes (`_ply_attributes`; PLY only) of a mesh file. OBJ and PLY go through
    trimesh's format readers directly: `trimesh.Trimesh` drops file normals that disagree
    with its face normals, which Mitsuba keeps."""
    import trimesh
    from trimesh.exchange.obj import load_obj
    from trimesh.exchange.ply import load_ply

    if suffix not in (".obj", ".ply"):
        mesh = trimesh.load(str(path), force="mesh", process=False)
        v = np.asarray(getattr(mesh, "vertices", np.zeros((0, 3))), dtype=np.float64)
        f = np.asarray(getattr(mesh, "faces", np.zeros((0, 3))), dtype=np.int64)
        return v.reshape(-1, 3), f.reshape(-1, 3), None, None, {}
    with open(path, "rb") as fh:
        if suffix == ".ply":
            parts = [load_ply(fh)]
        else:
            parts = list(load_obj(fh, skip_materials=True).get("geometry", {}).values())
    vs, fs, ns, uvs, offset = [], [], [], [], 0
    for g in parts:
        v = np.asarray(g.get("vertices", np.zeros((0, 3))), dtype=np.float64).reshape(-1, 3)
        f = np.asarray(g.get("faces", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
        vs.append(v)
        fs.append(f + offset)
        ns.append(_attribute(g.get("vertex_normals"), len(v), 3))
        uvs.append(_attribute(getattr(g.get("visual"), "uv", None), len(v), 2))
        offset += len(v)
    if not vs:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64), None, None, {}
    n = np.concatenate(ns) if all(x is not None for x in ns) else None
    uv = np.concatenate(uvs) if all(x is not None for x in uvs) else None
    v, f = np.concatenate(vs), np.concatenate(fs)
    attrs = {}
    if suffix == ".ply":
        attrs = _ply_attributes(parts[0].get("metadata", {}).get("_ply_raw"), len(v), len(f))
    return v, f, n, uv, attrs


def read_mesh(path: Path, where: str, *, attributes: bool = False):
    """Vertices `(v, 3)` float64 and faces `(f, 3)` int64 of a mesh file, checked; with
    `attributes`, also the file's vertex normals `(v, 3)` and uvs `(v, 2)` (`None` when the
    file has none; OBJ and PLY only) and its mesh attributes, a dict of `vertex_<name>`
    `(v, d)` and `face_<name>` `(f, d)` arrays (PLY only, Mitsuba's naming:
    `_ply_attributes`; non-finite values are refused).

    `where` prefixes every message (the scene file and line that names the mesh).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{where}mesh file not found: {path}")
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise _err(where, path, f"unsupported mesh file type {suffix or '(none)'!r} "
              f"(supported: {', '.join(MESH_SUFFIXES)}).")  # fmt: skip
    size = path.stat().st_size
    if size == 0:
        raise _err(where, path, "the file is empty.")
    data = None
    if suffix == ".ply":
        _check_ply_header(where, path, size)
    elif suffix == ".obj":
        data = path.read_bytes()
        nul = data.find(b"\x00")
        if nul >= 0 and not data.startswith(_BOMS):
            raise _err(
                where, path, f"binary data (a NUL byte at offset {nul}); an OBJ file is text."
            )
        if _OBJ_ZERO_INDEX.search(data):
            raise _err(where, path, _obj_problem(data, None) or "a face index is 0.")
    try:
        v, f, normals, uvs, attrs = _load(path, suffix)
    except Exception as e:  # trimesh raises many types for a bad file
        detail = _obj_problem(data, None) if data is not None else None
        raise _err(
            where, path, detail or f"cannot read the mesh ({type(e).__name__}: {e})."
        ) from None
    if f.size == 0:
        detail = _obj_problem(data, None) if data is not None else None
        raise _err(where, path, detail or "the file holds no triangles.")
    finite = np.isfinite(v).all(axis=1)
    in_range = ((f >= 0) & (f < len(v))).all(axis=1)
    for name, a in attrs.items():
        if not np.isfinite(a).all():
            k = int(np.argmin(np.isfinite(a).all(axis=1)))
            raise _err(where, path, f"attribute {name!r} has a non-finite value in row {k} "
                       f"(0-based): {a[k].tolist()}.")  # fmt: skip
    if finite.all() and in_range.all():
        return (v, f, normals, uvs, attrs) if attributes else (v, f)
    detail = _obj_problem(data, len(v)) if data is not None else None
    if detail is None and not finite.all():
        k = int(np.argmin(finite))
        detail = f"vertex {k} (0-based, in file order) has a non-finite coordinate {v[k].tolist()}."
    elif detail is None:
        k = int(np.argmin(in_range))
        detail = f"triangle {k} (0-based) {f[k].tolist()} indexes a vertex outside [0, {len(v)})."
    raise _err(where, path, detail)


def load_mesh(path) -> TriangleMesh:
    """Read a triangle mesh from an OBJ, PLY, STL, OFF or glTF file (through trimesh).

    Polygons are triangulated by trimesh; vertices are kept as in the file (no merging or
    reordering), so face indices match the file's. Degenerate (zero-area) triangles are kept;
    the scene loaders drop them (or refuse them on an emitter).

    **Arguments:**

    - `path`: the mesh file. Vertex coordinates are in the file's length unit.

    **Returns:**

    A `TriangleMesh` (without materials). [file length unit]

    **Raises:**

    `FileNotFoundError` for a missing file; `SceneError` (a `ValueError`) naming the file (and
    for OBJ the line) when it has an unsupported suffix, is empty, binary garbage, truncated, a
    PLY header whose element counts exceed the file's size (checked before reading the body),
    non-finite vertex coordinates, a face index outside the vertices, or no triangles.

    !!! note "Thesis"
        Ch. 8 (scene geometry); file reading by trimesh (`Dawson-Haggerty2019`).
    """
    v, f = read_mesh(Path(path), "")
    return TriangleMesh(v, f.astype(np.int32))
