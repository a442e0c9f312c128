"""Participating media in Mitsuba 3 XML scenes (thesis ch. 4 and 9).

`extract_media` takes every `<medium>` out of a parsed scene tree before the rest of the
loader sees it, and records where each one is bound:

- `<medium type="homogeneous" id=...>` with `sigma_t` and `albedo` (`rgb`, `spectrum` or
  `float`; an RGB `sigma_t` is upsampled as an unbounded spectrum, an RGB `albedo` as an
  albedo spectrum), `scale` (a `float`, default 1) and an optional `<phase type="isotropic">`
  or `<phase type="hg">` with `g` in (-1, 1); `sample_emitters` is accepted (next-event
  estimation always runs);
- `<medium type="heterogeneous">` with `<volume name="sigma_t" type="gridvolume">` (a Mitsuba
  `.vol` `filename`, read here by `_volume_files.read_vol`, optional `to_world`) or
  `type="constvolume"` (`value`), an `albedo` volume or spectral value, `scale` and a phase
  function;
- at the top level (referable by `id`), inside a `<shape>` as `name="interior"` or
  `name="exterior"` (or a `<ref name="interior" id=...>`), and inside the `<sensor>` (the
  camera's medium).

A shape with an interior but no exterior has a vacuum outside, and the other way round, as in
Mitsuba; a shape with neither bounds no medium (a ray crossing it stays in its medium). Bad
values (negative or non-finite coefficients, an albedo outside [0, 1], `g` outside (-1, 1))
raise `SceneError` naming the file, the line and the parameter.
"""

import dataclasses
from pathlib import Path

import numpy as np

from ...radiometry import PiecewiseLinearSpectrum
from .._spectral import LinearRGB
from ._description import MediumDescription, SceneError, ShapeDescription
from ._volume_files import read_vol

__all__ = ["MediaBinding", "extract_media"]

_MEDIUM_PARAMS = {
    "homogeneous": {"sigma_t", "albedo", "scale", "sample_emitters"},
    "heterogeneous": {"albedo", "scale", "sample_emitters"},
}
_PHASES = {"isotropic": set(), "hg": {"g"}}


@dataclasses.dataclass
class MediaBinding:
    """The media of a scene file and where they are bound (`extract_media`)."""

    media: list = dataclasses.field(default_factory=list)
    ids: dict = dataclasses.field(default_factory=dict)
    shape_sides: dict = dataclasses.field(default_factory=dict)  # id(shape node) -> (in, out)
    camera_medium: int = -1

    def bind(self, node, shape: ShapeDescription) -> ShapeDescription:
        """The shape with the interior/exterior media of its XML `node`."""
        if id(node) not in self.shape_sides:
            return shape
        interior, exterior = self.shape_sides[id(node)]
        return dataclasses.replace(shape, interior=interior, exterior=exterior)

    def assemble_args(self) -> dict:
        """Keyword arguments of `assemble` for the media."""
        return {"media": tuple(self.media), "camera_medium": self.camera_medium}


def _samples(value) -> np.ndarray:
    if isinstance(value, LinearRGB):
        return np.asarray(value.rgb, np.float64)
    if isinstance(value, PiecewiseLinearSpectrum):
        return np.asarray(value.values, np.float64)
    if isinstance(value, int | float) and not isinstance(value, bool):
        return np.asarray([value], np.float64)
    return np.asarray(getattr(value, "scale", np.nan), np.float64).reshape(-1)


def _check(ctx, node, name: str, value, lower: float, upper: float, open_: bool = False):
    v = _samples(value)
    bad = ~np.isfinite(v) | ((v <= lower) | (v >= upper) if open_ else (v < lower) | (v > upper))
    if np.any(bad):
        lb, ub = ("(", ")") if open_ else ("[", "]")
        raise SceneError(
            f"{ctx.file}:{node.line}: <medium> parameter '{name}' must be finite and in "
            f"{lb}{lower}, {upper}{ub}, got {v.tolist()}."
        )


def _child(node, name: str):
    for ch in node.children:
        if ch.attrib.get("name") == name:
            return ch
    return node


def _volume(ctx, node, properties, transform) -> dict:
    kind = ctx.attr(node, "type")
    if kind == "constvolume":
        props = properties(ctx, node, {"value"})
        if "value" not in props:
            raise ctx.err(node, "a constvolume needs a 'value'")
        return {"type": kind, "value": props["value"]}
    if kind == "gridvolume":
        props = properties(ctx, node, {"filename", "to_world", "filter_type", "raw"})
        if "filename" not in props:
            raise ctx.err(node, "a gridvolume needs a 'filename'")
        path = Path(props["filename"])
        path = path if path.is_absolute() else ctx.base / path
        where = f"{ctx.file}:{node.line}"
        out = {"type": kind, "filename": str(path), "where": where}
        out["data"] = read_vol(path, where=where)
        if "to_world" in props:
            out["to_world"] = props["to_world"]
        if props.get("filter_type", "trilinear") != "trilinear":
            raise ctx.err(node, "only filter_type 'trilinear' is supported")
        return out
    raise ctx.err(node, f"unsupported volume type '{kind}'; supported: constvolume, gridvolume")


def _medium(ctx, node, binding: MediaBinding, properties, transform) -> int:
    kind = ctx.attr(node, "type")
    if kind not in _MEDIUM_PARAMS:
        raise ctx.err(
            node, f"unsupported medium type '{kind}'; supported: {sorted(_MEDIUM_PARAMS)}"
        )
    for ch in node.children:
        if ch.tag not in ("phase", "volume", "rgb", "spectrum", "float", "boolean", "transform"):
            raise ctx.err(ch, f"unsupported tag <{ch.tag}> inside <medium> (line {ch.line})")
    params = properties(ctx, node, _MEDIUM_PARAMS[kind])
    params.pop("sample_emitters", None)
    for name in ("sigma_t", "albedo"):
        if name in params:
            _check(ctx, _child(node, name), name, params[name], 0.0, np.inf if name == "sigma_t"
                   else 1.0)  # fmt: skip
    scale = params.get("scale", 1.0)
    if not isinstance(scale, float):
        raise ctx.err(_child(node, "scale"), f"parameter 'scale' must be a <float>, got {scale!r}")
    _check(ctx, _child(node, "scale"), "scale", scale, 0.0, np.inf)
    g = 0.0
    for ch in node.children:
        if ch.tag == "phase":
            pk = ctx.attr(ch, "type")
            if pk not in _PHASES:
                raise ctx.err(ch, f"unsupported phase type '{pk}'; supported: {sorted(_PHASES)}")
            pp = properties(ctx, ch, _PHASES[pk])
            g = pp.get("g", 0.0)
            if not isinstance(g, float):
                raise ctx.err(ch, f"parameter 'g' must be a <float>, got {g!r}")
            _check(ctx, _child(ch, "g"), "g", g, -1.0, 1.0, open_=True)
        elif ch.tag == "volume":
            name = ctx.attr(ch, "name")
            if name not in ("sigma_t", "albedo") or kind != "heterogeneous":
                raise ctx.err(ch, f"unsupported <volume name='{name}'> in a {kind} medium")
            vol = _volume(ctx, ch, properties, transform)
            if vol["type"] == "constvolume":
                upper = np.inf if name == "sigma_t" else 1.0
                _check(ctx, _child(ch, "value"), name, vol["value"], 0.0, upper)
            params[name] = vol
    params["scale"] = scale
    params["g"] = g
    if kind == "homogeneous":
        params.setdefault("sigma_t", 1.0)
        params.setdefault("albedo", 0.75)
    else:
        if "sigma_t" not in params:
            raise ctx.err(node, "a heterogeneous medium needs a 'sigma_t' volume")
        params.setdefault("albedo", 0.75)
    name = node.attrib.get("id", f"medium@{node.line}")
    binding.media.append(MediumDescription(kind, params, name=name))
    return len(binding.media) - 1


def _resolve(ctx, node, binding, properties, transform) -> int:
    if node.tag == "medium":
        return _medium(ctx, node, binding, properties, transform)
    rid = ctx.attr(node, "id")
    if rid not in binding.ids:
        raise ctx.err(node, f"unknown medium id '{rid}' (define it before its use)")
    return binding.ids[rid]


def _is_medium_ref(ctx, node, binding) -> bool:
    return node.tag == "ref" and (
        node.attrib.get("name") in ("interior", "exterior") or node.attrib.get("id") in binding.ids
    )


def extract_media(ctx, elements: list, *, properties, transform) -> tuple[list, MediaBinding]:
    """Take the `<medium>` elements (and references to them) out of the top-level elements
    of a parsed Mitsuba XML scene and parse them (module docstring).

    **Arguments:**

    - `ctx`: the XML loader's context (file name, folder, `err`, `attr`).
    - `elements`: the scene's top-level nodes; shape and sensor nodes lose their media
        children in place.
    - `properties`, `transform`: the loader's parsers of plugin parameters and transforms.

    **Returns:**

    `(elements without the media, MediaBinding)` for the loader and `assemble`.
    """
    binding = MediaBinding()
    kept = []
    for ch in elements:
        if ch.tag == "medium":
            idx = _medium(ctx, ch, binding, properties, transform)
            if "id" in ch.attrib:
                binding.ids[ch.attrib["id"]] = idx
        else:
            kept.append(ch)
    for ch in kept:
        if ch.tag not in ("shape", "sensor"):
            continue
        children = []
        sides = {}
        for sub in ch.children:
            if sub.tag == "medium" or _is_medium_ref(ctx, sub, binding):
                idx = _resolve(ctx, sub, binding, properties, transform)
                if ch.tag == "sensor":
                    binding.camera_medium = idx
                    continue
                side = sub.attrib.get("name")
                if side not in ("interior", "exterior"):
                    raise ctx.err(sub, "a shape's medium needs name='interior' or 'exterior'")
                if side in sides:
                    raise ctx.err(sub, f"a shape takes one {side} medium")
                sides[side] = idx
            else:
                children.append(sub)
        ch.children = children
        if sides:
            binding.shape_sides[id(ch)] = (sides.get("interior", -1), sides.get("exterior", -1))
    return kept, binding
