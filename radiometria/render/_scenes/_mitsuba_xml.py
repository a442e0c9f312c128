"""A Mitsuba 3 XML scene subset (thesis ch. 8).

`load_mitsuba_xml` reads the part of Mitsuba 3's scene format that the renderer can represent,
and rejects everything else with an error that names the file, the line and the tag:

- `scene`: the `version` attribute; `<default name value>` (a value the caller passes,
  `params=` or `radiometria render -D name=value`, wins) and `$name` substitution in every
  attribute of every element; `<path value>` (a search folder, relative to the file that
  names it); `<include filename>` (an XML file whose `<scene>` children are read in its
  place; a cycle is an error that lists the files); `id` on any object (a second use of an
  id is an error) and `<ref id>` where a BSDF goes (a shape, `twosided`).
- file names (meshes, spectra, includes) resolve against the folder of the file that names
  them, then the `<path>` folders (the latest first), then the scene file's folder.
- `shape`: `obj`, `ply` (`filename`; vertex normals and uvs kept, `flip_tex_coords` for
  OBJ; a PLY file's other properties become mesh attributes with Mitsuba's names:
  `_mesh_files._ply_attributes`), `serialized` (`filename`, `shape_index`; vertex colours
  become the attribute `vertex_color`), `rectangle`, `disk`, `cube`, `cylinder`
  (`radius`, `p0`, `p1`), `sphere` (`center`, `radius`), tessellated with Mitsuba's
  parametrisation as described in `radiometria.render._scenes._shapes` (a sphere that does
  not emit is then intersected exactly: `compile_scene`); `to_world`,
  `flip_normals` on all, `face_normals` on meshes, cylinders and spheres (without it, a mesh
  without vertex normals gets Mitsuba's angle-weighted ones); one `bsdf` (inline or `ref`)
  and one `area` emitter. `shapegroup` (with an `id`, at the top level, shapes without
  emitters) and `instance` (one `ref` to a group and a `to_world`) are flattened into the
  merged mesh.
- `transform`: `matrix` (16 values, row-major), `translate`, `rotate` (axis and `angle` in
  degrees), `scale`, `lookat` (`origin`, `target`, `up`), applied in document order.
- `bsdf`: every plugin of `radiometria.render._registry.MATERIALS` (`diffuse`, `roughdiffuse`,
  `conductor`, `roughconductor`, `dielectric`, `roughdielectric`, `plastic`, `roughplastic`,
  `thindielectric`, `null`, `principled`, `principledthin`, ...) with the parameters it
  declares, and `twosided` (one nested BSDF); an `id` makes it referable by `ref`. Composites
  nest other BSDFs (inline `<bsdf>` or `<ref id>`, in order): `blendbsdf` (two, and a `weight`,
  a number or a texture), `mask` (one, `opacity`, default 0.5; Mitsuba's `twosided` may not wrap
  it, nor a blend with a transmitting child), `normalmap` (one, a `normalmap` bitmap, give it
  `raw=true`) and `bumpmap` (one, a nested unnamed height `<texture>`, `scale`); the last two
  take `flip_invalid_normals` and `use_shadowing_function` (default true, as Mitsuba 3.9).
- `emitter`: `area` inside a shape; `radiance` as `rgb`, `spectrum` (`value="v"` or
  `"l1:v1, l2:v2, ..."` in nm) or blackbody (`<spectrum type="blackbody">` with
  `temperature` and optional `scale`, or Mitsuba 0.6's `<blackbody temperature=...>`).
  Outside shapes: `point`, `spot` (with a bitmap `texture` projected over its cone, as
  Mitsuba), `directional`, `constant`, `envmap`, `projector` (`irradiance` a spectrum, bitmap
  or checkerboard, `scale`, `fov`/`fov_axis` or `focal_length`, a rigid `to_world`).
- Textures (`_textures_xml.TEXTURED_PARAMETERS`): `diffuse` `reflectance`; `plastic` and
  `roughplastic` `diffuse_reflectance`, `specular_reflectance`; `conductor` and
  `roughconductor` `specular_reflectance`, `eta`, `k`; `roughconductor` and
  `roughdielectric` `alpha`, `alpha_u`, `alpha_v`; `dielectric`, `roughdielectric` and
  `thindielectric` `specular_reflectance`, `specular_transmittance`; `blendbsdf` `weight`;
  `mask` `opacity`; `normalmap`, `bumpmap`; `spot` `texture`; `projector` `irradiance`;
  `principled` and `principledthin` `base_color` and every scalar Mitsuba reads as a
  texture (`roughness`, `metallic`, `spec_trans`, `diff_trans`, ...; a thin sheet's `eta`
  too, not the principled `eta` or `specular`).
  Each takes a `bitmap` or `checkerboard`; BSDF parameters also a `mesh_attribute` (`name`
  `vertex_<name>` or `face_<name>`, `scale`). Scalar parameters (roughness, weight, opacity)
  use the texels' luminance; Mitsuba's `roughplastic` `alpha` is a number only (its tables
  depend on it).
- `sensor`: `perspective` with `fov` and `fov_axis`, or `focal_length` (35 mm equivalent,
  diagonal, as Mitsuba), `to_world`, `near_clip`, `far_clip`; `thinlens` with those and
  `aperture_radius` (required), `focus_distance`; `orthographic` (`to_world`, whose scale sets
  the imaged extent, `near_clip`, `far_clip`); nested `film` and `sampler`.
- `film`: `hdrfilm` `width`, `height` (other options ignored) and an `rfilter`: `box`,
  `tent`, `gaussian`, `mitchell`, `catmullrom` or `lanczos` with its parameters.
- `sampler`: a name of `radiometria.render._registry.SAMPLERS`: `independent`, or Mitsuba's
  stratified and low-discrepancy samplers `stratified`, `multijitter`, `ldsampler`, `sobol`,
  all rendered with padded Owen-scrambled Sobol points (`OwenSobol`, stratified in every
  elementary interval); `sample_count` becomes the scene's `spp` and `seed` its `seed`.
- `integrator`: every plugin of `radiometria.render._registry.INTEGRATORS`: `path` with
  `max_depth` (-1 = unbounded), `rr_depth`, `hide_emitters` (ignored); `direct`; `moment`
  (Mitsuba's wrapper that adds the moments of its one nested integrator to the film) renders
  its nested integrator.

Textures and other plugins are not supported.
"""

import dataclasses
import math
import xml.parsers.expat
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...camera import fov_from_focal_length_deg
from ...radiometry import AbstractSpectrum, BlackbodySpectrum, PiecewiseLinearSpectrum
from .._lights import read_envmap
from .._registry import CAMERAS, INTEGRATORS, LIGHTS, MATERIALS, SAMPLERS
from .._spectral import LinearRGB, SpectralValue
from . import _shapes
from ._description import (
    CameraDescription,
    FilmDescription,
    LightDescription,
    Material,
    SceneDescription,
    SceneError,
    ShapeDescription,
    assemble,
    check_spectral_values,
    look_at_matrix,
    read_scene_text,
)
from ._media_xml import extract_media
from ._mesh_files import read_mesh
from ._serialized import read_serialized
from ._shapes import ShapeMesh
from ._textures_xml import texture_property, texture_ref_properties, texture_spec

__all__ = ["load_mitsuba_xml"]


# ---------------------------------------------------------------------------------------------
# A small XML tree with line numbers (expat reports the line of each start tag)


@dataclass
class _Node:
    tag: str
    attrib: dict
    line: int
    children: list = field(default_factory=list)
    file: str = ""  # the file the element is in (the scene file or an included one)


def _parse_xml(text: str, file: str) -> _Node:
    parser = xml.parsers.expat.ParserCreate()
    stack: list[_Node] = []
    root: list[_Node] = []

    def start(tag, attrib):
        node = _Node(tag, dict(attrib), parser.CurrentLineNumber, file=file)
        if stack:
            stack[-1].children.append(node)
        else:
            root.append(node)
        stack.append(node)

    def end(tag):
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(text, True)
    except xml.parsers.expat.ExpatError as e:
        msg = xml.parsers.expat.ErrorString(e.code)
        raise SceneError(f"{file}:{e.lineno}:{e.offset}: malformed XML: {msg}.") from None
    return root[0]


# ---------------------------------------------------------------------------------------------
# Value parsing


class _Ctx:
    def __init__(self, file: str, base: Path, params: dict):
        self.file, self.base, self.params = file, base, params
        self.refs: dict[str, tuple[_Node, object]] = {}
        self.ids: dict[str, _Node] = {}  # every id in the scene, for duplicates
        self.search: list[Path] = []  # <path> folders, the latest first

    def err(self, node: _Node, msg: str) -> SceneError:
        name = f" name='{node.attrib['name']}'" if "name" in node.attrib else ""
        return SceneError(f"{node.file or self.file}:{node.line}: <{node.tag}{name}>: {msg}")

    def resolve(self, node: _Node, filename: str) -> Path:
        """A file a scene names: absolute, or relative to the folder of the file that names
        it, then to the `<path>` folders (the latest first), then to the scene file's folder.
        A name found nowhere resolves against the naming file's folder (so that the error
        about the missing file names that path)."""
        path = Path(filename)
        if path.is_absolute():
            return path
        own = Path(node.file).parent if node.file else self.base
        for folder in (own, *self.search, self.base):
            if (folder / path).exists():
                return folder / path
        return own / path

    def attr(self, node: _Node, key: str, default=None) -> str:
        if key not in node.attrib:
            if default is not None:
                return default
            raise self.err(node, f"missing attribute '{key}'")
        return self.subst(node, node.attrib[key])

    def subst(self, node: _Node, value: str) -> str:
        if "$" not in value:
            return value
        out = value
        for name in sorted(self.params, key=len, reverse=True):
            out = out.replace("$" + name, str(self.params[name]))
        if "$" in out:
            raise self.err(node, f"no value for the parameter in {value!r} (add a <default>)")
        return out

    def floats(self, node: _Node, text: str, n: int | None = None) -> np.ndarray:
        try:
            vals = np.array([float(x) for x in text.replace(",", " ").split()], dtype=np.float64)
        except ValueError:
            raise self.err(node, f"expected numbers, got {text!r}") from None
        if n is not None and vals.size != n:
            raise self.err(node, f"expected {n} numbers, got {vals.size} in {text!r}")
        if not np.all(np.isfinite(vals)):
            raise self.err(node, f"non-finite number in {text!r}")
        return vals


def _vec3(ctx: _Ctx, node: _Node, default: float = 0.0) -> np.ndarray:
    """`value="x, y, z"` (or one number), or `x`, `y`, `z` attributes."""
    if "value" in node.attrib:
        v = ctx.floats(node, ctx.attr(node, "value"))
        if v.size == 1:
            return np.repeat(v, 3)
        if v.size != 3:
            raise ctx.err(node, f"expected 1 or 3 numbers, got {v.size}")
        return v
    return np.array([float(ctx.floats(node, ctx.attr(node, k, str(default)), 1)[0]) for k in "xyz"])


def _rotation(axis: np.ndarray, angle_deg: float) -> np.ndarray:
    big = np.max(np.abs(axis))
    if big == 0:
        raise ValueError("zero rotation axis")
    axis = axis / big  # scaled first, so that the norm cannot overflow
    x, y, z = axis / np.linalg.norm(axis)
    a = math.radians(angle_deg)
    c, s = math.cos(a), math.sin(a)
    m = np.eye(4)
    m[:3, :3] = [
        [c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
        [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
        [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)],
    ]
    return m


def _transform(ctx: _Ctx, node: _Node) -> np.ndarray:
    m = np.eye(4)
    for op in node.children:
        t = np.eye(4)
        if op.tag == "matrix":
            t = ctx.floats(op, ctx.attr(op, "value"), 16).reshape(4, 4)
        elif op.tag == "translate":
            t[:3, 3] = _vec3(ctx, op, 0.0)
        elif op.tag == "scale":
            t[:3, :3] = np.diag(_vec3(ctx, op, 1.0))
        elif op.tag == "rotate":
            axis = _vec3(ctx, op, 0.0)
            angle = float(ctx.floats(op, ctx.attr(op, "angle"), 1)[0])
            try:
                t = _rotation(axis, angle)
            except ValueError:
                raise ctx.err(op, "the rotation axis is zero") from None
        elif op.tag == "lookat":
            try:
                t = look_at_matrix(
                    ctx.floats(op, ctx.attr(op, "origin"), 3),
                    ctx.floats(op, ctx.attr(op, "target"), 3),
                    ctx.floats(op, ctx.attr(op, "up", "0, 1, 0"), 3),
                )
            except ValueError as e:
                raise ctx.err(op, str(e)) from None
        else:
            raise ctx.err(op, f"unsupported transform element <{op.tag}> (line {op.line})")
        with np.errstate(over="ignore", invalid="ignore"):  # checked below
            m = t @ m
        if not np.all(np.isfinite(m)):
            raise ctx.err(op, "the transform overflows float64 (an absurd scale or translation)")
    return m


def _spectrum_value(ctx: _Ctx, node: _Node) -> SpectralValue:
    """rgb / spectrum / blackbody / float property -> a typed spectral value. Spectra (rgb,
    spectrum, blackbody) must be finite and >= 0: the error names the file, the line and the
    parameter. (A plain float may be negative, e.g. a principal point offset.)"""
    value = _parse_spectrum_value(ctx, node)
    if node.tag == "float":
        return value
    if isinstance(value, LinearRGB | float):
        samples = value.rgb if isinstance(value, LinearRGB) else value
    elif isinstance(value, PiecewiseLinearSpectrum):
        samples = value.values
    else:
        samples = value.scale
    where = f"{node.file or ctx.file}:{node.line}: parameter '{node.attrib.get('name', node.tag)}'"
    check_spectral_values(samples, where)
    return value


def _checked_spectrum(ctx: _Ctx, node: _Node, wl: np.ndarray, val: np.ndarray, what: str):
    """A `PiecewiseLinearSpectrum` of >= 2 strictly increasing wavelengths [nm]."""
    if len(wl) < 2 or np.any(np.diff(wl) <= 0):
        raise ctx.err(node, f"{what}: expected >= 2 strictly increasing wavelengths [nm]")
    if not (np.all(np.isfinite(wl)) and np.all(np.isfinite(val))):
        raise ctx.err(node, f"{what}: non-finite wavelength or value")
    return PiecewiseLinearSpectrum(wl, val)


def _tabulated_spectrum(ctx: _Ctx, node: _Node, kind: str) -> PiecewiseLinearSpectrum:
    """Mitsuba 3's `<spectrum type="regular">` (`wavelength_min`, `wavelength_max` [nm],
    `values` evenly spaced) and `type="irregular"` (`wavelengths` [nm], `values`)."""
    _only_children(ctx, node, {"float", "string"})
    props = {}
    for ch in node.children:
        props[ctx.attr(ch, "name")] = ctx.attr(ch, "value")
    names = {"regular": {"wavelength_min", "wavelength_max", "values"},
             "irregular": {"wavelengths", "values"}}[kind]  # fmt: skip
    if set(props) != names:
        raise ctx.err(
            node, f"a {kind!r} spectrum needs exactly the parameters {sorted(names)}, got "
            f"{sorted(props)}"
        )  # fmt: skip
    val = ctx.floats(node, props["values"])
    if kind == "regular":
        lo = float(ctx.floats(node, props["wavelength_min"], 1)[0])
        hi = float(ctx.floats(node, props["wavelength_max"], 1)[0])
        if not hi > lo:
            raise ctx.err(node, f"wavelength_max ({hi}) must exceed wavelength_min ({lo}) [nm]")
        wl = np.linspace(lo, hi, val.size)
    else:
        wl = ctx.floats(node, props["wavelengths"])
        if wl.size != val.size:
            raise ctx.err(node, f"{wl.size} wavelengths but {val.size} values")
    return _checked_spectrum(ctx, node, wl, val, f"{kind} spectrum")


def _spectrum_file(ctx: _Ctx, node: _Node) -> PiecewiseLinearSpectrum:
    """Mitsuba's spectrum file (`.spd`): lines `wavelength value` (nm, any unit), `#` starts
    a comment. Errors name the scene file and line and the spectrum file's line."""
    path = ctx.resolve(node, ctx.attr(node, "filename"))
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FileNotFoundError(
            f"{node.file or ctx.file}:{node.line}: spectrum file not found: {path}"
        ) from None
    except (OSError, UnicodeDecodeError) as e:
        raise ctx.err(node, f"cannot read spectrum file {path}: {e}") from None
    wl, val = [], []
    for number, line in enumerate(text.splitlines(), 1):
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue
        try:
            if len(fields) != 2:
                raise ValueError
            a, b = float(fields[0]), float(fields[1])
        except ValueError:
            raise ctx.err(
                node, f"spectrum file {path}, line {number}: expected 'wavelength value', got "
                f"{line.strip()[:80]!r}"
            ) from None  # fmt: skip
        wl.append(a)
        val.append(b)
    return _checked_spectrum(ctx, node, np.array(wl), np.array(val), f"spectrum file {path}")


def _parse_spectrum_value(ctx: _Ctx, node: _Node) -> SpectralValue:
    if node.tag == "rgb":
        text = ctx.attr(node, "value").strip()
        if text.startswith("#") and len(text) == 7:
            srgb = np.array([int(text[i : i + 2], 16) / 255.0 for i in (1, 3, 5)])
            lin = np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)
            return LinearRGB(lin)
        rgb = ctx.floats(node, text)
        if rgb.size not in (1, 3):
            raise ctx.err(node, f"expected 1 or 3 numbers, got {rgb.size} in {text!r}")
        return LinearRGB(np.broadcast_to(rgb, (3,)))  # one value: a grey, as Mitsuba reads it
    if node.tag == "float":
        return float(ctx.floats(node, ctx.attr(node, "value"), 1)[0])
    if node.tag == "blackbody":  # Mitsuba 0.6
        temp = ctx.attr(node, "temperature").strip().rstrip("Kk")
        scale = ctx.attr(node, "scale", "1")
        t = float(ctx.floats(node, temp, 1)[0])
        if t <= 0:
            raise ctx.err(node, f"temperature must be > 0 [K], got {t}")
        return BlackbodySpectrum(t, float(ctx.floats(node, scale, 1)[0]))
    if node.tag == "spectrum":
        kind = ctx.attr(node, "type", "")
        if kind == "blackbody":
            props = _properties(ctx, node, {"temperature", "scale"})
            t = props.get("temperature")
            if not isinstance(t, float) or t <= 0:
                raise ctx.err(node, "a blackbody spectrum needs a temperature > 0 [K]")
            scale = props.get("scale", 1.0)
            if not isinstance(scale, float):
                raise ctx.err(node, f"a blackbody scale must be a number, got {scale!r}")
            return BlackbodySpectrum(t, scale)
        if kind in ("regular", "irregular"):
            return _tabulated_spectrum(ctx, node, kind)
        if kind:
            raise ctx.err(
                node, f"unsupported spectrum type {kind!r} (line {node.line}); supported: "
                "'blackbody', 'regular', 'irregular'"
            )  # fmt: skip
        if "filename" in node.attrib:
            return _spectrum_file(ctx, node)
        text = ctx.attr(node, "value")
        if ":" not in text:
            return float(ctx.floats(node, text, 1)[0])
        pairs = [p.split(":") for p in text.replace(",", " ").split()]
        try:
            wl = np.array([float(a) for a, _ in pairs])
            val = np.array([float(b) for _, b in pairs])
        except ValueError:
            raise ctx.err(node, f"expected 'wavelength:value' pairs, got {text!r}") from None
        if len(wl) < 2 or np.any(np.diff(wl) <= 0):
            raise ctx.err(node, "expected >= 2 strictly increasing wavelengths [nm]")
        return PiecewiseLinearSpectrum(wl, val)
    if node.tag == "texture":
        raise ctx.err(node, f"textures are not supported (line {node.line})")
    raise ctx.err(node, f"expected a spectrum (rgb, spectrum, float), got <{node.tag}>")


_VALUE_TAGS = ("integer", "float", "boolean", "string", "rgb", "spectrum", "blackbody", "point",
               "vector", "transform", "texture")  # fmt: skip


def _properties(ctx: _Ctx, node: _Node, allowed: set[str]) -> dict:
    """Parse the property children of a plugin; nested objects are left to the caller."""
    out = {}
    for ch in node.children:
        if ch.tag not in _VALUE_TAGS:
            continue
        if ch.tag == "texture":  # a texture parameter (_textures_xml)
            name, out[name] = texture_property(ctx, ch, node, allowed, _properties)
            continue
        name = ctx.attr(ch, "name")
        if name not in allowed:
            raise ctx.err(ch, f"unsupported parameter '{name}' of <{node.tag} type="
                          f"'{node.attrib.get('type', '')}'> (line {ch.line}); supported: "
                          f"{sorted(allowed)}")  # fmt: skip
        if ch.tag == "integer":
            try:
                out[name] = int(ctx.attr(ch, "value"))
            except ValueError:
                raise ctx.err(ch, f"expected an integer, got {ch.attrib.get('value')!r}") from None
        elif ch.tag == "boolean":
            v = ctx.attr(ch, "value").strip().lower()
            if v not in ("true", "false"):
                raise ctx.err(ch, f"expected true or false, got {v!r}")
            out[name] = v == "true"
        elif ch.tag == "string":
            out[name] = ctx.attr(ch, "value")
        elif ch.tag in ("point", "vector"):
            out[name] = _vec3(ctx, ch)
        elif ch.tag == "transform":
            out[name] = _transform(ctx, ch)
        else:
            out[name] = _spectrum_value(ctx, ch)
        out[name] = _expected_type(ctx, ch, name, out[name])
    return out


_SPECTRAL = (LinearRGB, AbstractSpectrum, float)
_TYPES = {
    int: ("an <integer>", ("width", "height", "sample_count", "max_depth", "rr_depth", "seed",
                           "crop_offset_x", "crop_offset_y", "crop_width", "crop_height",
                           "emitter_samples", "bsdf_samples", "shading_samples")),
    float: ("a <float>", ("fov", "near_clip", "far_clip", "radius", "alpha", "alpha_u",
                          "alpha_v", "temperature", "stddev", "B", "C", "lobes",
                          "focus_distance", "aperture_radius", "principal_point_offset_x",
                          "principal_point_offset_y", "scale")),
    str: ("a <string>", ("fov_axis", "focal_length", "filename", "material", "distribution", "name",
                         "pixel_format", "component_format", "file_format")),
    bool: ("a <boolean>", ("flip_normals", "face_normals", "flip_tex_coords", "hide_emitters",
                           "sample_visible", "jitter", "compensate", "banner",
                           "sample_border")),
    np.ndarray: ("a <transform> (to_world) or a <point> (center)", ("to_world", "center")),
    _SPECTRAL: ("an <rgb>, <spectrum> or <float>", ("reflectance", "radiance", "eta", "k",
                                                     "specular_reflectance",
                                                     "specular_transmittance")),
    (str, *_SPECTRAL): ("a <string> or a spectrum", ("int_ior", "ext_ior")),
}  # fmt: skip
_EXPECTED = {name: (kind, what) for kind, (what, names) in _TYPES.items() for name in names}


def _expected_type(ctx: _Ctx, node: _Node, name: str, value):
    """A parameter's value has the kind its name calls for (an integer width, a float fov,
    a spectral reflectance...): else an error names the file, the line and the parameter."""
    if name not in _EXPECTED:
        return value
    kind, what = _EXPECTED[name]
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    ok = isinstance(value, kind) and not (kind in (int, float) and isinstance(value, bool))
    if ok and kind is np.ndarray:
        ok = value.shape == _SHAPES[name]
    if not ok:
        raise ctx.err(node, f"parameter '{name}' must be {what}, got <{node.tag}>")
    if kind is _SPECTRAL and isinstance(value, float):  # a grey spectrum given as a <float>
        check_spectral_values(value, f"{node.file or ctx.file}:{node.line}: parameter '{name}'")
    return value


_SHAPES = {"to_world": (4, 4), "center": (3,)}


# ---------------------------------------------------------------------------------------------
# Plugins

_FILTER_PARAMS = {
    "box": {"radius"},
    "tent": {"radius"},
    "gaussian": {"stddev", "radius"},
    "mitchell": {"B", "C", "radius"},
    "catmullrom": {"radius"},
    "lanczos": {"lobes", "radius"},
}
_FILTER_DEFAULTS = {
    "box": {"radius": 0.5},
    "tent": {"radius": 1.0},
    "gaussian": {"stddev": 0.5},
    "mitchell": {"B": 1 / 3, "C": 1 / 3, "radius": 2.0},
    "catmullrom": {"radius": 2.0},
    "lanczos": {"lobes": 3, "radius": 3.0},
}


def _only_children(ctx: _Ctx, node: _Node, allowed: set[str]) -> None:
    for ch in node.children:
        if ch.tag not in allowed and ch.tag not in _VALUE_TAGS:
            raise ctx.err(ch, f"unsupported tag <{ch.tag}> inside <{node.tag}> (line {ch.line})")


def _bsdf(ctx: _Ctx, node: _Node, materials: list, name: str = "") -> int:
    kind = ctx.attr(node, "type")
    name = node.attrib.get("id", name) or f"bsdf@{node.line}"
    if kind == "twosided":
        _only_children(ctx, node, {"bsdf", "ref"})
        inner = [c for c in node.children if c.tag in ("bsdf", "ref")]
        if len(inner) != 1:
            raise ctx.err(node, "a twosided BSDF with one nested <bsdf> or <ref> is supported")
        if [c for c in node.children if c.tag not in ("bsdf", "ref")]:
            raise ctx.err(node, "twosided takes no parameters here")
        if inner[0].tag == "ref":  # a two-sided copy; the referenced BSDF stays one-sided
            m = materials[_ref(ctx, inner[0], "bsdf")]
            materials.append(Material(m.type, m.params, two_sided=True, name=name))
            return len(materials) - 1
        idx = _bsdf(ctx, inner[0], materials, name)
        m = materials[idx]
        if m.type in _COMPOSITE:  # Mitsuba's twosided nests no transmitting BSDF
            try:
                MATERIALS[m.type].from_properties(m.params, two_sided=True, where="twosided")
            except ValueError as e:
                raise ctx.err(node, str(e).removeprefix("twosided: ")) from None
        materials[idx] = Material(m.type, m.params, two_sided=True, name=name)
        return idx
    if kind in _COMPOSITE:
        return _composite_bsdf(ctx, node, materials, kind, name)
    if kind not in MATERIALS:
        raise ctx.err(
            node, f"unsupported BSDF type '{kind}' (line {node.line}); supported: "
            f"{sorted([*MATERIALS, 'twosided'])}"
        )  # fmt: skip
    _only_children(ctx, node, {"ref"})
    params = _properties(ctx, node, set(MATERIALS[kind].PARAMETERS))
    params.update(texture_ref_properties(ctx, node, _ref))  # <ref name=... id=texture>
    if kind == "diffuse" and "reflectance" not in params:
        params["reflectance"] = 0.5
    materials.append(Material(kind, params, two_sided=False, name=name))
    return len(materials) - 1


# BSDFs with nested BSDFs: how many
_COMPOSITE = {"blendbsdf": 2, "mask": 1, "normalmap": 1, "bumpmap": 1}


def _composite_bsdf(ctx: _Ctx, node: _Node, materials: list, kind: str, name: str) -> int:
    """`blendbsdf` (two nested BSDFs, `weight`) or `mask` (one nested BSDF, `opacity`): the
    nested BSDFs (inline, or `<ref id>` to a BSDF) become plugins now, passed to the composite
    plugin as `bsdf_0`, `bsdf_1` (`radiometria.render._materials._composite`)."""
    _only_children(ctx, node, {"bsdf", "ref"})
    cls = MATERIALS[kind]
    scalar_names = set(cls.PARAMETERS) - {"bsdf_0", "bsdf_1"}
    # bumpmap's height texture is a nested <texture> (or <ref id>) without a name
    unnamed = [c for c in node.children if c.tag == "texture" and "name" not in c.attrib]
    if unnamed and kind != "bumpmap":
        raise ctx.err(unnamed[0], f"a <texture> inside '{kind}' needs a 'name'")
    named = [c for c in node.children if not any(c is u for u in unnamed)]
    params = _properties(ctx, dataclasses.replace(node, children=named), scalar_names)
    for ch in unnamed:
        if "texture" in params:
            raise ctx.err(ch, "a bumpmap takes one height texture")
        params["texture"] = texture_spec(ctx, ch, _properties)
    nested = []
    for ch in node.children:
        if ch.tag == "bsdf":
            idx = _bsdf(ctx, ch, materials)
            if idx != len(materials) - 1:  # pragma: no cover - _bsdf appends inline BSDFs
                raise ctx.err(ch, "internal error: a nested BSDF was not the last one parsed")
            nested.append((ch, materials.pop()))
        elif ch.tag == "ref":
            rid = ctx.attr(ch, "id")
            target = ctx.refs.get(rid, (None, None))[0]
            if target is not None and target.tag == "bsdf":
                nested.append((ch, materials[_ref(ctx, ch, "bsdf")]))
            elif kind == "bumpmap" and "name" not in ch.attrib:
                params["texture"] = _ref(ctx, ch, "texture")
            else:  # a texture parameter (weight, opacity)
                one = dataclasses.replace(node, children=[ch])
                params.update(texture_ref_properties(ctx, one, _ref))
    if len(nested) != _COMPOSITE[kind]:
        raise ctx.err(node, f"a '{kind}' BSDF needs {_COMPOSITE[kind]} nested <bsdf> or <ref> "
                      f"(line {node.line}), got {len(nested)}")  # fmt: skip
    for i, (ch, m) in enumerate(nested):
        if m.type not in MATERIALS:
            raise ctx.err(ch, f"unsupported BSDF type '{m.type}' nested in '{kind}'")
        where = f"{ch.file or ctx.file}:{ch.line}: nested BSDF {m.name!r}"
        try:
            params[f"bsdf_{i}"] = MATERIALS[m.type].from_properties(
                m.params, two_sided=m.two_sided, where=where
            )
        except (ValueError, TypeError) as e:
            raise ctx.err(ch, str(e)) from None
    where = f"{node.file or ctx.file}:{node.line}: <bsdf type='{kind}'>"
    try:  # check the parameters now, with the line (the scene compiles it again)
        cls.from_properties(params, where=where)
    except (ValueError, TypeError) as e:
        raise ctx.err(node, str(e).removeprefix(where + ": ")) from None
    materials.append(Material(kind, params, two_sided=False, name=name))
    return len(materials) - 1


def _ref(ctx: _Ctx, node: _Node, kind: str):
    """The object a `<ref id>` names, which must be a `kind` (e.g. `"bsdf"`) defined before."""
    _only_attributes(ctx, node, {"id", "name"})
    rid = ctx.attr(node, "id")
    if rid not in ctx.refs:
        if rid in ctx.ids:
            other = ctx.ids[rid]
            raise ctx.err(
                node, f"'{rid}' (the <{other.tag}> at {other.file}:{other.line}) cannot be "
                f"referenced here; a <{kind}> is needed, defined at the top level before its use"
            )  # fmt: skip
        raise ctx.err(node, f"unknown id '{rid}' (define it before its use)")
    ref_node, ref_value = ctx.refs[rid]
    if ref_node.tag != kind:
        raise ctx.err(node, f"'{rid}' is a <{ref_node.tag}>; a <{kind}> is needed here")
    return ref_value


def _plugin(ctx: _Ctx, node: _Node, registry: dict, what: str) -> tuple[str, dict]:
    """The plugin a tag names (a key of one of the renderer's registries) and its parameters,
    checked against the names the plugin declares."""
    kind = ctx.attr(node, "type")
    if kind not in registry:
        raise ctx.err(
            node, f"unsupported {what} type '{kind}' (line {node.line}); supported: "
            f"{sorted(registry)}"
        )  # fmt: skip
    _only_children(ctx, node, set())
    return kind, _properties(ctx, node, set(registry[kind].PARAMETERS))


def _grey_illuminant_floats(node: _Node, props: dict) -> dict:
    """An emitter's `<float>` radiance, intensity or irradiance is a grey illuminant (D65
    shaped, the given luminance), as Mitsuba 3 reads it (`texture_d65`: a float emits what
    `<rgb value="v, v, v">` emits), while `<spectrum value="v">` stays flat (equal energy)."""
    for ch in node.children:
        name = ch.attrib.get("name")
        if ch.tag == "float" and name in _EMISSION_PARAMS and isinstance(props.get(name), float):
            props[name] = LinearRGB(np.full(3, props[name]))
    return props


_EMISSION_PARAMS = ("radiance", "intensity", "irradiance")


def _emitter(ctx: _Ctx, node: _Node) -> dict:
    """An `area` emitter inside a shape (the shape's triangles emit)."""
    _, props = _plugin(ctx, node, {"area": LIGHTS["area"]}, "emitter (inside a <shape>)")
    if "radiance" not in props:
        raise ctx.err(node, "an area emitter needs a 'radiance'")
    _grey_illuminant_floats(node, props)
    return {"radiance": props["radiance"], "two_sided": False}


_DEFAULT_EMISSION = {
    "constant": "radiance",
    "point": "intensity",
    "spot": "intensity",
    "directional": "irradiance",
    "projector": "irradiance",
}


def _light(ctx: _Ctx, node: _Node) -> LightDescription:
    """An emitter outside a shape: `point`, `spot`, `directional`, `constant`, `envmap` with
    the parameters its plugin declares; an envmap's image is read here (`read_envmap`), so
    that a missing, non-equirectangular or invalid file is named with this line."""
    lights = {k: v for k, v in LIGHTS.items() if k != "area"}
    kind, props = _plugin(ctx, node, lights, "emitter (outside a <shape>)")
    _grey_illuminant_floats(node, props)
    where = f"{node.file or ctx.file}:{node.line}: <emitter type='{kind}'>"
    # Mitsuba's default emission is white light as an illuminant (its `texture_d65(name, 1)`:
    # D65 with Y = 1), not an equal-energy spectrum (a plain `1` would be one).
    default = _DEFAULT_EMISSION.get(kind)
    if default is not None and default not in props:
        props[default] = LinearRGB(np.ones(3))
    if kind == "envmap":
        if "filename" not in props:
            raise ctx.err(node, "an envmap emitter needs a 'filename'")
        path = ctx.resolve(node, props["filename"])
        try:
            props["data"] = read_envmap(path, f"{where} parameter 'filename'")
        except ValueError as e:
            raise SceneError(str(e)) from None
        props["filename"] = str(path)
        scale = props.get("scale", 1.0)
        if not (isinstance(scale, float) and np.isfinite(scale) and scale >= 0):
            raise ctx.err(node, f"parameter 'scale' must be a finite float >= 0, got {scale!r}")
    else:  # the plugin's own checks (angles, directions, transforms), with this line named
        try:
            LIGHTS[kind].from_properties([props], where=[where])
        except ValueError as e:
            raise SceneError(str(e)) from None
    return LightDescription(kind, props, name=node.attrib.get("id", f"{kind}@{node.line}"),
                            where=where)  # fmt: skip


_MESH = {"to_world", "flip_normals", "face_normals"}
_SHAPE_PARAMS = {
    "obj": _MESH | {"filename", "flip_tex_coords"},
    "ply": _MESH | {"filename"},
    "serialized": _MESH | {"filename", "shape_index"},
    "rectangle": {"to_world", "flip_normals"},
    "disk": {"to_world", "flip_normals"},
    "cube": {"to_world", "flip_normals"},
    "cylinder": _MESH | {"radius", "p0", "p1"},
    "sphere": _MESH | {"center", "radius"},
    "shapegroup": set(),
    "instance": {"to_world"},
}
_FLAT = ("rectangle", "disk")  # shapes at z = 0: their to_world needs rank 2, others 3


def _shape_mesh(ctx: _Ctx, node: _Node, kind: str, props: dict) -> ShapeMesh:
    """The object-space mesh of a shape (before `to_world`)."""
    loc = f"{node.file or ctx.file}:{node.line}: "
    if kind in ("obj", "ply", "serialized"):
        if "filename" not in props:
            raise ctx.err(node, f"a '{kind}' shape needs a 'filename'")
        path = ctx.resolve(node, props["filename"])
        if kind == "serialized":
            index = props.get("shape_index", 0)
            if index < 0:
                raise ctx.err(node, f"parameter 'shape_index' must be >= 0, got {index}")
            mesh, _ = read_serialized(path, loc, index)
        else:
            v, f, n, uv, attrs = read_mesh(path, loc, attributes=True)
            if uv is not None and kind == "obj" and props.get("flip_tex_coords", True):
                uv = np.stack([uv[:, 0], 1.0 - uv[:, 1]], axis=-1)  # Mitsuba's default
            mesh = ShapeMesh(v, f, n, uv, attrs)
        if mesh.normals is not None:  # zero-length file normals: Mitsuba's would be NaN
            length = np.linalg.norm(mesh.normals, axis=1, keepdims=True)
            if not np.all(length > 0):
                mesh.normals = None
            else:
                mesh.normals = mesh.normals / length
        if mesh.normals is None and not props.get("face_normals", False):
            mesh.normals = _shapes.vertex_normals(mesh.vertices, mesh.faces)
        return mesh
    if kind in ("cylinder", "sphere"):
        radius = props.get("radius", 1.0)
        if not isinstance(radius, float) or not radius > 0:
            raise ctx.err(node, f"parameter 'radius' must be a float > 0, got {radius!r}")
        if kind == "sphere":
            return _shapes.sphere(props.get("center", np.zeros(3)), radius)
        p0, p1 = props.get("p0", np.zeros(3)), props.get("p1", np.array([0.0, 0.0, 1.0]))
        if not np.linalg.norm(p1 - p0) > 0:
            raise ctx.err(node, f"parameters 'p0' and 'p1' must differ, got {p0.tolist()} twice")
        return _shapes.cylinder(radius, p0, p1)
    return {"rectangle": _shapes.rectangle, "disk": _shapes.disk, "cube": _shapes.cube}[kind]()


def _shape_list(
    ctx: _Ctx, node: _Node, materials: list, default_material: list
) -> list[ShapeDescription]:
    """The shapes a top-level `<shape>` adds: one, none for a `shapegroup` (kept for its
    instances) or the group's shapes under an `instance`'s `to_world`."""
    kind = ctx.attr(node, "type")
    groups = ctx.__dict__.setdefault("shape_groups", {})
    if kind == "shapegroup":
        _only_children(ctx, node, {"shape"})
        if "id" not in node.attrib:
            raise ctx.err(node, "a 'shapegroup' needs an 'id' (instances refer to it)")
        members = []
        for ch in node.children:
            if ctx.attr(ch, "type") in ("shapegroup", "instance"):
                raise ctx.err(ch, "a 'shapegroup' cannot hold a shapegroup or an instance")
            if any(sub.tag == "emitter" for sub in ch.children):
                raise ctx.err(ch, "shapes in a 'shapegroup' cannot be emitters (as in Mitsuba)")
            members.append(_shape(ctx, ch, materials, default_material))
        groups[node.attrib["id"]] = members
        return []
    if kind != "instance":
        return [_shape(ctx, node, materials, default_material)]
    _only_children(ctx, node, {"ref"})
    props = _properties(ctx, node, _SHAPE_PARAMS["instance"])
    refs = [ch for ch in node.children if ch.tag == "ref"]
    if len(refs) != 1:
        raise ctx.err(node, "an 'instance' needs exactly one <ref id> to a 'shapegroup'")
    gid = ctx.attr(refs[0], "id")
    if gid not in groups:
        raise ctx.err(refs[0], f"no 'shapegroup' with id '{gid}' before this line")
    m = props.get("to_world", np.eye(4))
    name = node.attrib.get("id", f"instance@{node.line}")
    out = []
    for sh in groups[gid]:
        mesh = ShapeMesh(sh.vertices, sh.faces, sh.normals, sh.uvs, sh.attributes, sh.sphere)
        try:
            mesh = _shapes.transform_mesh(mesh, m, dims=1)
        except ValueError as e:
            raise ctx.err(node, f"parameter 'to_world': {e}") from None
        out.append(dataclasses.replace(
            sh, name=f"{name}/{sh.name}", vertices=mesh.vertices, faces=mesh.faces,
            normals=mesh.normals, sphere=mesh.sphere,
            where=f"{node.file or ctx.file}:{node.line}: instance "
            f"'{name}' of '{gid}'",
        ))  # fmt: skip
    return out


def _shape(ctx: _Ctx, node: _Node, materials: list, default_material: list) -> ShapeDescription:
    kind = ctx.attr(node, "type")
    if kind not in _SHAPE_PARAMS or kind in ("shapegroup", "instance"):
        raise ctx.err(
            node, f"unsupported shape type '{kind}' (line {node.line}); supported: "
            f"{sorted(_SHAPE_PARAMS)} (shapegroup and instance at the top level only)"
        )  # fmt: skip
    _only_children(ctx, node, {"bsdf", "emitter", "ref"})
    props = _properties(ctx, node, _SHAPE_PARAMS[kind])
    where = f"{node.file or ctx.file}:{node.line}: shape '{node.attrib.get('id', kind)}'"
    mesh = _shape_mesh(ctx, node, kind, props)
    if props.get("face_normals", False):
        mesh.normals = None
    dims = 2 if kind in _FLAT else 3 if kind not in ("obj", "ply", "serialized") else 1
    try:
        mesh = _shapes.transform_mesh(
            mesh, props.get("to_world", np.eye(4)), flip_normals=props.get("flip_normals", False),
            dims=dims,
        )  # fmt: skip
    except ValueError as e:
        raise SceneError(f"{where}: parameter 'to_world': {e}") from None
    material = None
    emitter = None
    for ch in node.children:
        if ch.tag == "bsdf":
            if material is not None:
                raise ctx.err(ch, "a shape takes one BSDF")
            material = _bsdf(ctx, ch, materials)
        elif ch.tag == "ref":
            if material is not None:
                raise ctx.err(ch, "a shape takes one BSDF")
            material = _ref(ctx, ch, "bsdf")
        elif ch.tag == "emitter":
            if emitter is not None:
                raise ctx.err(ch, "a shape takes one emitter")
            emitter = _emitter(ctx, ch)
    if material is None and emitter is not None:  # Mitsuba: an emitter's default is black
        names = [m.name for m in materials]
        if "default-emitter" not in names:
            materials.append(Material("diffuse", {"reflectance": 0.0}, name="default-emitter"))
            names.append("default-emitter")
        material = names.index("default-emitter")
    if material is None:  # Mitsuba's default: diffuse, reflectance 0.5
        if not default_material:
            materials.append(Material("diffuse", {"reflectance": 0.5}, name="default"))
            default_material.append(len(materials) - 1)
        material = default_material[0]
    name = node.attrib.get("id", f"{kind}@{node.line}")
    return ShapeDescription(
        name, mesh.vertices, mesh.faces, material, emitter, where=where, normals=mesh.normals,
        uvs=mesh.uvs, attributes=mesh.attributes, sphere=mesh.sphere,
    )  # fmt: skip


_SENSOR_COMMON = {"to_world", "near_clip", "far_clip"}
_SENSOR_PARAMS = {
    "perspective": _SENSOR_COMMON | {"fov", "fov_axis", "focal_length", "focus_distance",
                                     "principal_point_offset_x", "principal_point_offset_y"},
    "thinlens": _SENSOR_COMMON | {"fov", "fov_axis", "focal_length", "focus_distance",
                                  "aperture_radius"},
    "orthographic": _SENSOR_COMMON,
}  # fmt: skip


def _sensor_lens(ctx: _Ctx, node: _Node, kind: str, props: dict) -> dict:
    """The `type` and lens fields of the `CameraDescription` of a sensor: a `thinlens` needs
    `aperture_radius` >= 0 (as in Mitsuba); its `focus_distance` (> 0) defaults to
    `far_clip`, Mitsuba's default."""
    if kind != "thinlens":
        return {"type": kind}
    if "aperture_radius" not in props:
        raise ctx.err(node, f"sensor 'thinlens' (line {node.line}) needs 'aperture_radius'")
    radius = float(props["aperture_radius"])
    focus = float(props.get("focus_distance", props.get("far_clip", 1e4)))
    if not (math.isfinite(radius) and radius >= 0.0):
        raise ctx.err(node, f"aperture_radius must be >= 0 [scene units], got {radius}")
    if not (math.isfinite(focus) and focus > 0.0):
        raise ctx.err(node, f"focus_distance must be > 0 [scene units], got {focus}")
    return {"type": kind, "aperture_radius": radius, "focus_distance": focus}


def _sensor(ctx: _Ctx, node: _Node):
    kind = ctx.attr(node, "type")
    if kind not in CAMERAS:
        raise ctx.err(
            node, f"unsupported sensor type '{kind}' (line {node.line}); supported: "
            f"{sorted(CAMERAS)}"
        )  # fmt: skip
    _only_children(ctx, node, {"film", "sampler"})
    props = _properties(ctx, node, _SENSOR_PARAMS[kind])
    lens = _sensor_lens(ctx, node, kind, props)
    # `focus_distance` of a `perspective` sensor is read and unused, as in Mitsuba 3 (only a
    # `thinlens` has a focal plane).
    if kind == "perspective":
        pp = tuple(float(props.get(f"principal_point_offset_{a}", 0.0)) for a in "xy")
        if not all(math.isfinite(v) for v in pp):
            raise ctx.err(node, f"principal_point_offset_x/y must be finite, got {pp}")
        lens["principal_point"] = pp
    to_world = props.get("to_world", np.eye(4))
    if not abs(np.linalg.det(to_world[:3, :3])) > 1e-12:
        raise ctx.err(node, "degenerate camera transform: its 3x3 part is singular")
    axis = props.get("fov_axis", "x")
    if axis not in ("x", "y", "diagonal", "smaller", "larger"):
        raise ctx.err(node, f"unknown fov_axis {axis!r}")
    if kind == "orthographic":  # no field of view: the to_world scale sets the extent
        fov, axis = 90.0, "x"
    elif "fov" in props:
        fov = props["fov"] if isinstance(props["fov"], float) else None
    else:
        f_mm = props.get("focal_length", "50mm").strip().removesuffix("mm")
        f_mm = float(ctx.floats(node, f_mm, 1)[0])
        if not (math.isfinite(f_mm) and f_mm > 0):
            raise ctx.err(node, f"focal_length must be > 0 [mm], got {f_mm}")
        fov = fov_from_focal_length_deg(f_mm)
        axis = "diagonal"
    if fov is None or not 0 < fov < 180:
        raise ctx.err(node, f"fov must be in (0, 180) degrees, got {fov}")
    camera = CameraDescription(
        **lens,
        to_world=to_world,
        fov_deg=float(fov),
        fov_axis=axis,
        near_clip=float(props.get("near_clip", 1e-2)),
        far_clip=float(props.get("far_clip", 1e4)),
    )
    film = FilmDescription(width=768, height=576)
    spp, sampler, seed = None, None, None  # None: the file names no sampler
    for ch in node.children:
        if ch.tag == "film":
            film = _film(ctx, ch)
        elif ch.tag == "sampler":
            _only_children(ctx, ch, set())
            sampler = ctx.attr(ch, "type")
            if sampler not in SAMPLERS:
                raise ctx.err(
                    ch, f"unsupported sampler type '{sampler}' (line {ch.line}); supported: "
                    f"{sorted(SAMPLERS)}"
                )  # fmt: skip
            sp = _properties(ctx, ch, {"sample_count", "seed", "jitter", "scramble_seed"})
            spp = sp.get("sample_count")
            if spp is not None and spp < 1:
                raise ctx.err(ch, f"sample_count must be >= 1, got {spp}")
            # Mitsuba's `seed` offsets the sampler's random sequence: here it is the render's
            # seed (`jax.random.key(seed)`) unless the caller gives one. `scramble_seed` (no
            # Mitsuba 3 sampler has it) would be silently dropped, so only 0 is accepted.
            seed = sp.get("seed")
            if seed is not None and not 0 <= seed < 2**31:
                raise ctx.err(ch, f"seed must be in [0, 2^31), got {seed}")
            if sp.get("scramble_seed", 0) != 0:
                raise ctx.err(
                    ch, f"parameter 'scramble_seed' = {sp['scramble_seed']} is not supported "
                    "(only 0); give the sampler's 'seed' instead"
                )  # fmt: skip
    return camera, film, spp, sampler, seed


def _film(ctx: _Ctx, node: _Node) -> FilmDescription:
    kind = ctx.attr(node, "type")
    if kind != "hdrfilm":
        raise ctx.err(node, f"unsupported film type '{kind}' (line {node.line}); only 'hdrfilm'")
    _only_children(ctx, node, {"rfilter"})
    props = _properties(
        ctx, node, {"width", "height", "pixel_format", "component_format", "file_format",
                    "crop_offset_x", "crop_offset_y", "crop_width", "crop_height",
                    "sample_border", "compensate", "banner"}
    )  # fmt: skip
    width, height = props.get("width", 768), props.get("height", 576)
    if width < 1 or height < 1:
        raise ctx.err(node, f"width and height must be >= 1 [px], got {width} x {height}")
    # A crop window (Mitsuba's defaults: the whole film) must lie inside the film.
    crop = (
        props.get("crop_offset_x", 0), props.get("crop_offset_y", 0),
        props.get("crop_width", width), props.get("crop_height", height),
    )  # fmt: skip
    if (
        crop[0] < 0
        or crop[1] < 0
        or crop[2] < 1
        or crop[3] < 1
        or (crop[0] + crop[2] > width or crop[1] + crop[3] > height)
    ):
        raise ctx.err(
            node, f"crop window {crop[2]} x {crop[3]} at ({crop[0]}, {crop[1]}) [px] does not "
            f"fit in the {width} x {height} film (offsets >= 0, sizes >= 1, offset + size <= "
            "film size)"
        )  # fmt: skip
    crop = None if crop == (0, 0, width, height) else crop
    kind_f, params = "gaussian", dict(_FILTER_DEFAULTS["gaussian"])
    for ch in node.children:
        if ch.tag == "rfilter":
            kind_f = ctx.attr(ch, "type")
            if kind_f not in _FILTER_PARAMS:
                raise ctx.err(ch, f"unsupported rfilter type '{kind_f}' (line {ch.line})")
            _only_children(ctx, ch, set())
            p = _properties(ctx, ch, _FILTER_PARAMS[kind_f])
            params = dict(_FILTER_DEFAULTS[kind_f])
            params.update(p)
    if kind_f == "gaussian" and "radius" not in params:
        params["radius"] = 4.0 * params["stddev"]
    return FilmDescription(
        width=width, height=height, filter=kind_f, filter_params=params, crop=crop
    )


# ---------------------------------------------------------------------------------------------
# Scene-level structure: <default>, <path>, <include>, $name substitution, ids

_MAX_INCLUDE_DEPTH = 32


def _collect(ctx: _Ctx, root: _Node, chain: tuple[Path, ...], out: list[_Node], cli: set):
    """Walk the top level of `root` in document order: record `<default>`s (a value given by
    the caller wins), add `<path>` folders, inline the children of `<include>`d files (their
    relative names resolve against their own folder), and append every other element to
    `out`."""
    for ch in root.children:
        if ch.tag == "default":
            _only_attributes(ctx, ch, {"name", "value"})
            name = ch.attrib.get("name")
            if not name or "value" not in ch.attrib:
                raise ctx.err(ch, "a <default> needs a 'name' and a 'value'")
            if name not in cli:
                ctx.params[name] = ch.attrib["value"]
        elif ch.tag == "path":
            _only_attributes(ctx, ch, {"value"})
            folder = Path(ctx.attr(ch, "value"))
            if not folder.is_absolute():
                folder = Path(ch.file).parent / folder
            if not folder.is_dir():
                raise ctx.err(ch, f"the search path {str(folder)!r} is not a folder")
            ctx.search.insert(0, folder)
        elif ch.tag == "include":
            _only_attributes(ctx, ch, {"filename"})
            target = ctx.resolve(ch, ctx.attr(ch, "filename"))
            key = target.resolve()
            if key in chain:
                names = " -> ".join(str(p) for p in (*chain[chain.index(key) :], key))
                raise ctx.err(ch, f"include cycle: {names}")
            if len(chain) > _MAX_INCLUDE_DEPTH:
                raise ctx.err(ch, f"includes nested deeper than {_MAX_INCLUDE_DEPTH} files")
            if not target.is_file():
                raise FileNotFoundError(f"{ch.file}:{ch.line}: <include>: no file {str(target)!r}")
            if target.suffix.lower() != ".xml":
                raise ctx.err(ch, f"only XML files can be included, got {str(target)!r}")
            sub = _parse_xml(read_scene_text(target), str(target))
            if sub.tag != "scene":
                raise ctx.err(sub, f"an included file's root must be <scene>, got <{sub.tag}>")
            _collect(ctx, sub, (*chain, key), out, cli)
        else:
            out.append(ch)


def _only_attributes(ctx: _Ctx, node: _Node, allowed: set[str]) -> None:
    for key in node.attrib:
        if key not in allowed:
            raise ctx.err(node, f"unknown attribute '{key}'; valid: {sorted(allowed)}")


def _substitute(ctx: _Ctx, node: _Node) -> None:
    """`$name` -> its value in every attribute of `node` and its descendants, and the ids
    recorded (a second element with one id is an error)."""
    node.attrib = {k: ctx.subst(node, v) for k, v in node.attrib.items()}
    if "id" in node.attrib and node.tag != "ref":
        rid = node.attrib["id"]
        if rid in ctx.ids:
            first = ctx.ids[rid]
            raise ctx.err(node, f"duplicate id '{rid}' (first at {first.file}:{first.line})")
        ctx.ids[rid] = node
    for ch in node.children:
        _substitute(ctx, ch)


def _integrator(ctx: _Ctx, node: _Node) -> tuple[str, dict]:
    """An `<integrator>`; a `moment` wrapper renders its one nested integrator (the moments
    themselves are an output of Mitsuba's film that this renderer does not produce)."""
    if ctx.attr(node, "type") == "moment":
        _only_children(ctx, node, {"integrator"})
        nested = [c for c in node.children if c.tag == "integrator"]
        if len(nested) != 1 or len(nested) != len(node.children):
            raise ctx.err(node, "a 'moment' integrator needs exactly one nested <integrator>")
        return _integrator(ctx, nested[0])
    kind, p = _plugin(ctx, node, INTEGRATORS, "integrator")
    where = f"{node.file or ctx.file}:{node.line}"
    try:
        INTEGRATORS[kind].from_properties(p, where=where)
    except (ValueError, TypeError) as e:
        # The plugin's own checks (`check_path_fields`: max_depth 0) may not name the file.
        raise (SceneError(str(e)) if where in str(e) else ctx.err(node, str(e))) from None
    return kind, p


def load_mitsuba_xml(path, *, params: dict | None = None) -> SceneDescription:
    """Load a Mitsuba 3 XML scene (the subset in the module docstring of
    `radiometria.render._scenes._mitsuba_xml`) into a `SceneDescription`.

    Meshes are transformed to world space and merged; each `bsdf` becomes a `Material` (a
    `ref` reuses the referenced one; a shape without one gets Mitsuba's default, diffuse 0.5);
    an `area` emitter becomes an `AreaEmitter` on its shape's triangles. Without a sensor, the
    camera is Mitsuba's default (identity `to_world`, 45 degrees) with a 768 x 576 film.

    **Arguments:**

    - `path`: the `.xml` file; relative mesh file names are relative to its folder. [path]
    - `params`: values for `$name` substitutions; they override the file's `<default>` tags.

    **Returns:**

    A `SceneDescription` (coordinates in the file's length unit).

    **Raises:**

    `FileNotFoundError` for a missing scene or mesh file; `SceneError` (a `ValueError`)
    naming the file and the line for malformed XML, an unsupported tag, plugin or parameter
    (its name is in the message), a bad value, a degenerate emitter triangle.

    !!! note "Thesis"
        Ch. 8 (scene description); Mitsuba 3's scene format (`Jakob2022`).
    """
    path = Path(path)
    text = read_scene_text(path)
    file = str(path)
    root = _parse_xml(text, file)
    given = {str(k): str(v) for k, v in (params or {}).items()}
    ctx = _Ctx(file, path.parent, dict(given))
    if root.tag != "scene":
        raise ctx.err(root, f"the root element must be <scene>, got <{root.tag}>")
    elements: list[_Node] = []
    _collect(ctx, root, (path.resolve(),), elements, set(given))
    for ch in elements:
        _substitute(ctx, ch)
    elements, media = extract_media(ctx, elements, properties=_properties, transform=_transform)
    materials: list[Material] = []
    default_material: list[int] = []
    shapes: list[ShapeDescription] = []
    lights: list[LightDescription] = []
    camera = CameraDescription(to_world=np.eye(4), fov_deg=45.0, fov_axis="x")
    film = FilmDescription(width=768, height=576)
    spp, sampler, seed = None, None, None  # None: the file names no sampler
    max_depth: int | None = None
    rr_depth = 5
    integrator = "path"
    integrator_params: tuple = ()
    for ch in elements:
        if ch.tag == "bsdf":
            idx = _bsdf(ctx, ch, materials)
            if "id" in ch.attrib:
                ctx.refs[ch.attrib["id"]] = (ch, idx)
        elif ch.tag == "shape":
            for sh in _shape_list(ctx, ch, materials, default_material):
                shapes.append(media.bind(ch, sh))
        elif ch.tag == "emitter":
            lights.append(_light(ctx, ch))
        elif ch.tag == "texture" and "id" in ch.attrib:  # used by <ref> (_textures_xml)
            ctx.refs[ch.attrib["id"]] = (ch, texture_spec(ctx, ch, _properties))
        elif ch.tag == "sensor":
            camera, film, spp, sampler, seed = _sensor(ctx, ch)
        elif ch.tag == "integrator":
            integrator, p = _integrator(ctx, ch)
            md = p.get("max_depth", -1)
            if md == 0 or md < -1:
                raise ctx.err(ch, f"max_depth must be -1 (unbounded) or >= 1, got {md}")
            max_depth = None if md == -1 else md
            rr_depth = p.get("rr_depth", 5)
            integrator_params = tuple(
                (k, v) for k, v in p.items() if k not in ("max_depth", "rr_depth")
            )
        else:
            what = f" type='{ch.attrib['type']}'" if "type" in ch.attrib else ""
            raise ctx.err(ch, f"unsupported tag <{ch.tag}{what}> at line {ch.line}")
    scene = assemble(
        shapes, materials, camera, film, max_depth=max_depth, rr_depth=rr_depth, spp=spp,
        integrator=integrator, unit="file units", source=file, lights=tuple(lights),
        **media.assemble_args(),
    )  # fmt: skip
    return dataclasses.replace(
        scene, sampler=sampler, seed=seed, integrator_params=integrator_params
    )
