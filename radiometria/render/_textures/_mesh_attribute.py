"""Mitsuba's `mesh_attribute` texture: a mesh's per-vertex or per-face values as a texture.

The attribute's values are baked per triangle corner when the scene is compiled, as spectra
(sigmoid-polynomial coefficients and a scale, the way a bitmap's texels are), into the
`RenderScene.face_attributes` table; each hit then carries its triangle's corner values and
barycentrics after its uv (`hit_columns`), and the texture interpolates the corners' spectra.
"""

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from ..._checks import device_array
from ...upsampling import (
    RGBAlbedoSpectrum,
    RGBUnboundedSpectrum,
    get_lut,
    sigmoid_polynomial_jakob2019,
)
from .._spectral import RGB_LUMINANCE
from ._base import AbstractTexture

__all__ = [
    "ATTRIBUTE_BLOCK",
    "HIT_COLUMNS",
    "SPECTRUM_KINDS",
    "MeshAttributeTexture",
    "corner_spectra",
]

#: Columns of one baked attribute per hit: 3 corners x (3 sigmoid coefficients, scale).
ATTRIBUTE_BLOCK = 12
#: Columns of a hit's surface coordinates before the attribute blocks: u, v, b1, b2.
HIT_COLUMNS = 4
# A polynomial this large makes the sigmoid 1 to float32 precision: a spectrally constant
# value is stored as (0, 0, _GREY) with the value as the scale.
_GREY = 1e8
_SPECTRA = {RGBAlbedoSpectrum: "albedo", RGBUnboundedSpectrum: "unbounded", None: "scalar"}
SPECTRUM_KINDS = ("albedo", "unbounded", "scalar")


def corner_spectra(values, spectrum: str) -> np.ndarray:
    """Attribute values at triangle corners as spectra: `(..., 4)` float64, the nm
    sigmoid-polynomial coefficients (thesis eq. 2.27) and the scale of each value.

    **Arguments:**

    - `values`: `(..., d)` values, finite; d = 1 (a grey value, spectrally constant, any
        sign and size, as Mitsuba) or d = 3 (linear sRGB, >= 0).
    - `spectrum`: `"albedo"` (3-channel values clipped to [0, 1] and upsampled as
        reflectances), `"unbounded"` (any size >= 0: scale 2 max(rgb)), thesis 2.2.3, or
        `"scalar"` (a scalar parameter, Mitsuba's `eval_1`: RGB becomes its luminance,
        Rec. 709 Y, spectrally constant).
    """
    x = np.asarray(values, np.float64)
    if spectrum == "scalar" and x.shape[-1] == 3:
        x = x @ RGB_LUMINANCE[:, None]
    if x.shape[-1] == 1:
        coeffs = np.zeros(x.shape[:-1] + (3,))
        coeffs[..., 2] = _GREY
        return np.concatenate([coeffs, x], axis=-1)
    if x.shape[-1] != 3:
        raise ValueError(f"a mesh attribute must have 1 or 3 channels, got {x.shape[-1]}.")
    if np.any(x < 0):
        raise ValueError(f"3-channel (RGB) values must be >= 0, got {x.min():.6g}.")
    if spectrum == "albedo":
        scale = np.ones(x.shape[:-1])
        x = np.clip(x, 0.0, 1.0)
    elif spectrum == "unbounded":
        scale = 2.0 * x.max(axis=-1)
        x = np.where(scale[..., None] > 0, x / np.where(scale > 0, scale, 1.0)[..., None], 0)
    else:
        raise ValueError(f"`spectrum` must be one of {SPECTRUM_KINDS}, got {spectrum!r}.")
    flat = x.reshape(-1, 3)
    coeffs = np.asarray(get_lut("sRGB").coefficients(device_array(flat)), np.float64)
    # Black and white are the table's (0, 0, -inf) and (0, 0, inf): kept finite, same spectra.
    coeffs = np.clip(coeffs, -_GREY, _GREY)
    return np.concatenate([coeffs.reshape(x.shape), scale[..., None]], axis=-1)


class MeshAttributeTexture(AbstractTexture):
    r"""A mesh attribute as a texture (Mitsuba 3's `mesh_attribute`), one row per material.

    A `vertex_<name>` attribute is interpolated over each triangle with the hit's
    barycentrics, $\sum_i b_i S_i(\lambda)$, where $S_i$ is the spectrum of corner $i$'s value
    (as Mitsuba 3's spectral variants interpolate the corners' spectra, not their RGB); a
    `face_<name>` attribute is its triangle's value. 3-channel values are linear sRGB
    upsampled through the coefficient table (thesis eq. 2.25-2.27, section 2.2.3) when the
    scene is compiled; 1-channel values are spectrally constant. The result is multiplied by
    the row's `scale`.

    The values live in the scene (`RenderScene.face_attributes`), not in the texture: the
    texture knows its attribute's place among a hit's surface coordinates (`block`), which
    `compile_scene` sets. A hit's coordinates are `(u, v, b1, b2, block 0, block 1, ...)`,
    each block the 3 corners' coefficients and scales of one attribute.

    **Fields:**

    - `scale`: `(m,)` factor of each row (Mitsuba's `scale`, default 1). [the parameter's
        unit]
    - `attribute`: the attribute's name, `vertex_<name>` or `face_<name>` (static).
    - `spectrum`: `"albedo"`, `"unbounded"` or `"scalar"`, how RGB values become spectra
        (`corner_spectra`; static).
    - `block`: the attribute's block among the hit's coordinates, -1 until the scene is
        compiled (static).

    ??? cite "References"
        `Jakob2022` (Mitsuba 3's `mesh_attribute` and its mesh attributes, interpolated as
        spectra in spectral variants); `Jakob2019` (coefficient tables).
    """

    NAME: ClassVar[str] = "mesh_attribute"
    scale: Float[Array, " m"]
    attribute: str = eqx.field(static=True)
    spectrum: str = eqx.field(static=True, default="albedo")
    block: int = eqx.field(static=True, default=-1)

    def __check_init__(self):
        if not self.attribute.startswith(("vertex_", "face_")):
            raise ValueError(
                f"`attribute` must start with 'vertex_' or 'face_', got {self.attribute!r}."
            )
        if self.spectrum not in SPECTRUM_KINDS:
            raise ValueError(f"`spectrum` must be one of {SPECTRUM_KINDS}, got {self.spectrum!r}.")

    @classmethod
    def from_name(
        cls, attribute: str, rgb_spectrum: type | None = RGBAlbedoSpectrum, scale: float = 1.0,
        dtype=jnp.float32,
    ) -> "MeshAttributeTexture":  # fmt: skip
        """One row reading `attribute`, RGB values upsampled with `rgb_spectrum`
        (`RGBAlbedoSpectrum` or `RGBUnboundedSpectrum`; emission is not supported), or, with
        `rgb_spectrum=None`, their luminance (a scalar parameter)."""
        if rgb_spectrum not in _SPECTRA:
            raise ValueError(
                "a mesh_attribute texture is supported for BSDF parameters (reflectances and "
                "unbounded values), not for emission."
            )
        if not np.isfinite(scale):
            raise ValueError(f"`scale` must be finite, got {scale}.")
        return cls(device_array([scale], dtype), attribute, _SPECTRA[rgb_spectrum])

    @property
    def n_rows(self) -> int:
        return int(self.scale.shape[0])

    def __call__(
        self,
        row: Int[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        uv: Float[Array, "n _"] | None = None,
    ) -> Float[Array, "n k"]:
        first = HIT_COLUMNS + ATTRIBUTE_BLOCK * self.block
        if self.block < 0 or uv is None or uv.shape[-1] < first + ATTRIBUTE_BLOCK:
            raise ValueError(
                f"the mesh_attribute texture of {self.attribute!r} needs hits carrying the "
                "scene's mesh attributes: render a scene compiled by compile_scene."
            )
        corners = uv[:, first : first + ATTRIBUTE_BLOCK].reshape(-1, 3, 4)
        b1, b2 = uv[:, 2:3], uv[:, 3:4]
        weights = (1.0 - b1 - b2, b1, b2)
        wl = wavelength_nm.astype(corners.dtype)
        out = 0.0
        for i, b in enumerate(weights):
            s = sigmoid_polynomial_jakob2019(corners[:, i, :3], wl) * corners[:, i, 3:4]
            out = out + b * s
        return (out * self.scale[row][:, None]).astype(wavelength_nm.dtype)
