"""The JSON scene format of the built-in scenes (thesis ch. 8).

The schema is that of `data/cornell_box.json` (Mitsuba 3's `cornell_box()` as world-space
triangles) and `data/cornell_box_measured.json` (the Cornell measurements): a camera, a film,
materials by name (`type` `"lambertian"` or a BSDF plugin name; spectral values as linear sRGB
lists, `{wavelengths_nm, values}` objects, or names of entries in `spectra`), shapes as
triangles or quads with a material and an optional emitter, and an integrator. Every error
names the file and the JSON path of the field.
"""

import json
import math

import numpy as np

from ...radiometry import PiecewiseLinearSpectrum
from .._registry import MATERIALS
from .._spectral import LinearRGB, SpectralValue
from ._description import (
    FOV_AXES,
    CameraDescription,
    FilmDescription,
    Material,
    SceneDescription,
    SceneError,
    ShapeDescription,
    assemble,
    check_spectral_values,
    look_at_matrix,
)
from ._measured import orient_measured

__all__ = ["load_json"]


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
        except (TypeError, ValueError, OverflowError):
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
        if not abs(np.linalg.det(m[:3, :3])) > 1e-12:
            raise cam["to_world"].err("degenerate camera transform: its 3x3 part is singular")
    else:
        key_o, key_d = (
            ("position", "direction") if cam.has("position") else ("origin", "looks_towards")
        )
        o = cam[key_o].array((3,))
        try:
            m = look_at_matrix(o, o + cam[key_d].array((3,)), cam["up"].array((3,)))
        except ValueError as e:
            raise cam.err(f"degenerate camera ({key_o}, {key_d}, up): {e}") from None
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
    if word in MATERIALS:
        return word
    raise node.err(f"unknown material type {text!r}; valid: 'lambertian', {tuple(MATERIALS)}")


def _json_spectrum(node: _Json, spectra: _Json | None, grid: np.ndarray | None) -> SpectralValue:
    """A spectral value: an rgb list, a {wavelengths_nm, values} object, or a name in `spectra`;
    its values must be finite and >= 0 (the error names the file and the field)."""
    value = _parse_json_spectrum(node, spectra, grid)
    samples = value.rgb if isinstance(value, LinearRGB) else value.values
    check_spectral_values(samples, f"{node.file}: field '{node.path}'")
    return value


def _parse_json_spectrum(
    node: _Json, spectra: _Json | None, grid: np.ndarray | None
) -> SpectralValue:
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
        return PiecewiseLinearSpectrum(wl, vals)
    if isinstance(v, list) and grid is not None and len(v) == len(grid) and len(v) != 3:
        return PiecewiseLinearSpectrum(grid, node.array((len(grid),)))
    return LinearRGB(node.array((3,)))


def _reflectance_grid(spectra: _Json) -> np.ndarray | None:
    if not spectra.has("reflectance_wavelengths_nm"):
        return None
    g = spectra["reflectance_wavelengths_nm"]
    start, stop, step = (g[k].number() for k in ("start", "stop", "step"))
    if step <= 0 or stop <= start:
        raise g.err("expected start < stop and step > 0")
    n = int(round((stop - start) / step)) + 1
    return start + step * np.arange(n)


def load_json(text: str, file: str, *, measured_fixups: bool = False) -> SceneDescription:
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
                if key in ("type", "two_sided"):
                    continue
                pname = key.removesuffix("_linear_srgb").removesuffix("_spectrum")
                params[pname] = _json_spectrum(val, spectra, grid)
            two = False
            if m.has("two_sided"):
                two = m["two_sided"].value
                if not isinstance(two, bool):
                    raise m["two_sided"].err(f"must be true or false, got {two!r}")
            index[name] = len(materials)
            materials.append(Material(kind, params, two_sided=two, name=name))

    shapes: list[ShapeDescription] = []
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
                    rad = _json_spectrum(e["radiance_linear_srgb"], None, None)
                else:
                    rad = _json_spectrum(e["radiance"], spectra, None)
                two = "two-sided" in str(e.value.get("type", "")).lower()
            else:
                rad = _json_spectrum(e, spectra, None)
                two = False
            emitter = {"radiance": rad, "two_sided": two}
        shapes.append(
            ShapeDescription(name, v, f, index[mname], emitter, where=f"{file}: shape '{name}'")
        )

    if measured_fixups:
        orient_measured(shapes)
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
    return assemble(
        shapes,
        materials,
        camera,
        film,
        max_depth=max_depth,
        rr_depth=rr,
        unit=str(unit),
        source=file,
    )
