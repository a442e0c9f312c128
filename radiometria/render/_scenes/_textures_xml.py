"""Mitsuba 3 XML textures: `<texture type="bitmap|checkerboard|mesh_attribute">` as a
parameter of a BSDF,
or at the top level with an `id` and used by `<ref name="..." id="..."/>` (thesis ch. 8).

The loader (`_mitsuba_xml`) hands texture elements here; a texture becomes a `TextureSpec`
(a bitmap's texels are read now, so that a bad image is reported with the scene file and
line), which the material plugin upsamples when the scene is compiled. Textures are accepted
where the renderer's plugins look them up at the hit's uv (`TEXTURED_PARAMETERS`); elsewhere
an error names the file, the line and the parameter.

- `bitmap`: `filename` (PNG, JPEG, BMP, TGA, TIFF, OpenEXR), `filter_type` (`bilinear`,
  `nearest`), `wrap_mode` (`repeat`, `mirror`, `clamp`), `raw` (no sRGB decoding of 8- and
  16-bit images), `to_uv`.
- `checkerboard`: `color0`, `color1` (spectra: `rgb`, `spectrum`, `float`), `to_uv`.
- `mesh_attribute`: `name` (`vertex_<name>` or `face_<name>`, an attribute of the shapes'
  meshes: PLY properties and serialized vertex colours), `scale`; for BSDF parameters only.
"""

from collections.abc import Callable

import numpy as np

from .._textures import TextureSpec, read_texture_image
from .._textures._bitmap import FILTER_TYPES, WRAP_MODES
from ._description import check_spectral_values

__all__ = ["TEXTURED_PARAMETERS", "texture_property", "texture_ref_properties", "texture_spec"]

# (plugin type, parameter) pairs whose value may be a texture.
TEXTURED_PARAMETERS = frozenset(
    {("diffuse", "reflectance"), ("blendbsdf", "weight"), ("mask", "opacity"),
     ("normalmap", "normalmap"), ("bumpmap", "texture"), ("spot", "texture"),
     ("area", "radiance"), ("projector", "irradiance"),
     ("conductor", "specular_reflectance"), ("conductor", "eta"), ("conductor", "k")}
    | {("roughconductor", n) for n in ("specular_reflectance", "alpha", "alpha_u", "alpha_v",
                                        "eta", "k")}
    | {("roughdielectric", n) for n in ("alpha", "alpha_u", "alpha_v")}
    | {(p, n) for p in ("dielectric", "roughdielectric", "thindielectric")
       for n in ("specular_reflectance", "specular_transmittance")}
    | {(p, n) for p in ("plastic", "roughplastic")
       for n in ("diffuse_reflectance", "specular_reflectance")}
    | {("principled", n) for n in ("base_color", "roughness", "anisotropic", "metallic",
                                   "spec_trans", "spec_tint", "sheen", "sheen_tint",
                                   "flatness", "clearcoat", "clearcoat_gloss")}
    | {("principledthin", n) for n in ("base_color", "roughness", "anisotropic", "spec_trans",
                                       "spec_tint", "sheen", "sheen_tint", "flatness",
                                       "diff_trans", "eta")}
)  # fmt: skip

_TEXTURE_PARAMETERS = {
    "bitmap": {"filename", "filter_type", "wrap_mode", "raw", "to_uv"},
    "checkerboard": {"color0", "color1", "to_uv"},
    "mesh_attribute": {"name", "scale"},
}
# Parameters whose textures are not looked up at hits through the hit's coordinates: a
# mesh_attribute texture cannot serve them.
_NOT_MESH_ATTRIBUTE = frozenset({("normalmap", "normalmap"), ("bumpmap", "texture")})


def _check_kind(ctx, ch, parent, name: str, spec: TextureSpec) -> TextureSpec:
    """`spec`, refused where its kind cannot serve the parameter: a mesh_attribute texture
    for emission (the emitters sample points by their own uv) or a bump or normal map."""
    kind = parent.attrib.get("type", "")
    if spec.type == "mesh_attribute" and (
        parent.tag != "bsdf" or (kind, name) in _NOT_MESH_ATTRIBUTE
    ):
        raise ctx.err(
            ch, f"a mesh_attribute texture is not supported for parameter '{name}' of "
            f"<{parent.tag} type='{kind}'> (line {ch.line}); it serves BSDF parameters "
            "(not emitters, bumpmap or normalmap)"
        )  # fmt: skip
    return spec


def _check_textured(ctx, ch, parent, name: str) -> None:
    kind = parent.attrib.get("type", "")
    if parent.tag not in ("bsdf", "emitter") or (kind, name) not in TEXTURED_PARAMETERS:
        where = f"<{parent.tag} type='{kind}'>"
        raise ctx.err(
            ch, f"a texture is not supported for parameter '{name}' of {where} (line "
            f"{ch.line}); textures are supported for: "
            f"{', '.join(f'{p} {n}' for p, n in sorted(TEXTURED_PARAMETERS))}"
        )  # fmt: skip


def texture_spec(ctx, node, properties: Callable) -> TextureSpec:
    """A `<texture>` element as a `TextureSpec`; `properties(ctx, node, allowed)` is the
    loader's parameter parser. A bitmap's image is read and checked here."""
    kind = ctx.attr(node, "type")
    if kind not in _TEXTURE_PARAMETERS:
        raise ctx.err(node, f"unsupported texture type '{kind}' (line {node.line}); supported: "
                      f"{sorted(_TEXTURE_PARAMETERS)}")  # fmt: skip
    for ch in node.children:
        if ch.tag in ("texture", "ref", "bsdf", "shape", "emitter"):
            raise ctx.err(ch, f"unsupported tag <{ch.tag}> inside a texture (line {ch.line})")
    p = properties(ctx, node, _TEXTURE_PARAMETERS[kind])
    where = f"{node.file or ctx.file}:{node.line}"
    to_uv = p.get("to_uv")
    if to_uv is not None and not np.all(np.isfinite(to_uv)):
        raise ctx.err(node, "to_uv must be finite")
    if kind == "mesh_attribute":
        attribute, scale = p.get("name"), p.get("scale", 1.0)
        if not isinstance(attribute, str) or not attribute.startswith(("vertex_", "face_")):
            raise ctx.err(node, f"a mesh_attribute texture needs a <string name='name'> that "
                          f"starts with 'vertex_' or 'face_', got {attribute!r}")  # fmt: skip
        if not isinstance(scale, float) or not np.isfinite(scale):
            raise ctx.err(node, f"parameter 'scale' must be a finite <float>, got {scale!r}")
        return TextureSpec("mesh_attribute", attribute=attribute, scale=scale, where=where)
    if kind == "checkerboard":
        colors = []
        for name, default in (("color0", 0.4), ("color1", 0.2)):
            value = p.get(name, default)
            if isinstance(value, str | bool | np.ndarray):
                raise ctx.err(node, f"'{name}' must be a spectrum (rgb, spectrum, float)")
            if isinstance(value, float):
                check_spectral_values(value, f"{where}: parameter '{name}'")
            colors.append(value)
        return TextureSpec("checkerboard", colors=tuple(colors), to_uv=to_uv, where=where)
    if "filename" not in p:
        raise ctx.err(node, "a bitmap texture needs a 'filename'")
    filter_type = p.get("filter_type", "bilinear")
    wrap_mode = p.get("wrap_mode", "repeat")
    raw = p.get("raw", False)
    for name, value, valid in (("filter_type", filter_type, FILTER_TYPES),
                               ("wrap_mode", wrap_mode, WRAP_MODES)):  # fmt: skip
        if value not in valid:
            raise ctx.err(node, f"{name} must be one of {list(valid)}, got {value!r}")
    if not isinstance(raw, bool):
        raise ctx.err(node, f"raw must be a <boolean>, got {raw!r}")
    path = ctx.resolve(node, p["filename"])
    try:
        rgb = read_texture_image(path, raw=raw)
    except FileNotFoundError as e:
        raise FileNotFoundError(f"{where}: <texture type='bitmap'>: {e}") from None
    except (OSError, ValueError) as e:  # TextureFileError and the EXR reader's errors
        raise ctx.err(node, str(e)) from None
    return TextureSpec(
        "bitmap", rgb=rgb, filter_type=filter_type, wrap_mode=wrap_mode, to_uv=to_uv, where=where
    )


def texture_property(ctx, ch, parent, allowed: set, properties: Callable) -> tuple[str, object]:
    """A `<texture name=...>` child of a plugin `parent`: its parameter name and
    `TextureSpec`, after checking that the plugin takes a texture there."""
    name = ctx.attr(ch, "name")
    if parent.tag == "texture":
        raise ctx.err(ch, f"nested textures are not supported (line {ch.line})")
    if name not in allowed:
        raise ctx.err(ch, f"unsupported parameter '{name}' of <{parent.tag} type="
                      f"'{parent.attrib.get('type', '')}'> (line {ch.line}); supported: "
                      f"{sorted(allowed)}")  # fmt: skip
    _check_textured(ctx, ch, parent, name)
    return name, _check_kind(ctx, ch, parent, name, texture_spec(ctx, ch, properties))


def texture_ref_properties(ctx, node, ref: Callable) -> dict:
    """The `<ref name=... id=.../>` children of a BSDF `node` that name top-level textures:
    parameter name -> `TextureSpec` (`ref(ctx, node, kind)` is the loader's lookup)."""
    out = {}
    for ch in node.children:
        if ch.tag != "ref":
            continue
        if "name" not in ch.attrib:
            raise ctx.err(ch, "a <ref> inside a BSDF needs the 'name' of the parameter")
        name = ctx.attr(ch, "name")
        _check_textured(ctx, ch, node, name)
        out[name] = _check_kind(ctx, ch, node, name, ref(ctx, ch, "texture"))
    return out
