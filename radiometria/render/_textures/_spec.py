"""Textures as scene files give them (`TextureSpec`), built into plugins by the materials."""

import dataclasses

import numpy as np

from .._spectral import SpectralValue
from ._base import AbstractTexture
from ._bitmap import BitmapTexture
from ._checkerboard import CheckerboardTexture
from ._mesh_attribute import MeshAttributeTexture

__all__ = ["TextureSpec", "texture_parameter"]


@dataclasses.dataclass(frozen=True)
class TextureSpec:
    """A texture of a scene file, not yet upsampled (the receiving parameter chooses the RGB
    spectrum: albedo for reflectances, thesis 2.2.3).

    **Fields:**

    - `type`: `"bitmap"`, `"checkerboard"` or `"mesh_attribute"` (Mitsuba 3's texture
        plugins).
    - `rgb`: `(h, w, 3)` linear texels of a bitmap (row 0 the top of the image), else `None`.
        [1, or the parameter's unit]
    - `colors`: a checkerboard's `(color0, color1)` spectral values, else `()`.
    - `filter_type`, `wrap_mode`: a bitmap's lookup (`"bilinear"`/`"nearest"`,
        `"repeat"`/`"mirror"`/`"clamp"`).
    - `to_uv`: `(4, 4)` or `(3, 3)` uv transform, or `None` (identity).
    - `attribute`, `scale`: a mesh_attribute's attribute name (`vertex_<name>` or
        `face_<name>`) and scale factor.
    - `where`: the file and line of the texture, for messages.
    """

    type: str
    rgb: np.ndarray | None = None
    colors: tuple[SpectralValue, ...] = ()
    filter_type: str = "bilinear"
    wrap_mode: str = "repeat"
    to_uv: np.ndarray | None = None
    attribute: str = ""
    scale: float = 1.0
    where: str = "scene"


def texture_parameter(value, rgb_spectrum: type, name: str, where: str) -> AbstractTexture | None:
    """The texture plugin (one row) of a parameter given as a `TextureSpec`, its texels and
    colours upsampled with `rgb_spectrum`; `None` when `value` is no texture. Errors name
    `where`, the texture's own location and the parameter `name`."""
    if not isinstance(value, TextureSpec):
        return None
    try:
        if value.type == "bitmap":
            return BitmapTexture.from_rgb(
                value.rgb,
                rgb_spectrum,
                filter_type=value.filter_type,
                wrap_mode=value.wrap_mode,
                to_uv=value.to_uv,
            )
        if value.type == "checkerboard":
            return CheckerboardTexture.from_values(*value.colors, rgb_spectrum, to_uv=value.to_uv)
        if value.type == "mesh_attribute":
            return MeshAttributeTexture.from_name(value.attribute, rgb_spectrum, value.scale)
    except (ValueError, TypeError) as e:
        raise ValueError(f"{where}: parameter {name!r}, texture at {value.where}: {e}") from None
    raise ValueError(f"{where}: parameter {name!r}: unsupported texture type {value.type!r}.")
