"""Triangle mesh files (OBJ, PLY, STL, OFF, glTF) read through trimesh (thesis ch. 8)."""

from pathlib import Path

import numpy as np

from .._geometry._mesh import TriangleMesh
from ._description import SceneError

__all__ = ["load_mesh", "read_mesh"]


def read_mesh(path: Path, where: str) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    if not path.is_file():
        raise FileNotFoundError(f"{where}mesh file not found: {path}")
    try:
        mesh = trimesh.load(str(path), force="mesh", process=False)
    except Exception as e:  # trimesh raises many types for a bad file
        raise SceneError(
            f"{where}{path}: cannot read the mesh ({type(e).__name__}: {e})."
        ) from None
    v = np.asarray(getattr(mesh, "vertices", np.zeros((0, 3))), dtype=np.float64)
    f = np.asarray(getattr(mesh, "faces", np.zeros((0, 3))), dtype=np.int64)
    if f.size == 0:
        raise SceneError(f"{where}{path}: the file holds no triangles.")
    return v.reshape(-1, 3), f.reshape(-1, 3)


def load_mesh(path) -> TriangleMesh:
    """Read a triangle mesh from an OBJ, PLY, STL, OFF or glTF file (through trimesh).

    Polygons are triangulated by trimesh; vertices are kept as in the file (no merging or
    reordering), so face indices match the file's.

    **Arguments:**

    - `path`: the mesh file. Vertex coordinates are in the file's length unit.

    **Returns:**

    A `TriangleMesh` (without materials). [file length unit]

    **Raises:**

    `FileNotFoundError` for a missing file, `SceneError` (a `ValueError`) naming the file when
    it cannot be read or holds no triangles.

    !!! note "Thesis"
        Ch. 8 (scene geometry); file reading by trimesh (`Dawson-Haggerty2019`).
    """
    v, f = read_mesh(Path(path), "")
    return TriangleMesh(v, f.astype(np.int32))
