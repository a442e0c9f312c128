"""Scene descriptions: what a scene file says, as plain frozen dataclasses (thesis ch. 8).

A `SceneDescription` is the offline, NumPy form of a scene: every shape merged into one
triangle array with a material index and an emitter index per triangle, the materials and
emitters with their parameters, the camera, the film and the integrator settings. The
integrators turn it into device arrays (`RenderScene`); nothing here touches JAX.

Spectral parameters (a reflectance, an emitted radiance, an index of refraction) are small
dicts with exactly one key:

- `{"rgb": array (3,)}`: a linear sRGB triple (Rec. 709 primaries, D65 white);
- `{"spectrum": (wavelengths_nm (k,), values (k,))}`: a tabulated spectrum, linear in
  between and zero outside (the Cornell measurements' convention);
- `{"blackbody": {"temperature": T [K], "scale": s}}`: `s` times Planck's law;
- `{"value": x}`: a wavelength-independent scalar (also for named IORs: `{"name": "bk7"}`).

Built-in scenes (`load_scene`):

- `"cornell-box"`: exactly `data/cornell_box.json`, the expansion of Mitsuba 3's
  `cornell_box()` into world-space triangles (36 triangles, 3 diffuse materials, one area
  light of 0.46 x 0.38 = 0.1748 units^2, camera at z = 3.9, 256 x 256 Gaussian film,
  `max_depth` 8).
- `"cornell-box-measured"`: `data/cornell_box_measured.json`, the Cornell Program of Computer
  Graphics measurements (mm; reflectance spectra 400-700 nm every 4 nm; light spectrum).
  The data lists quads with mixed orientation, so each quad is re-oriented here: a shape made
  of one quad (walls, floor, ceiling, light) faces the centre of the room's box, a shape of
  several quads (the two blocks) faces away from its own centroid. The light, which the data
  puts in the ceiling plane, is lowered by `MEASURED_LIGHT_OFFSET_MM` = 0.1 mm so it is in
  front of the ceiling. The camera (position, direction, up, 39.3077 degrees) becomes a
  `to_world` with Mitsuba's `look_at`; the film is the recommended 512 x 512 with the same
  Gaussian filter as the other box.

Degenerate triangles (zero area in float64) are dropped from ordinary shapes, and are an
error in an emitter (a light must have a positive area on every triangle).
"""

import dataclasses
import json
import math
from importlib import resources
from pathlib import Path

import numpy as np

from ..camera import look_at as _camera_look_at
from ._mesh import TriangleMesh, _areas, validate_triangles

__all__ = [
    "AreaEmitter",
    "CameraDescription",
    "FilmDescription",
    "MEASURED_LIGHT_OFFSET_MM",
    "Material",
    "SceneDescription",
    "SceneError",
    "BUILTIN_SCENES",
    "load_scene",
]

MEASURED_LIGHT_OFFSET_MM = 0.1
BUILTIN_SCENES = {
    "cornell-box": "cornell_box.json",
    "cornell-box-measured": "cornell_box_measured.json",
}
MATERIAL_TYPES = ("diffuse", "conductor", "roughconductor", "dielectric", "roughdielectric")
FOV_AXES = ("x", "y", "diagonal", "smaller", "larger")


class SceneError(ValueError):
    """A scene file or scene description is invalid; the message names the file and the line
    or field (thesis ch. 8: scene input)."""

    def __init__(self, message: str):
        super().__init__(message)


@dataclasses.dataclass(frozen=True)
class Material:
    """A surface material: a Mitsuba-style BSDF type and its parameters (thesis ch. 3 and 8).

    **Fields:**

    - `type`: `"diffuse"`, `"conductor"`, `"roughconductor"`, `"dielectric"` or
        `"roughdielectric"`.
    - `params`: parameter name -> value; spectral values use the dict forms of the module
        docstring (e.g. `{"reflectance": {"rgb": array([0.5, 0.5, 0.5])}}`); scalars
        (`alpha`) are `{"value": x}`; strings (`distribution`, `material`) are plain `str`.
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
class AreaEmitter:
    """A diffuse area light on a set of triangles of the merged mesh (thesis ch. 8).

    **Fields:**

    - `radiance`: emitted radiance, one of the dict forms of the module docstring.
        [W m^-2 sr^-1 nm^-1, or the file's relative unit]
    - `triangles`: `(k,)` int32 indices into `SceneDescription.faces`.
    - `areas`: `(k,)` areas of those triangles. [scene length unit^2]
    - `total_area`: their sum. [scene length unit^2]
    - `two_sided`: emit on both sides (default: only on the side of the triangle normal).
    - `name`: the shape's name.

    !!! note "Thesis"
        Ch. 8 (emitters; area lights are sampled uniformly by area, `Pharr2023` §12.2).
    """

    radiance: dict
    triangles: np.ndarray
    areas: np.ndarray
    total_area: float
    two_sided: bool = False
    name: str = ""


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

    !!! note "Thesis"
        Section 2.3.1 (pinhole camera model); Mitsuba's `perspective` sensor (`Jakob2022`).
    """

    to_world: np.ndarray
    fov_deg: float
    fov_axis: str = "x"
    near_clip: float = 1e-2
    far_clip: float = 1e4

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

    !!! note "Thesis"
        Section 2.3.2 (filtering image samples); Mitsuba's `hdrfilm` (`Jakob2022`).
    """

    width: int
    height: int
    filter: str = "gaussian"
    filter_params: dict = dataclasses.field(default_factory=lambda: {"stddev": 0.5, "radius": 2.0})


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
    - `camera`: `CameraDescription`.
    - `film`: `FilmDescription`.
    - `max_depth`: the path tracer's maximum number of path segments (Mitsuba's meaning: 1 =
        emitters seen directly, 2 = direct illumination), or `None` when the file leaves it
        unbounded or unset.
    - `rr_depth`: depth at which Russian roulette starts (Mitsuba's `rr_depth`).
    - `spp`: samples per pixel the file asks for, or `None`.
    - `shape_names`: tuple of shape names.
    - `unit`: the length unit of the coordinates (e.g. `"mm"`), as a string.
    - `source`: where the scene came from (built-in name or path).

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
    shape_names: tuple = ()
    unit: str = "scene units"
    source: str = ""

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
class _Shape:
    name: str
    vertices: np.ndarray
    faces: np.ndarray
    material: int
    emitter: dict | None = None  # {"radiance": ..., "two_sided": bool}
    where: str = ""


def _assemble(
    shapes: list[_Shape],
    materials: list[Material],
    camera: CameraDescription,
    film: FilmDescription,
    *,
    max_depth: int | None,
    rr_depth: int = 5,
    spp: int | None = None,
    unit: str = "scene units",
    source: str = "",
) -> SceneDescription:
    """Validate the shapes (degenerate rule), merge them and build the emitters."""
    all_v, all_f, mat, emi, owner, emitters = [], [], [], [], [], []
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
        f = f[keep].astype(np.int64)
        all_v.append(v)
        all_f.append(f + offset)
        mat.append(np.full(len(f), sh.material, np.int32))
        owner.append(np.full(len(f), si, np.int32))
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
                )
            )
        else:
            emi.append(np.full(len(f), -1, np.int32))
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
        shape_names=tuple(s.name for s in shapes),
        unit=unit,
        source=source,
    )


def _look_at(origin, target, up) -> np.ndarray:
    """`radiometria.camera.look_at` as a float64 NumPy matrix, for the offline scene loaders.

    Degenerate input (target equal to origin, up parallel to the view) raises `ValueError`.
    """
    o, t, u = (np.asarray(v, dtype=np.float64).reshape(3) for v in (origin, target, up))
    d = t - o
    if not np.any(d) or not np.any(np.cross(u, d)):
        raise ValueError("look_at: `target` equals `origin` or `up` is parallel to the view.")
    return np.asarray(_camera_look_at(o, t, u), dtype=np.float64)


# ---------------------------------------------------------------------------------------------
# Our JSON format (the schema of data/cornell_box.json and data/cornell_box_measured.json)


class _Json:
    """Field access that names the file and the JSON path in every error."""

    def __init__(self, value, path: str, file: str):
        self.value, self.path, self.file = value, path, file

    def err(self, msg: str) -> SceneError:
        return SceneError(f"{self.file}: field '{self.path}': {msg}")

    def has(self, key: str) -> bool:
        return isinstance(self.value, dict) and key in self.value

    def __getitem__(self, key):
        if isinstance(key, str):
            if not isinstance(self.value, dict):
                raise self.err(
                    f"expected an object with key '{key}', got {type(self.value).__name__}"
                )
            if key not in self.value:
                raise self.err(f"missing key '{key}'")
            sub = f"{self.path}.{key}" if self.path else key
        else:
            if not isinstance(self.value, list) or not -len(self.value) <= key < len(self.value):
                raise self.err(f"expected a list with an element {key}")
            sub = f"{self.path}[{key}]"
        return _Json(self.value[key], sub, self.file)

    def get(self, key, default=None):
        return self[key] if self.has(key) else _Json(default, f"{self.path}.{key}", self.file)

    def items(self):
        if not isinstance(self.value, dict):
            raise self.err("expected an object")
        return [(k, self[k]) for k in self.value]

    def list(self):
        if not isinstance(self.value, list):
            raise self.err(f"expected a list, got {type(self.value).__name__}")
        return [self[i] for i in range(len(self.value))]

    def number(self, positive: bool = False) -> float:
        v = self.value
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise self.err(f"expected a finite number, got {v!r}")
        if positive and v <= 0:
            raise self.err(f"expected a number > 0, got {v!r}")
        return float(v)

    def integer(self, minimum: int | None = None) -> int:
        v = self.value
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.err(f"expected an integer, got {v!r}")
        if minimum is not None and v < minimum:
            raise self.err(f"expected an integer >= {minimum}, got {v}")
        return int(v)

    def string(self) -> str:
        if not isinstance(self.value, str):
            raise self.err(f"expected a string, got {self.value!r}")
        return self.value

    def array(self, shape: tuple, dtype=np.float64) -> np.ndarray:
        try:
            a = np.asarray(self.value, dtype=dtype)
        except (TypeError, ValueError):
            raise self.err(f"expected a numeric array of shape {shape}") from None
        if a.ndim != len(shape) or any(
            s not in (-1, n) for s, n in zip(shape, a.shape, strict=True)
        ):
            raise self.err(f"expected shape {shape} (-1: any), got {a.shape}")
        if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
            raise self.err("contains a non-finite value")
        return a


def _fov_axis(text: str, node: _Json) -> str:
    word = text.strip().split()[0].lower() if text.strip() else ""
    if word not in FOV_AXES:
        raise node.err(f"fov_axis must start with one of {FOV_AXES}, got {text!r}")
    return word


def _json_camera(cam: _Json) -> tuple[CameraDescription, tuple[int, int] | None]:
    fov = cam["fov_deg"].number(positive=True)
    if not fov < 180:
        raise cam["fov_deg"].err(f"expected a field of view < 180 degrees, got {fov}")
    axis = _fov_axis(cam["fov_axis"].string(), cam["fov_axis"]) if cam.has("fov_axis") else "x"
    if cam.has("to_world"):
        m = cam["to_world"].array((4, 4))
    elif cam.has("position"):
        o = cam["position"].array((3,))
        m = _look_at(o, o + cam["direction"].array((3,)), cam["up"].array((3,)))
    else:
        o = cam["origin"].array((3,))
        m = _look_at(o, o + cam["looks_towards"].array((3,)), cam["up"].array((3,)))
    res = None
    if cam.has("recommended_resolution"):
        w, h = cam["recommended_resolution"].array((2,), dtype=np.int64)
        res = (int(w), int(h))
    near = cam["near_clip"].number(positive=True) if cam.has("near_clip") else 1e-2
    far = cam["far_clip"].number(positive=True) if cam.has("far_clip") else 1e4
    return CameraDescription(
        to_world=m, fov_deg=fov, fov_axis=axis, near_clip=near, far_clip=far
    ), res


def _json_film(root: _Json, res) -> FilmDescription:
    if not root.has("film"):
        w, h = res if res is not None else (256, 256)
        return FilmDescription(width=w, height=h)
    film = root["film"]
    width = film["width"].integer(minimum=1)
    height = film["height"].integer(minimum=1)
    if not film.has("reconstruction_filter"):
        return FilmDescription(width=width, height=height)
    rf = film["reconstruction_filter"]
    kind = rf["type"].string().lower()
    params = {}
    for key, val in rf.items():
        if key == "type":
            continue
        params[key.removesuffix("_px")] = val.number()
    return FilmDescription(width=width, height=height, filter=kind, filter_params=params)


def _json_material_type(text: str, node: _Json) -> str:
    t = text.lower()
    if t.startswith(("lambertian", "diffuse")):
        return "diffuse"
    word = t.split()[0] if t.split() else ""
    if word in MATERIAL_TYPES:
        return word
    raise node.err(f"unknown material type {text!r}; valid: 'lambertian', {MATERIAL_TYPES}")


def _json_spectrum(node: _Json, spectra: _Json | None, grid: np.ndarray | None) -> dict:
    """A spectral value: an rgb list, a {wavelengths_nm, values} object, or a name in `spectra`."""
    v = node.value
    if isinstance(v, str):
        if spectra is None or not spectra.has(v):
            raise node.err(f"names the spectrum {v!r}, which 'spectra' does not define")
        return _json_spectrum(spectra[v], None, grid)
    if isinstance(v, dict):
        wl = node["wavelengths_nm"].array((-1,))
        vals = node["values"].array((len(wl),))
        if len(wl) < 2 or np.any(np.diff(wl) <= 0):
            raise node["wavelengths_nm"].err("expected >= 2 strictly increasing wavelengths")
        return {"spectrum": (wl, vals)}
    if isinstance(v, list) and grid is not None and len(v) == len(grid) and len(v) != 3:
        return {"spectrum": (grid, node.array((len(grid),)))}
    return {"rgb": node.array((3,))}


def _reflectance_grid(spectra: _Json) -> np.ndarray | None:
    if not spectra.has("reflectance_wavelengths_nm"):
        return None
    g = spectra["reflectance_wavelengths_nm"]
    start, stop, step = (g[k].number() for k in ("start", "stop", "step"))
    if step <= 0 or stop <= start:
        raise g.err("expected start < stop and step > 0")
    n = int(round((stop - start) / step)) + 1
    return start + step * np.arange(n)


def _load_json(text: str, file: str, *, measured_fixups: bool = False) -> SceneDescription:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise SceneError(f"{file}:{e.lineno}:{e.colno}: malformed JSON: {e.msg}") from None
    root = _Json(data, "", file)
    if not isinstance(data, dict):
        raise root.err("the top level must be an object")
    camera, res = _json_camera(root["camera"])
    film = _json_film(root, res)
    spectra = root["spectra"] if root.has("spectra") else None
    grid = _reflectance_grid(spectra) if spectra is not None else None

    materials: list[Material] = []
    index: dict[str, int] = {}
    if root.has("materials"):
        for name, m in root["materials"].items():
            kind = (
                _json_material_type(m["type"].string(), m["type"]) if m.has("type") else "diffuse"
            )
            params = {}
            for key, val in m.items():
                if key == "type":
                    continue
                pname = key.removesuffix("_linear_srgb").removesuffix("_spectrum")
                params[pname] = _json_spectrum(val, spectra, grid)
            two = bool(m["two_sided"].value) if m.has("two_sided") else False
            index[name] = len(materials)
            materials.append(Material(kind, params, two_sided=two, name=name))

    shapes: list[_Shape] = []
    for s in root["shapes"].list():
        name = s["name"].string() if s.has("name") else s.path
        mname = s["material"].string()
        if mname not in index:
            # a material defined only by a reflectance spectrum in "spectra" (measured data)
            if spectra is not None and spectra.has(mname):
                index[mname] = len(materials)
                refl = _json_spectrum(spectra[mname], None, grid)
                materials.append(Material("diffuse", {"reflectance": refl}, name=mname))
            else:
                raise s["material"].err(f"unknown material {mname!r}")
        if s.has("quads"):
            quads = s["quads"].array((-1, 4, 3))
            v = quads.reshape(-1, 3)
            base = 4 * np.arange(len(quads))[:, None]
            f = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]], axis=1).reshape(-1, 3)
        else:
            v = s["vertices"].array((-1, 3))
            f = s["faces"].array((-1, 3), dtype=np.int64)
        emitter = None
        if s.has("emitter"):
            e = s["emitter"]
            if isinstance(e.value, dict):
                if e.has("radiance_linear_srgb"):
                    rad = {"rgb": e["radiance_linear_srgb"].array((3,))}
                else:
                    rad = _json_spectrum(e["radiance"], spectra, None)
                two = "two-sided" in str(e.value.get("type", "")).lower()
            else:
                rad = _json_spectrum(e, spectra, None)
                two = False
            emitter = {"radiance": rad, "two_sided": two}
        shapes.append(_Shape(name, v, f, index[mname], emitter, where=f"{file}: shape '{name}'"))

    if measured_fixups:
        _orient_measured(shapes)
    integ = root["integrator"] if root.has("integrator") else None
    max_depth, rr = 8, 5
    if integ is not None:
        if integ.has("max_depth"):
            max_depth = integ["max_depth"].integer(minimum=1)
        if integ.has("russian_roulette_from_depth"):
            rr = integ["russian_roulette_from_depth"].integer(minimum=1)
    unit = root["units"].value if root.has("units") else "scene units"
    if isinstance(unit, dict):
        unit = str(unit.get("length", "scene units"))
    unit = str(unit).split(";")[0].strip()
    return _assemble(
        shapes,
        materials,
        camera,
        film,
        max_depth=max_depth,
        rr_depth=rr,
        unit=str(unit),
        source=file,
    )


def _orient_measured(shapes: list[_Shape]) -> None:
    """Re-orient the measured Cornell box quads and lower its light (see the module docstring)."""
    allv = np.concatenate([s.vertices for s in shapes])
    room_centre = 0.5 * (allv.min(0) + allv.max(0))
    for s in shapes:
        v = np.asarray(s.vertices, dtype=np.float64)
        f = np.asarray(s.faces)
        n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        tri_centre = v[f].mean(axis=1)
        if len(f) <= 2:  # one quad: face the room's interior
            want = room_centre - tri_centre
        else:  # a block: face away from its own centroid
            want = tri_centre - v.mean(axis=0)
        flip = np.sum(n * want, axis=1) < 0
        s.faces = np.where(flip[:, None], f[:, [0, 2, 1]], f)
        if s.emitter is not None:
            v = v.copy()
            v[:, 1] -= MEASURED_LIGHT_OFFSET_MM
            s.vertices = v


# ---------------------------------------------------------------------------------------------
# Entry point


def _read_text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FileNotFoundError(f"scene file not found: {path}") from None
    except UnicodeDecodeError as e:
        raise SceneError(f"{path}: not UTF-8 text ({e.reason} at byte {e.start}).") from None


def load_scene(name_or_path, *, params: dict | None = None) -> SceneDescription:
    """Load a built-in scene by name, or a scene file by path.

    **Arguments:**

    - `name_or_path`: `"cornell-box"` or `"cornell-box-measured"` (built-ins, see the module
        docstring of `radiometria.render._scene`), or a path to a `.json` scene (the schema of
        the built-in files) or a Mitsuba 3 `.xml` scene (the subset of `load_mitsuba_xml`).
        [name or path]
    - `params`: for `.xml` files, values for `$name` substitutions (override `<default>`).

    **Returns:**

    A `SceneDescription`.

    **Raises:**

    `FileNotFoundError` for a missing file; `SceneError` (a `ValueError`) naming the file and
    the line (XML, malformed JSON) or the field (JSON) for an invalid one; `ValueError`
    listing the built-in names for an unknown name without a file suffix.

    !!! note "Thesis"
        Ch. 8 (scenes for light transport); the Cornell box of `Goral1984`, as built by
        Mitsuba 3 (`Jakob2022`).
    """
    if isinstance(name_or_path, str) and name_or_path in BUILTIN_SCENES:
        fname = BUILTIN_SCENES[name_or_path]
        text = resources.files("radiometria.render").joinpath("data", fname).read_text("utf-8")
        scene = _load_json(text, fname, measured_fixups=name_or_path == "cornell-box-measured")
        return dataclasses.replace(scene, source=name_or_path)
    path = Path(name_or_path)
    suffix = path.suffix.lower()
    if suffix == ".json":
        return _load_json(_read_text(path), str(path))
    if suffix == ".xml":
        from ._loaders import load_mitsuba_xml

        return load_mitsuba_xml(path, params=params)
    raise ValueError(
        f"Unknown scene {str(name_or_path)!r}: expected a built-in name "
        f"({', '.join(map(repr, BUILTIN_SCENES))}) or a path ending in .json or .xml."
    )
