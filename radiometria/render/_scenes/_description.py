"""Scene descriptions: what a scene file says, as plain frozen dataclasses (thesis ch. 8).

A `SceneDescription` is the offline, NumPy form of a scene: every shape merged into one
triangle array with a material index and an emitter index per triangle, the materials and
emitters with their parameters as the file gives them, the camera, the film and the
integrator settings. `compile_scene` turns it into the renderer's plugins (`RenderScene`,
camera, filter, integrator); nothing here touches JAX.

Parameters are kept as a file gives them (Mitsuba 3's `Properties`): numbers, strings, and
spectral values as typed objects, never as dicts: a `LinearRGB` triple (whose spectrum the
receiving plugin chooses: albedo, unbounded or illuminant, thesis 2.2.3), a
`radiometria.radiometry.PiecewiseLinearSpectrum` (tabulated, linear in between and zero
outside: the Cornell measurements' convention) or a `BlackbodySpectrum` (thesis eq. 1.24).

Degenerate triangles (zero area in float64) are dropped from ordinary shapes, and are an
error in an emitter (a light must have a positive area on every triangle).
"""

import dataclasses
from pathlib import Path

import numpy as np

from ...camera import look_at as camera_look_at
from .._geometry._mesh import TriangleMesh, _areas, validate_triangles
from .._spectral import SpectralValue
from .._textures import TextureSpec

__all__ = [
    "check_spectral_values",
    "read_scene_text",
    "AreaEmitter",
    "LightDescription",
    "CameraDescription",
    "FilmDescription",
    "Material",
    "MediumDescription",
    "SceneDescription",
    "SceneError",
]

FOV_AXES = ("x", "y", "diagonal", "smaller", "larger")


def read_scene_text(path: Path) -> str:
    """A scene file's text: `FileNotFoundError` naming a missing file, `SceneError` naming a
    file that is not UTF-8 text (a binary file given as a scene)."""
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FileNotFoundError(f"scene file not found: {path}") from None
    except UnicodeDecodeError as e:
        raise SceneError(f"{path}: not UTF-8 text ({e.reason} at byte {e.start}).") from None


def check_spectral_values(values, what: str) -> None:
    """Spectral parameters (reflectances, radiances, indices, factors) are finite and >= 0;
    `what` names the file, line or field, and the parameter."""
    v = np.asarray(values, np.float64)
    if not np.all(np.isfinite(v)) or np.any(v < 0):
        raise SceneError(f"{what}: values must be finite and >= 0, got {v.tolist()}.")


class SceneError(ValueError):
    """A scene file or scene description is invalid; the message names the file and the line
    or field (thesis ch. 8: scene input)."""

    def __init__(self, message: str):
        super().__init__(message)


@dataclasses.dataclass(frozen=True)
class Material:
    """A surface material: a Mitsuba-style BSDF type and its parameters (thesis ch. 3 and 8).

    **Fields:**

    - `type`: the BSDF plugin's name, a key of `radiometria.render._registry.MATERIALS`
        (`"diffuse"`, `"conductor"`, `"roughconductor"`, `"dielectric"`, ...).
    - `params`: parameter name -> value as the file gives it: spectral values as typed
        objects (module docstring; e.g. `{"reflectance": LinearRGB([0.5, 0.5, 0.5])}`),
        scalars (`alpha`) as numbers, names (`distribution`, `material`, a named `int_ior`)
        as `str`.
    - `two_sided`: scatter on both sides (Mitsuba's `twosided` wrapper); else only on the side
        the triangle normal points to, black from behind. [bool]
    - `name`: the id in the file, or a generated name.

    !!! note "Thesis"
        Ch. 3 (BSDFs), parameters as in Mitsuba 3 (`Jakob2022`).
    """

    type: str
    params: dict
    two_sided: bool = False
    name: str = ""


@dataclasses.dataclass(frozen=True)
class MediumDescription:
    """A participating medium: a Mitsuba-style medium type and its parameters (thesis ch. 4).

    **Fields:**

    - `type`: the medium plugin's name, a key of `radiometria.render._registry.MEDIA`
        (`"homogeneous"`, `"heterogeneous"`).
    - `params`: parameter name -> value as the file gives it: `sigma_t` and `albedo` as
        spectral values (an RGB `sigma_t` is an unbounded spectrum, an RGB `albedo` an albedo
        spectrum, thesis 2.2.3) or, for grids, `{"type": "gridvolume" | "constvolume", ...}`
        dicts; `scale` a number [1]; `g` the Henyey-Greenstein mean cosine (0: isotropic).
        Coefficients are per scene length unit. [scene units^-1]
    - `name`: the id in the file, or a generated name.

    !!! note "Thesis"
        Section 1.3 and ch. 4; Mitsuba 3's medium plugins (`Jakob2022`).
    """

    type: str
    params: dict
    name: str = ""


@dataclasses.dataclass(frozen=True)
class AreaEmitter:
    """A diffuse area light on a set of triangles of the merged mesh (thesis ch. 8).

    **Fields:**

    - `radiance`: emitted radiance, a spectral value of the module docstring (an RGB triple
        is an illuminant spectrum) or a `TextureSpec` (looked up at the emitting point's
        uv). [W m^-2 sr^-1 nm^-1, or the file's relative unit]
    - `triangles`: `(k,)` int32 indices into `SceneDescription.faces`.
    - `areas`: `(k,)` areas of those triangles. [scene length unit^2]
    - `total_area`: their sum. [scene length unit^2]
    - `two_sided`: emit on both sides (default: only on the side of the triangle normal).
    - `name`: the shape's name.
    - `sphere`: `(center (3,), radius)` of the true sphere when the triangles tessellate a
        `sphere` shape (its light samples are then drawn from the cone it subtends), else
        `None`. [scene length unit]

    !!! note "Thesis"
        Ch. 8 (emitters; area lights are sampled uniformly by area, `Pharr2023` §12.2).
    """

    radiance: "SpectralValue | TextureSpec"
    triangles: np.ndarray
    areas: np.ndarray
    total_area: float
    two_sided: bool = False
    name: str = ""
    sphere: tuple | None = None


@dataclasses.dataclass(frozen=True)
class SphereShape:
    """A `sphere` shape whose triangles tessellate a true sphere (thesis ch. 8): the renderer
    intersects the sphere itself (`radiometria.render.compile_scene`).

    **Fields:**

    - `center`: `(3,)` centre. [scene length unit]
    - `radius`: radius. [scene length unit]
    - `rotation`: `(3, 3)` rotation from the sphere's object frame (the axes of its uv:
        `u = phi / 2 pi` from +x towards +y, `v = theta / pi` from +z) to the scene's axes.
    - `triangles`: `(k,)` int32 indices into `SceneDescription.faces` of its tessellation.
    - `name`: the shape's name.

    !!! note "Thesis"
        Ch. 8 (shapes); Mitsuba 3's `sphere` (`Jakob2022`).
    """

    center: np.ndarray
    radius: float
    rotation: np.ndarray
    triangles: np.ndarray
    name: str = ""


@dataclasses.dataclass(frozen=True)
class LightDescription:
    """A light that is not on a shape: `point`, `spot`, `directional`, `constant`, `envmap`
    (thesis ch. 8).

    **Fields:**

    - `type`: the plugin's name, a key of `radiometria.render._registry.LIGHTS`.
    - `params`: parameter name -> value as the file gives it (spectral values as typed
        objects, `to_world` as a `(4, 4)` array, points and vectors as `(3,)` arrays, an
        environment map's image as `data`, `(H, W, 3)` linear RGB).
    - `name`: the id in the file, or a generated name.
    - `where`: the file and line (or field) that defines it, for error messages.

    !!! note "Thesis"
        Ch. 8 (light sources); Mitsuba 3's emitters (`Jakob2022`).
    """

    type: str
    params: dict
    name: str = ""
    where: str = ""


@dataclasses.dataclass(frozen=True)
class CameraDescription:
    """A pinhole (perspective) camera in Mitsuba's convention (thesis section 2.3.1).

    Camera space looks along +z with +y up and +x to the left of the image; `to_world` maps
    camera space to world space (its last column is the camera position).

    **Fields:**

    - `to_world`: `(4, 4)` float64 camera-to-world matrix. [scene length unit]
    - `fov_deg`: field of view along `fov_axis`. [degrees]
    - `fov_axis`: `"x"`, `"y"`, `"diagonal"`, `"smaller"` or `"larger"` (Mitsuba's names).
    - `near_clip`, `far_clip`: clip distances. [scene length unit]
    - `type`: the camera model, a name of `radiometria.render._registry.CAMERAS`:
        `"perspective"` (pinhole), `"thinlens"` or `"orthographic"` (which ignores `fov_deg`;
        the scale of `to_world` sets its imaged extent). Mitsuba's sensor names.
    - `aperture_radius`, `focus_distance`: the thin lens's radius and distance of the plane
        in focus (`"thinlens"` only). [scene length unit]
    - `principal_point`: the principal point offset `(x, y)` in fractions of the film
        (`"perspective"` only; Mitsuba's `principal_point_offset_x/y`). [-]

    !!! note "Thesis"
        Section 2.3.1 (pinhole camera model); Mitsuba's `perspective`, `thinlens` and
        `orthographic` sensors (`Jakob2022`).
    """

    to_world: np.ndarray
    fov_deg: float
    fov_axis: str = "x"
    near_clip: float = 1e-2
    far_clip: float = 1e4
    type: str = "perspective"
    aperture_radius: float = 0.0
    focus_distance: float = 1e4
    principal_point: tuple[float, float] = (0.0, 0.0)

    @property
    def origin(self) -> np.ndarray:
        """Camera position `(3,)`. [scene length unit]"""
        return np.asarray(self.to_world)[:3, 3]

    @property
    def direction(self) -> np.ndarray:
        """Unit viewing direction `(3,)` (camera +z in world space)."""
        d = np.asarray(self.to_world)[:3, 2]
        return d / np.linalg.norm(d)

    @property
    def up(self) -> np.ndarray:
        """Unit up vector `(3,)` (camera +y in world space)."""
        u = np.asarray(self.to_world)[:3, 1]
        return u / np.linalg.norm(u)


@dataclasses.dataclass(frozen=True)
class FilmDescription:
    """Image size and reconstruction filter (thesis section 2.3.2).

    **Fields:**

    - `width`, `height`: image size. [px]
    - `filter`: filter type: `"box"`, `"tent"`, `"gaussian"`, `"mitchell"`,
        `"catmullrom"` or `"lanczos"` (Mitsuba's names).
    - `filter_params`: e.g. `{"stddev": 0.5, "radius": 2.0}` for the Gaussian. [px]
    - `crop`: `None` (the whole film), or the crop window `(offset_x, offset_y, crop_width,
        crop_height)` of the `width` x `height` film that is rendered (Mitsuba's
        `crop_offset_*`, `crop_width`, `crop_height`); the image is the window's size. [px]

    !!! note "Thesis"
        Section 2.3.2 (filtering image samples); Mitsuba's `hdrfilm` (`Jakob2022`).
    """

    width: int
    height: int
    filter: str = "gaussian"
    filter_params: dict = dataclasses.field(default_factory=lambda: {"stddev": 0.5, "radius": 2.0})
    crop: tuple[int, int, int, int] | None = None


@dataclasses.dataclass(frozen=True)
class SceneDescription:
    """A whole scene as NumPy arrays and plain Python values (thesis ch. 8).

    **Fields:**

    - `vertices`: `(v, 3)` float64 positions of all shapes. [scene length unit]
    - `faces`: `(f, 3)` int32 triangles (no degenerate ones).
    - `face_material`: `(f,)` int32 index into `materials`.
    - `face_emitter`: `(f,)` int32 index into `emitters`, -1 for a non-emissive triangle.
    - `face_shape`: `(f,)` int32 index into `shape_names`.
    - `materials`: tuple of `Material`.
    - `emitters`: tuple of `AreaEmitter`.
    - `lights`: tuple of `LightDescription`, the lights that are not on a shape.
    - `camera`: `CameraDescription`.
    - `film`: `FilmDescription`.
    - `integrator`: the integrator plugin's name, a key of
        `radiometria.render._registry.INTEGRATORS` (`"path"`, `"direct"`).
    - `max_depth`: the path tracer's maximum number of path segments (Mitsuba's meaning: 1 =
        emitters seen directly, 2 = direct illumination), or `None` when the file leaves it
        unbounded or unset.
    - `rr_depth`: depth at which Russian roulette starts (Mitsuba's `rr_depth`).
    - `integrator_params`: the integrator's other parameters as `(name, value)` pairs (e.g.
        `(("hide_emitters", True),)`), passed to its `from_properties`.
    - `spp`: samples per pixel the file asks for, or `None`.
    - `seed`: the sampler's seed the file asks for (Mitsuba's seed offset; the render's
        `jax.random.key` seed), or `None`.
    - `sampler`: the sampler the file asks for, a name of
        `radiometria.render._registry.SAMPLERS` (Mitsuba's names), or `None` where it names
        none (`render` then uses Mitsuba's default, `independent`; the command line its
        lowest-error one, `sobol`).
    - `shape_names`: tuple of shape names.
    - `unit`: the length unit of the coordinates (e.g. `"mm"`), as a string.
    - `source`: where the scene came from (built-in name or path).
    - `media`: tuple of `MediumDescription` (default none).
    - `face_interior`, `face_exterior`: `(f,)` int32 medium index behind / in front of each
        triangle's normal, -1 for a vacuum, -2 where the shape bounds no medium; `None` when
        the scene has no media.
    - `camera_medium`: index of the medium the camera is in, -1 for a vacuum.
    - `vertex_normals`: `(v, 3)` unit shading normals, interpolated across each triangle
        (Mitsuba's vertex normals), NaN rows for the vertices of shapes shaded by their face
        normals; `None` when no shape has any.
    - `vertex_uvs`: `(v, 2)` texture coordinates, NaN rows for the vertices of shapes without
        uvs; `None` when no shape has any. [1]
    - `mesh_attributes`: Mitsuba's mesh attributes of the shapes, by name
        (`"vertex_<name>"`: `(v, d)` per vertex, `"face_<name>"`: `(f, d)` per triangle), NaN
        rows for the shapes without that attribute (`mesh_attribute` textures read them).
    - `spheres`: tuple of `SphereShape`, the shapes whose triangles tessellate a true sphere
        (Mitsuba's `sphere` under a similarity without a mirror, normals outward).

    !!! note "Thesis"
        Ch. 8 (scene description for light transport); file formats of Mitsuba 3
        (`Jakob2022`).
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_material: np.ndarray
    face_emitter: np.ndarray
    face_shape: np.ndarray
    materials: tuple
    emitters: tuple
    camera: CameraDescription
    film: FilmDescription
    max_depth: int | None = 8
    rr_depth: int = 5
    spp: int | None = None
    seed: int | None = None
    integrator: str = "path"
    integrator_params: tuple = ()
    sampler: str | None = None
    shape_names: tuple = ()
    unit: str = "scene units"
    source: str = ""
    lights: tuple = ()
    media: tuple = ()
    face_interior: np.ndarray | None = None
    face_exterior: np.ndarray | None = None
    camera_medium: int = -1
    vertex_normals: np.ndarray | None = None
    vertex_uvs: np.ndarray | None = None
    mesh_attributes: dict = dataclasses.field(default_factory=dict)
    spheres: tuple = ()

    def __post_init__(self):
        f = np.asarray(self.faces)
        n = len(f)
        where = self.source or "scene"
        if f.ndim != 2 or f.shape[1] != 3:
            raise SceneError(f"{where}: faces must have shape (f, 3), got {f.shape}.")
        for name in ("face_material", "face_emitter", "face_shape"):
            a = np.asarray(getattr(self, name))
            if a.shape != (n,):
                raise SceneError(f"{where}: {name} must have shape ({n},), got {a.shape}.")
        fm = np.asarray(self.face_material)
        if n and (fm.min() < 0 or fm.max() >= len(self.materials)):
            raise SceneError(
                f"{where}: face_material must index the {len(self.materials)} materials."
            )
        fe = np.asarray(self.face_emitter)
        if n and (fe.min() < -1 or fe.max() >= len(self.emitters)):
            raise SceneError(
                f"{where}: face_emitter must be -1 or index the {len(self.emitters)} emitters."
            )

    @property
    def n_triangles(self) -> int:
        """Number of triangles."""
        return int(len(self.faces))

    @property
    def mesh(self) -> TriangleMesh:
        """The merged geometry as a `TriangleMesh` with per-face material indices."""
        return TriangleMesh(self.vertices, self.faces, self.face_material)

    @property
    def emissive_triangles(self) -> np.ndarray:
        """Indices `(l,)` of all emissive triangles, in emitter order."""
        if not self.emitters:
            return np.zeros(0, np.int32)
        return np.concatenate([e.triangles for e in self.emitters]).astype(np.int32)


# ---------------------------------------------------------------------------------------------
# Assembly shared by the JSON and Mitsuba loaders


@dataclasses.dataclass
class ShapeDescription:
    name: str
    vertices: np.ndarray
    faces: np.ndarray
    material: int
    emitter: dict | None = None  # {"radiance": SpectralValue, "two_sided": bool}
    where: str = ""
    interior: int = -2  # medium behind the normal (-1 vacuum, -2: no medium boundary)
    exterior: int = -2  # medium in front of the normal
    normals: np.ndarray | None = None  # (v, 3) shading normals, or None: face normals shade
    uvs: np.ndarray | None = None  # (v, 2) texture coordinates, or None
    # Mitsuba's mesh attributes: "vertex_<name>" (v, d) and "face_<name>" (f, d) arrays
    attributes: dict = dataclasses.field(default_factory=dict)
    sphere: tuple | None = None  # a tessellated sphere's (center, radius, rotation), `ShapeMesh`


def assemble(
    shapes: list[ShapeDescription],
    materials: list[Material],
    camera: CameraDescription,
    film: FilmDescription,
    *,
    max_depth: int | None,
    rr_depth: int = 5,
    spp: int | None = None,
    integrator: str = "path",
    unit: str = "scene units",
    source: str = "",
    lights: tuple = (),
    media: tuple = (),
    camera_medium: int = -1,
) -> SceneDescription:
    """Validate the shapes (degenerate rule), merge them and build the emitters."""
    all_v, all_f, mat, emi, owner, emitters, spheres = [], [], [], [], [], [], []
    sides: list[np.ndarray] = []
    normals: list[np.ndarray] = []
    uvs: list[np.ndarray] = []
    attrs: dict[str, list[tuple[int, int, np.ndarray]]] = {}  # name: (shape, first row, values)
    offset = 0
    n_faces = 0
    for si, sh in enumerate(shapes):
        v = np.asarray(sh.vertices, dtype=np.float64).reshape(-1, 3)
        f = np.asarray(sh.faces).reshape(-1, 3)
        try:
            keep = validate_triangles(
                v, f, where=sh.where or sh.name, degenerate="error" if sh.emitter else "drop"
            )
        except ValueError as e:
            raise SceneError(str(e)) from None
        for name, a in sh.attributes.items():
            a = np.asarray(a, np.float64)
            a = a.reshape(len(a), -1)
            rows = len(v) if name.startswith("vertex_") else len(keep)
            if not name.startswith(("vertex_", "face_")) or len(a) != rows:
                raise SceneError(f"{sh.where or sh.name}: mesh attribute {name!r} of shape "
                                 f"{a.shape}: expected 'vertex_<name>' with {len(v)} rows or "
                                 f"'face_<name>' with {len(keep)}.")  # fmt: skip
            if name.startswith("face_"):
                a = a[keep]  # the triangles the loader keeps
            first = offset if name.startswith("vertex_") else n_faces
            attrs.setdefault(name, []).append((si, first, a))
        f = f[keep].astype(np.int64)
        all_v.append(v)
        all_f.append(f + offset)
        for attr, out, cols in ((sh.normals, normals, 3), (sh.uvs, uvs, 2)):
            a = np.full((len(v), cols), np.nan) if attr is None else np.asarray(attr, np.float64)
            if a.shape != (len(v), cols):
                raise SceneError(f"{sh.where or sh.name}: per-vertex attribute of shape "
                                 f"{a.shape}, expected ({len(v)}, {cols}).")  # fmt: skip
            out.append(a)
        mat.append(np.full(len(f), sh.material, np.int32))
        owner.append(np.full(len(f), si, np.int32))
        sides.append(np.tile(np.array([[sh.interior, sh.exterior]], np.int32), (len(f), 1)))
        if sh.emitter is not None:
            if len(f) == 0:
                raise SceneError(f"{sh.where or sh.name}: an emitter needs at least one triangle.")
            tri = np.arange(n_faces, n_faces + len(f), dtype=np.int32)
            areas = _areas(np, v, f)
            emi.append(np.full(len(f), len(emitters), np.int32))
            emitters.append(
                AreaEmitter(
                    radiance=sh.emitter["radiance"],
                    triangles=tri,
                    areas=areas,
                    total_area=float(areas.sum()),
                    two_sided=bool(sh.emitter.get("two_sided", False)),
                    name=sh.name,
                    sphere=None if sh.sphere is None else tuple(sh.sphere[:2]),
                )
            )
        else:
            emi.append(np.full(len(f), -1, np.int32))
        if sh.sphere is not None and len(f):
            c, r, rot = sh.sphere
            spheres.append(SphereShape(
                np.asarray(c, np.float64), float(r), np.asarray(rot, np.float64),
                np.arange(n_faces, n_faces + len(f), dtype=np.int32), sh.name,
            ))  # fmt: skip
        offset += len(v)
        n_faces += len(f)
    cat = lambda xs, shape, dt: np.concatenate(xs).astype(dt) if xs else np.zeros(shape, dt)
    return SceneDescription(
        vertices=cat(all_v, (0, 3), np.float64),
        faces=cat(all_f, (0, 3), np.int32),
        face_material=cat(mat, (0,), np.int32),
        face_emitter=cat(emi, (0,), np.int32),
        face_shape=cat(owner, (0,), np.int32),
        materials=tuple(materials),
        emitters=tuple(emitters),
        camera=camera,
        film=film,
        max_depth=max_depth,
        rr_depth=rr_depth,
        spp=spp,
        integrator=integrator,
        shape_names=tuple(s.name for s in shapes),
        unit=unit,
        source=source,
        lights=tuple(lights),
        media=tuple(media),
        face_interior=cat(sides, (0, 2), np.int32)[:, 0] if media else None,
        face_exterior=cat(sides, (0, 2), np.int32)[:, 1] if media else None,
        camera_medium=camera_medium,
        vertex_normals=_attribute(normals, [s.normals for s in shapes], 3),
        vertex_uvs=_attribute(uvs, [s.uvs for s in shapes], 2),
        mesh_attributes=_mesh_attributes(attrs, offset, n_faces),
        spheres=tuple(spheres),
    )


def _mesh_attributes(attrs: dict, n_vertices: int, n_faces: int) -> dict[str, np.ndarray]:
    """The shapes' mesh attributes merged over the scene's vertices or triangles (NaN rows
    where a shape has none); all shapes' channels of one name must agree."""
    out = {}
    for name, parts in attrs.items():
        dims = {a.shape[1] for _, _, a in parts}
        if len(dims) > 1:
            raise SceneError(f"mesh attribute {name!r} has {sorted(dims)} channels on different "
                             "shapes; one name must have one channel count.")  # fmt: skip
        rows = n_vertices if name.startswith("vertex_") else n_faces
        merged = np.full((rows, dims.pop()), np.nan)
        for _, first, a in parts:
            merged[first : first + len(a)] = a
        out[name] = merged
    return out


def _attribute(parts: list, given: list, cols: int) -> np.ndarray | None:
    """Merged per-vertex attribute (NaN rows where a shape has none), `None` if none has."""
    if all(g is None for g in given):
        return None
    return np.concatenate(parts) if parts else np.zeros((0, cols))


def look_at_matrix(origin, target, up) -> np.ndarray:
    """`radiometria.camera.look_at` as a float64 NumPy matrix, for the offline scene loaders.

    Degenerate input (target equal to origin, up parallel to the view) raises `ValueError`.
    """
    o, t, u = (np.asarray(v, dtype=np.float64).reshape(3) for v in (origin, target, up))
    d = t - o
    if not np.any(d) or not np.any(np.cross(u, d)):
        raise ValueError("look_at: `target` equals `origin` or `up` is parallel to the view.")
    return np.asarray(camera_look_at(o, t, u), dtype=np.float64)


# ---------------------------------------------------------------------------------------------
# Our JSON format (the schema of data/cornell_box.json and data/cornell_box_measured.json)
