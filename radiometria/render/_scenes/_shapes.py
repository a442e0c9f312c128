"""Mitsuba 3's analytic shapes as triangle meshes, and the mesh operations of its shapes
(thesis ch. 8).

The scene description holds triangles, so `rectangle`, `disk`, `cube`, `cylinder` and
`sphere` become meshes here (a sphere also keeps its true sphere, which the renderer
intersects instead: `ShapeMesh.sphere`), in Mitsuba 3's object space and with its
parametrisation, so that a texture lookup or a shading normal finds the same values as on
Mitsuba's shape:

- `rectangle`: [-1, 1]^2 at z = 0, normal +z, uv = ((x + 1) / 2, (y + 1) / 2); 2 triangles,
    exact.
- `cube`: [-1, 1]^3, 4 vertices per face (face normals), Mitsuba's vertex order and uvs;
    12 triangles, exact.
- `disk`: the unit disk at z = 0, normal +z, uv = (r, phi / 2 pi); a fan of
    `DISK_SEGMENTS` triangles (area `n sin(2 pi / n) / 2` instead of pi: 0.04 % short).
- `cylinder`: radius `radius` around the segment `p0` -> `p1`, open ends, normals outward,
    uv = (phi / 2 pi, z along the axis); `CYLINDER_SEGMENTS` quads around the axis with
    per-vertex (radial) shading normals.
- `sphere`: a latitude-longitude mesh of `SPHERE_RINGS` x `SPHERE_SEGMENTS` cells with the
    exact normal at every vertex (interpolated across each triangle as a shading normal) and
    uv = (phi / 2 pi, theta / pi) (Mitsuba's). Error bound: every point of the mesh lies
    within `SPHERE_MAX_RADIAL_ERROR` x radius (1.1e-3) inside the true sphere; a sphere that
    covers 30 pixels across on screen is off by less than 0.02 px at its silhouette, below
    what any image comparison at a few hundred samples per pixel can see, while its shading
    normals are exact at the vertices and differ by at most half a cell's angle in between.

Every shape takes Mitsuba's `to_world` (positions by the matrix, normals by its cofactor
matrix, which is what cross products of edges obey, so shading normals and the winding stay on
one side under a mirroring transform) and `flip_normals` (reversed winding, negated normals).
Meshes without vertex normals get Mitsuba's: angle-weighted averages of the face normals
around each vertex (`vertex_normals`), unless `face_normals` is set.
"""

import dataclasses

import numpy as np

__all__ = [
    "CYLINDER_SEGMENTS",
    "DISK_SEGMENTS",
    "SPHERE_MAX_RADIAL_ERROR",
    "SPHERE_RINGS",
    "SPHERE_SEGMENTS",
    "ShapeMesh",
    "cube",
    "cylinder",
    "disk",
    "rectangle",
    "sphere",
    "transform_mesh",
    "vertex_normals",
]

SPHERE_RINGS = 48  # cells in theta (pole to pole)
SPHERE_SEGMENTS = 96  # cells in phi
# Largest 1 - |p| / r over the mesh: at the centre of the widest cell's long diagonal, where
# the chord between opposite corners at angular distance d sags by 1 - cos(d / 2).
SPHERE_MAX_RADIAL_ERROR = 1.1e-3
DISK_SEGMENTS = 128
CYLINDER_SEGMENTS = 96


@dataclasses.dataclass
class ShapeMesh:
    """A triangle mesh with optional per-vertex shading normals and uvs (NumPy, float64).

    - `vertices`: `(v, 3)` positions. [scene length unit]
    - `faces`: `(f, 3)` int64 vertex indices; the winding sets the front side.
    - `normals`: `(v, 3)` unit shading normals, or `None` (the face normals shade).
    - `uvs`: `(v, 2)` texture coordinates, or `None`.
    - `attributes`: Mitsuba's mesh attributes: `vertex_<name>` `(v, d)` and `face_<name>`
        `(f, d)` arrays (e.g. `vertex_color`), read by `mesh_attribute` textures.
    - `sphere`: for a tessellated `sphere` with outward normals, the true sphere's
        `(center (3,), radius, rotation (3, 3))` [scene length unit], the rotation taking
        its object frame (its uv's axes) to the scene's, so that the renderer intersects
        it analytically and an emitter on it is sampled by the cone it subtends
        (`AreaLight`); `None` for other meshes, and once a transform that is not a
        similarity with positive determinant, or `flip_normals`, is applied.
    """

    vertices: np.ndarray
    faces: np.ndarray
    normals: np.ndarray | None = None
    uvs: np.ndarray | None = None
    attributes: dict = dataclasses.field(default_factory=dict)
    sphere: tuple | None = None


def rectangle() -> ShapeMesh:
    """Mitsuba's `rectangle`: [-1, 1]^2 at z = 0, normal +z."""
    v = np.array([[-1, -1, 0], [1, -1, 0], [-1, 1, 0], [1, 1, 0]], np.float64)
    f = np.array([[1, 2, 0], [1, 3, 2]], np.int64)
    return ShapeMesh(v, f, None, (v[:, :2] + 1.0) / 2.0)


# Mitsuba's cube: 4 vertices per face (for face normals), 12 triangles, its vertex order.
_CUBE_V = np.array(
    [[1, -1, -1], [1, -1, 1], [-1, -1, 1], [-1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, 1, 1],
     [1, 1, 1], [1, -1, -1], [1, 1, -1], [1, 1, 1], [1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1],
     [-1, -1, 1], [-1, -1, 1], [-1, 1, 1], [-1, 1, -1], [-1, -1, -1], [1, 1, -1], [1, -1, -1],
     [-1, -1, -1], [-1, 1, -1]], dtype=np.float64)  # fmt: skip
_CUBE_F = (np.array([[0, 1, 2], [3, 0, 2]])[None] + 4 * np.arange(6)[:, None, None]).reshape(-1, 3)
_CUBE_UV = np.tile(np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float64), (6, 1))


def cube() -> ShapeMesh:
    """Mitsuba's `cube`: [-1, 1]^3, outward normals."""
    return ShapeMesh(_CUBE_V.copy(), _CUBE_F.astype(np.int64), None, _CUBE_UV.copy())


def disk(segments: int = DISK_SEGMENTS) -> ShapeMesh:
    """Mitsuba's `disk`: the unit disk at z = 0, normal +z, uv = (r, phi / 2 pi). The rim
    vertex at phi = 0 appears twice (v = 0 and v = 1); the centre has one vertex per fan
    triangle, with v at the triangle's middle angle."""
    k = np.arange(segments + 1)
    phi = 2.0 * np.pi * k / segments
    rim = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=-1)
    rim[-1] = rim[0]
    centre = np.zeros((segments, 3))
    v = np.concatenate([rim, centre])
    uv_rim = np.stack([np.ones(segments + 1), k / segments], axis=-1)
    uv_centre = np.stack([np.zeros(segments), (np.arange(segments) + 0.5) / segments], axis=-1)
    i = np.arange(segments)
    f = np.stack([segments + 1 + i, i, i + 1], axis=-1)
    return ShapeMesh(v, f.astype(np.int64), None, np.concatenate([uv_rim, uv_centre]))


def _grid_faces(rows: int, cols: int) -> np.ndarray:
    """Two triangles per cell of a (rows + 1) x (cols + 1) vertex grid, counter-clockwise
    seen from the side that (d/dcol) x (d/drow) points to."""
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    a = r * (cols + 1) + c
    b, d = a + 1, a + cols + 1
    e = d + 1
    return np.concatenate([np.stack([a, b, e], -1), np.stack([a, e, d], -1)]).reshape(-1, 3)


def cylinder(radius: float, p0, p1, segments: int = CYLINDER_SEGMENTS) -> ShapeMesh:
    """Mitsuba's `cylinder`: radius `radius` [scene length unit] around the segment from
    `p0` to `p1` (`(3,)` points), open ends, normals outward, uv = (phi / 2 pi, z), with phi
    measured from the first axis of Mitsuba's frame around the axis (Duff et al. 2017)."""
    p0, p1 = np.asarray(p0, np.float64), np.asarray(p1, np.float64)
    d = p1 - p0
    axis = d / np.linalg.norm(d)
    s, t = _frame(axis)
    phi = 2.0 * np.pi * np.arange(segments + 1) / segments
    z = np.array([0.0, 1.0])
    zz, pp = np.meshgrid(z, phi, indexing="ij")
    radial = np.cos(pp)[..., None] * s + np.sin(pp)[..., None] * t  # (2, n + 1, 3)
    radial[:, -1] = radial[:, 0]
    v = p0 + radius * radial + zz[..., None] * d
    uv = np.stack([pp / (2.0 * np.pi), zz], axis=-1)
    # d/dphi x d/dz points outward: faces wound as (phi, z) cells seen from outside.
    f = _grid_faces(1, segments)
    return ShapeMesh(v.reshape(-1, 3), f, radial.reshape(-1, 3), uv.reshape(-1, 2))


def sphere(
    center=(0.0, 0.0, 0.0),
    radius: float = 1.0,
    rings: int = SPHERE_RINGS,
    segments: int = SPHERE_SEGMENTS,
) -> ShapeMesh:
    """Mitsuba's `sphere` of `radius` [scene length unit] around `center`, normals outward,
    uv = (phi / 2 pi, theta / pi) with theta from +z and phi from +x towards +y.

    A latitude-longitude grid: the seam (phi = 0 and 2 pi) and the poles have duplicated
    vertices so that every triangle interpolates its uvs without a jump; the zero-area
    triangles at the poles are dropped.
    """
    theta = np.pi * np.arange(rings + 1) / rings
    phi = 2.0 * np.pi * np.arange(segments + 1) / segments
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    n = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=-1)
    n[:, -1] = n[:, 0]
    n[0], n[-1] = (0.0, 0.0, 1.0), (0.0, 0.0, -1.0)
    uv = np.stack([ph / (2.0 * np.pi), th / np.pi], axis=-1)
    # Rows grow in theta (towards -z), columns in phi: d/dphi x d/dtheta points inward, so the
    # cells are wound the other way round.
    f = _grid_faces(rings, segments)[:, [0, 2, 1]]
    v = n.reshape(-1, 3)
    keep = np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
    f = f[keep > 1e-12]
    c = np.asarray(center, np.float64)
    return ShapeMesh(
        v * radius + c, f, v.copy(), uv.reshape(-1, 2), sphere=(c, float(radius), np.eye(3))
    )


def _frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mitsuba's `coordinate_system` (Duff et al. 2017): two unit vectors s, t with
    (s, t, n) right-handed and orthonormal."""
    sign = 1.0 if n[2] >= 0 else -1.0
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    s = np.array([1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]])
    t = np.array([b, sign + n[1] * n[1] * a, -n[1]])
    return s, t


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Mitsuba's vertex normals for a mesh without them: at each vertex, the face normals of
    the triangles around it weighted by their angle at that vertex, normalised (Thuermer and
    Wuethrich 1998). A vertex of no (or only degenerate) triangles gets (0, 0, 1).

    **Arguments:** `vertices` `(v, 3)` [scene length unit], `faces` `(f, 3)`.

    **Returns:** `(v, 3)` unit normals.
    """
    v = np.asarray(vertices, np.float64)
    f = np.asarray(faces, np.int64)
    p = v[f]  # (f, 3, 3)
    fn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.linalg.norm(fn, axis=1, keepdims=True)
    fn = np.where(length > 0, fn / np.where(length > 0, length, 1.0), 0.0)
    out = np.zeros_like(v)
    for k in range(3):  # the three corners of every triangle (vectorised over triangles)
        a = p[:, (k + 1) % 3] - p[:, k]
        b = p[:, (k + 2) % 3] - p[:, k]
        la, lb = np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)
        cos = np.sum(a * b, axis=1) / np.where(la * lb > 0, la * lb, 1.0)
        angle = np.arccos(np.clip(cos, -1.0, 1.0))
        np.add.at(out, f[:, k], fn * angle[:, None])
    length = np.linalg.norm(out, axis=1, keepdims=True)
    return np.where(length > 0, out / np.where(length > 0, length, 1.0), [0.0, 0.0, 1.0])


def _cofactor(m: np.ndarray) -> np.ndarray:
    """det(m) m^-T, also for a singular `m`: its columns are cross products of m's columns."""
    c0, c1, c2 = m[:, 0], m[:, 1], m[:, 2]
    return np.stack([np.cross(c1, c2), np.cross(c2, c0), np.cross(c0, c1)], axis=1)


def transform_mesh(
    mesh: ShapeMesh, to_world: np.ndarray, *, flip_normals: bool = False, dims: int = 3
) -> ShapeMesh:
    """`mesh` under the `(4, 4)` affine `to_world` (positions by the matrix, normals by its
    cofactor matrix, normalised), then `flip_normals` (reversed winding, negated normals).

    `dims` is the number of object-space axes the shape spans (2 for a flat `rectangle` or
    `disk` at z = 0, 3 otherwise): a transform that collapses them raises `ValueError`.
    """
    m = np.asarray(to_world, np.float64)
    lin = m[:3, :3]
    cols = lin[:, :dims]
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is refused just below
        scale = np.prod(np.linalg.norm(cols, axis=0))
        if dims == 3:
            volume = abs(np.linalg.det(lin))
        else:
            volume = np.linalg.norm(np.cross(cols[:, 0], cols[:, 1])) if dims == 2 else scale
        if dims == 1:  # a mesh of any dimension: only a transform that collapses everything
            scale = volume = float(np.linalg.norm(lin))
    if not (np.all(np.isfinite(m)) and np.isfinite(scale) and np.isfinite(volume)):
        raise ValueError(
            "the transform is not finite or too large (its lengths, areas or volumes overflow "
            f"float64); linear part {lin.tolist()}, translation {m[:3, 3].tolist()}."
        )
    if not scale > 0 or volume <= 1e-12 * scale:
        raise ValueError(
            f"the transform is degenerate: it maps the shape's {dims} axes to a "
            f"{'plane or lower (zero volume' if dims == 3 else 'line or point (zero area'}; "
            "linear part "
            f"{np.round(lin, 6).tolist()}); a shape needs a transform of full rank."
        )
    with np.errstate(over="ignore", invalid="ignore"):  # non-finite vertices are refused later
        v = mesh.vertices @ lin.T + m[:3, 3]
    normals = mesh.normals
    if normals is not None:
        with np.errstate(over="ignore", invalid="ignore"):  # refused just below
            n = normals @ _cofactor(lin).T
            n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        if not np.all(np.isfinite(n)):
            raise ValueError(
                "the transform is too large for the shape's normals (their cofactor matrix "
                f"overflows float64); linear part {lin.tolist()}."
            )
        normals = -n if flip_normals else n
    f = mesh.faces[:, [0, 2, 1]] if flip_normals else mesh.faces
    return ShapeMesh(
        v, f, normals, mesh.uvs, mesh.attributes, _transform_sphere(mesh.sphere, m, flip_normals)
    )


def _transform_sphere(sphere, m: np.ndarray, flip_normals: bool):
    """A sphere's `(center, radius, rotation)` under the affine `m`, if `m` keeps it a sphere
    with outward normals (a similarity, `L^T L = s^2 I`, without a mirror: `det L > 0`);
    else `None`."""
    if sphere is None or flip_normals:
        return None
    lin = m[:3, :3]
    gram = lin.T @ lin
    s2 = np.trace(gram) / 3.0
    if not s2 > 0 or np.max(np.abs(gram - s2 * np.eye(3))) > 1e-9 * s2:
        return None
    if np.linalg.det(lin) <= 0:
        return None
    s = np.sqrt(s2)
    return lin @ sphere[0] + m[:3, 3], float(s * sphere[1]), (lin / s) @ sphere[2]
