"""Triangle meshes as pytrees, and the per-triangle geometry helpers (thesis ch. 8).

A mesh is a pair of arrays, vertex positions `(v, 3)` and vertex-index triples `(f, 3)`,
optionally with a material index per face. Everything here is array code: the helpers work on
NumPy or JAX arrays, under `jit` and `vmap`, and (where a value is differentiable) under `grad`.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float, Int

__all__ = [
    "TriangleMesh",
    "icosphere",
    "merge_meshes",
    "sample_triangle_point",
    "triangle_areas",
    "triangle_normals",
    "validate_triangles",
]


class TriangleMesh(eqx.Module):
    """An indexed triangle mesh: vertex positions, faces and an optional material per face.

    **Fields:**

    - `vertices`: vertex positions, shape `(v, 3)`, floating point. [scene length unit]
    - `faces`: vertex indices of each triangle, shape `(f, 3)`, int32. The winding
        `(v0, v1, v2)` gives the geometric normal `(v1 - v0) x (v2 - v0)` (right-hand rule).
    - `material`: optional material index per face, shape `(f,)`, int32, or `None`.

    Construction converts NumPy input to JAX arrays; `faces` and `material` become int32.
    The shapes are checked (static tier, `ValueError`); index ranges are checked by
    `validate_triangles`, which the loaders call.

    !!! note "Thesis"
        Ch. 8 (light transport: surfaces are triangle meshes); the layout follows pbrt's
        `TriangleMesh` (`Pharr2023` §6.5).
    """

    vertices: Float[Array, "v 3"]
    faces: Int[Array, "f 3"]
    material: Int[Array, " f"] | None = None

    def __init__(self, vertices: ArrayLike, faces: ArrayLike, material: ArrayLike | None = None):
        vertices = jnp.asarray(vertices)
        if not jnp.issubdtype(vertices.dtype, jnp.floating):
            raise TypeError(f"`vertices` must be floating point, got dtype {vertices.dtype}.")
        if vertices.ndim != 2 or vertices.shape[1] != 3:
            raise ValueError(f"`vertices` must have shape (v, 3), got {vertices.shape}.")
        faces_np = np.asarray(faces)
        if faces_np.dtype.kind not in "iu":
            raise TypeError(f"`faces` must be integer vertex indices, got dtype {faces_np.dtype}.")
        if faces_np.ndim != 2 or faces_np.shape[1] != 3:
            raise ValueError(f"`faces` must have shape (f, 3), got {faces_np.shape}.")
        self.vertices = vertices
        self.faces = jnp.asarray(faces_np, dtype=jnp.int32)
        if material is None:
            self.material = None
        else:
            mat = np.asarray(material)
            if mat.dtype.kind not in "iu" or mat.shape != (faces_np.shape[0],):
                raise ValueError(
                    f"`material` must be an integer array of shape ({faces_np.shape[0]},), got "
                    f"dtype {mat.dtype} and shape {mat.shape}."
                )
            self.material = jnp.asarray(mat, dtype=jnp.int32)

    @property
    def n_triangles(self) -> int:
        """The number of triangles `f`."""
        return int(self.faces.shape[0])


def _corners(xp, vertices, faces):
    v = xp.asarray(vertices)
    f = xp.asarray(faces)
    return v[f[..., 0]], v[f[..., 1]], v[f[..., 2]]


def _areas(xp, vertices, faces):
    v0, v1, v2 = _corners(xp, vertices, faces)
    n = xp.cross(v1 - v0, v2 - v0)
    n2 = xp.sum(n * n, axis=-1)
    ok = n2 > 0
    return xp.where(ok, 0.5 * xp.sqrt(xp.where(ok, n2, 1.0)), 0.0)


def triangle_normals(vertices: ArrayLike, faces: ArrayLike) -> Float[Array, "*f 3"]:
    """Unit geometric normals `normalize((v1 - v0) x (v2 - v0))` of the triangles.

    **Arguments:**

    - `vertices`: vertex positions `(v, 3)`. [scene length unit]
    - `faces`: vertex indices `(..., 3)`, integer.

    **Returns:**

    Unit normals `(..., 3)` [dimensionless], on the side from which the vertices appear
    counter-clockwise. A degenerate (zero-area) triangle gives the zero vector, with a finite
    gradient (the norm is guarded).

    !!! note "Thesis"
        Ch. 8; `Pharr2023` §6.5.1 (triangle geometric normal).
    """
    v0, v1, v2 = _corners(jnp, vertices, faces)
    n = jnp.cross(v1 - v0, v2 - v0)
    n2 = jnp.sum(n * n, axis=-1, keepdims=True)
    ok = n2 > 0
    inv = 1.0 / jnp.sqrt(jnp.where(ok, n2, 1.0))
    return jnp.where(ok, n * inv, 0.0)


def triangle_areas(vertices: ArrayLike, faces: ArrayLike) -> Float[Array, "*f"]:
    """Areas `|(v1 - v0) x (v2 - v0)| / 2` of the triangles.

    **Arguments:**

    - `vertices`: vertex positions `(v, 3)`. [scene length unit]
    - `faces`: vertex indices `(..., 3)`, integer.

    **Returns:**

    Areas `(...,)` [scene length unit^2]; exactly 0 for a degenerate triangle, with a finite
    gradient.

    !!! note "Thesis"
        Ch. 8 (area light sampling needs the triangle area); `Pharr2023` §6.5.1.
    """
    return _areas(jnp, vertices, faces)


def sample_triangle_point(
    vertices: ArrayLike, faces: ArrayLike, prim: ArrayLike, u: ArrayLike
) -> tuple[Float[Array, "*n 3"], Float[Array, "*n 3"], Float[Array, "*n 2"]]:
    r"""Sample points uniformly (by area) on the given triangles.

    Uses the square-root warp $b_2 = 1 - \sqrt{u_0}$, $b_1 = u_1\sqrt{u_0}$, $b_0 = 1 - b_1 - b_2$,
    so the density is $1/A$ with respect to area on the chosen triangle.

    **Arguments:**

    - `vertices`: vertex positions `(v, 3)`. [scene length unit]
    - `faces`: vertex indices `(f, 3)`, integer.
    - `prim`: index of the triangle to sample per point, integer `(...,)`.
    - `u`: uniform variates in [0, 1)^2, shape `(..., 2)`. [dimensionless]

    **Returns:**

    `(points (..., 3), normals (..., 3), barycentrics (..., 2))`: positions [scene length unit],
    unit geometric normals [dimensionless] and the barycentrics `(b1, b2)` of the point, in the
    convention of `Hit` (`p = (1 - b1 - b2) v0 + b1 v1 + b2 v2`).

    !!! note "Thesis"
        Ch. 5 and 8 (uniform sampling of area lights); `Pharr2023` §A.5.5 (the square-root
        warp of `Turk1990`).
    """
    v = jnp.asarray(vertices)
    f = jnp.asarray(faces)[jnp.asarray(prim)]
    u = jnp.asarray(u)
    su0 = jnp.sqrt(u[..., 0])
    b1 = u[..., 1] * su0
    b2 = 1.0 - su0
    # b2 = 1 - sqrt(u0), b1 = u1 sqrt(u0): uniform by area, and b0 = 1 - b1 - b2 >= 0
    b0 = 1.0 - b1 - b2
    v0, v1, v2 = v[f[..., 0]], v[f[..., 1]], v[f[..., 2]]
    p = b0[..., None] * v0 + b1[..., None] * v1 + b2[..., None] * v2
    n = jnp.cross(v1 - v0, v2 - v0)
    n2 = jnp.sum(n * n, axis=-1, keepdims=True)
    ok = n2 > 0
    n = jnp.where(ok, n / jnp.sqrt(jnp.where(ok, n2, 1.0)), 0.0)
    return p, n, jnp.stack([b1, b2], axis=-1)


def validate_triangles(
    vertices: np.ndarray,
    faces: np.ndarray,
    *,
    where: str = "mesh",
    degenerate: str = "drop",
) -> np.ndarray:
    """Check a NumPy mesh and apply the degenerate-triangle rule; returns the kept face mask.

    Offline (NumPy) validation used by every loader:

    - vertex coordinates must be finite; face indices must lie in `[0, v)`;
    - a triangle whose area is exactly 0 in float64 (repeated index, or collinear corners) is
      *degenerate*. With `degenerate="drop"` (the loaders' rule for ordinary surfaces) it is
      removed, because it can never be hit and has no normal; with `degenerate="error"` (the rule
      for emitters: a light with a zero-area triangle cannot be sampled by area) a `ValueError`
      names it.

    **Arguments:**

    - `vertices`: `(v, 3)` positions. [scene length unit]
    - `faces`: `(f, 3)` integer indices.
    - `where`: a description (file, line, shape name) put in every message.
    - `degenerate`: `"drop"` or `"error"`.

    **Returns:**

    A boolean mask `(f,)` of the faces to keep.

    !!! note "Thesis"
        Ch. 8 (scene description); the rule follows pbrt, which skips degenerate triangles
        (`Pharr2023` §6.5).
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise ValueError(f"{where}: vertices must have shape (v, 3), got {vertices.shape}.")
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError(f"{where}: faces must have shape (f, 3), got {faces.shape}.")
    if faces.dtype.kind not in "iu":
        raise ValueError(f"{where}: face indices must be integers, got dtype {faces.dtype}.")
    if not np.all(np.isfinite(vertices)):
        bad = int(np.argwhere(~np.isfinite(vertices))[0, 0])
        raise ValueError(f"{where}: vertex {bad} has a non-finite coordinate {vertices[bad]}.")
    if faces.size and (faces.min() < 0 or faces.max() >= len(vertices)):
        bad = int(np.argwhere((faces < 0) | (faces >= len(vertices)))[0, 0])
        raise ValueError(
            f"{where}: face {bad} {faces[bad].tolist()} indexes a vertex outside "
            f"[0, {len(vertices)})."
        )
    with np.errstate(over="ignore", invalid="ignore"):  # huge coordinates: checked just below
        areas = _areas(np, vertices, faces) if faces.size else np.zeros(0)
    if not np.all(np.isfinite(areas)):
        bad = int(np.argwhere(~np.isfinite(areas))[0, 0])
        raise ValueError(
            f"{where}: triangle {bad} (vertices {faces[bad].tolist()}) is too large for "
            "float64 arithmetic (its area overflows); rescale the scene."
        )
    keep = areas > 0
    if degenerate == "error" and not np.all(keep):
        bad = int(np.argwhere(~keep)[0, 0])
        raise ValueError(
            f"{where}: triangle {bad} (vertices {faces[bad].tolist()}) has zero area; an emitter "
            "must have a positive area on every triangle."
        )
    if degenerate not in ("drop", "error"):
        raise ValueError(f"`degenerate` must be 'drop' or 'error', got {degenerate!r}.")
    return keep


def merge_meshes(
    meshes: list[tuple[np.ndarray, np.ndarray]],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Concatenate NumPy meshes into one vertex and one face array.

    **Arguments:**

    - `meshes`: a list of `(vertices (v_i, 3), faces (f_i, 3))` pairs. [scene length unit]

    **Returns:**

    `(vertices (sum v_i, 3) float64, faces (sum f_i, 3) int32, shape_index (sum f_i,) int32)`,
    with the face indices offset to the merged vertex array and `shape_index[k]` the position in
    `meshes` of the shape that face `k` came from.

    !!! note "Thesis"
        Ch. 8 (a scene is one array of triangles); cf. `Pharr2023` §7.1.
    """
    verts, faces, owner = [], [], []
    offset = 0
    for i, (v, f) in enumerate(meshes):
        v = np.asarray(v, dtype=np.float64).reshape(-1, 3)
        f = np.asarray(f, dtype=np.int64).reshape(-1, 3)
        verts.append(v)
        faces.append(f + offset)
        owner.append(np.full(len(f), i, dtype=np.int32))
        offset += len(v)
    if not verts:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int32), np.zeros(0, np.int32)
    return (
        np.concatenate(verts),
        np.concatenate(faces).astype(np.int32),
        np.concatenate(owner),
    )


def icosphere(subdivisions: int = 3, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """A triangulated unit-radius icosphere (NumPy), outward-facing, `20 * 4**subdivisions` faces.

    Each level splits every triangle into four at its edge midpoints, which are projected back
    onto the sphere; shared edges share their midpoint vertex, so the mesh is closed (watertight)
    and has `10 * 4**subdivisions + 2` vertices. The Mitsuba loader tessellates a `sphere` shape
    with `subdivisions=4` (5120 triangles, largest radial gap below 0.2 % of the radius).

    **Arguments:**

    - `subdivisions`: number of 1-to-4 splits, >= 0.
    - `radius`: sphere radius. [scene length unit]

    **Returns:**

    `(vertices (v, 3) float64, faces (f, 3) int32)`.

    !!! note "Thesis"
        Ch. 8 (test geometry); the construction is the classic subdivided icosahedron
        (`Loop1987`-style 1-to-4 split, without smoothing).
    """
    if isinstance(subdivisions, bool) or not isinstance(subdivisions, int | np.integer):
        raise TypeError(f"`subdivisions` must be an int, got {subdivisions!r}.")
    if subdivisions < 0:
        raise ValueError(f"`subdivisions` must be >= 0, got {subdivisions}.")
    g = (1.0 + 5.0**0.5) / 2.0
    v = np.array(
        [
            [-1, g, 0], [1, g, 0], [-1, -g, 0], [1, -g, 0],
            [0, -1, g], [0, 1, g], [0, -1, -g], [0, 1, -g],
            [g, 0, -1], [g, 0, 1], [-g, 0, -1], [-g, 0, 1],
        ],
        dtype=np.float64,
    )  # fmt: skip
    f = np.array(
        [
            [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
            [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
            [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
            [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
        ],
        dtype=np.int64,
    )  # fmt: skip
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(int(subdivisions)):
        nv = len(v)
        edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        key = np.sort(edges, axis=1)
        uniq, inv = np.unique(key[:, 0] * nv + key[:, 1], return_inverse=True)
        a, b = uniq // nv, uniq % nv
        mid = v[a] + v[b]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m = inv.reshape(3, -1).T + nv  # midpoints of edges (0,1), (1,2), (2,0) of each face
        v = np.concatenate([v, mid])
        f0, f1, f2 = f[:, 0], f[:, 1], f[:, 2]
        m01, m12, m20 = m[:, 0], m[:, 1], m[:, 2]
        f = np.concatenate(
            [
                np.stack([f0, m01, m20], 1),
                np.stack([f1, m12, m01], 1),
                np.stack([f2, m20, m12], 1),
                np.stack([m01, m12, m20], 1),
            ]
        )
    return v * float(radius), f.astype(np.int32)
