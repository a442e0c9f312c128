"""Mitsuba's `bitmap` texture: an image of sigmoid-polynomial coefficients, looked up by uv."""

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from ..._checks import device_array
from ...upsampling import (
    RGBAlbedoSpectrum,
    RGBIlluminantSpectrum,
    RGBUnboundedSpectrum,
    get_lut,
    sigmoid_polynomial_jakob2019,
)
from .._spectral import LinearRGB, SpectrumTable, tabulate_spectrum
from ._base import AbstractTexture

__all__ = ["FILTER_TYPES", "WRAP_MODES", "BitmapTexture", "uv_transform"]

FILTER_TYPES = ("bilinear", "nearest")
WRAP_MODES = ("repeat", "mirror", "clamp")


def uv_transform(to_uv) -> np.ndarray:
    """Mitsuba's `to_uv` (a 4 x 4 matrix, or 3 x 3) as the 3 x 3 affine map of (u, v, 1):
    rows and columns 0, 1 and 3 of the 4 x 4 matrix (Mitsuba's `Transform4f::extract`)."""
    m = np.asarray(np.eye(3) if to_uv is None else to_uv, np.float64)
    if m.shape == (4, 4):
        m = m[np.ix_([0, 1, 3], [0, 1, 3])]
    if m.shape != (3, 3) or not np.all(np.isfinite(m)):
        raise ValueError(f"`to_uv` must be a finite 3 x 3 or 4 x 4 matrix, got shape {m.shape}.")
    return m


def _wrap(i: Array, n: int, mode: str) -> Array:
    """Texel indices wrapped into [0, n) (Dr.Jit's texture wrap modes)."""
    if mode == "repeat":
        return jnp.mod(i, n)
    if mode == "clamp":
        return jnp.clip(i, 0, n - 1)
    i = jnp.mod(i, 2 * n)  # mirror: ... 1 0 | 0 1 ... n-1 | n-1 ... 0 | 0 1 ...
    return jnp.where(i >= n, 2 * n - 1 - i, i)


class BitmapTexture(AbstractTexture):
    r"""An image texture (Mitsuba 3's `bitmap`) for one material (one row).

    The texels' linear RGB colours are turned into sigmoid-polynomial coefficients once, when
    the texture is built (the coefficient table's lookup, thesis eq. 2.25-2.27); a lookup
    evaluates the spectra of the texels around `uv` at the path's wavelengths and
    interpolates them (bilinear) or takes the nearest texel's, as Mitsuba 3 does in its
    spectral variants. Texel $(i, j)$ (column, row; row 0 the image's first, top row) has its
    centre at $u = (i + 1/2)/w$, $v = (j + 1/2)/h$, after `to_uv` maps the surface's uv.

    Build one with `BitmapTexture.from_rgb(rgb, rgb_spectrum, ...)`.

    **Fields:**

    - `coeffs`: `(h, w, 3)` nm coefficients of each texel (`sigmoid_polynomial_jakob2019`).
    - `scale`: `(h, w)` factor of each texel's spectrum (2 max(rgb) for unbounded and
        illuminant spectra, 1 for reflectances). [the parameter's unit]
    - `illuminant`: `None`, or a one-row `SpectrumTable` of the normalised D65 illuminant
        that multiplies emission spectra (`RGBIlluminantSpectrum`).
    - `to_uv`: `(3, 3)` affine map of $(u, v, 1)$. [1]
    - `filter_type`: `"bilinear"` or `"nearest"` (static); `wrap_mode`: `"repeat"`,
        `"mirror"` or `"clamp"` (static).

    !!! note "Thesis"
        Eq. 2.25-2.27 (the sigmoid-polynomial spectra of texels), section 2.2.3.

    ??? cite "References"
        `Jakob2022` (Mitsuba 3's `bitmap`: texel centres, wrap modes, spectral texels);
        `Jakob2019` (coefficient tables); `Pharr2023` §10.4.2 (image textures).
    """

    NAME: ClassVar[str] = "bitmap"
    coeffs: Float[Array, "h w 3"]
    scale: Float[Array, "h w"]
    illuminant: SpectrumTable | None
    to_uv: Float[Array, "3 3"]
    filter_type: str = eqx.field(static=True, default="bilinear")
    wrap_mode: str = eqx.field(static=True, default="repeat")

    def __check_init__(self):
        if self.filter_type not in FILTER_TYPES:
            raise ValueError(f"`filter_type` must be one of {FILTER_TYPES}, got "
                             f"{self.filter_type!r}.")  # fmt: skip
        if self.wrap_mode not in WRAP_MODES:
            raise ValueError(f"`wrap_mode` must be one of {WRAP_MODES}, got {self.wrap_mode!r}.")

    @classmethod
    def from_rgb(
        cls,
        rgb,
        rgb_spectrum: type = RGBAlbedoSpectrum,
        *,
        filter_type: str = "bilinear",
        wrap_mode: str = "repeat",
        to_uv=None,
        dtype=jnp.float32,
    ) -> "BitmapTexture":
        """Upsample an image's linear sRGB texels to spectra (NumPy and one table lookup).

        **Arguments:**

        - `rgb`: `(h, w, 3)` linear sRGB texels, row 0 the top of the image, finite and
            >= 0. Reflectances (`RGBAlbedoSpectrum`) are clipped to [0, 1], as a reflectance
            cannot exceed 1. [1, or the parameter's unit]
        - `rgb_spectrum`: `RGBAlbedoSpectrum` (reflectances), `RGBUnboundedSpectrum` (values
            of any size) or `RGBIlluminantSpectrum` (emission), thesis 2.2.3.
        - `filter_type`, `wrap_mode`, `to_uv`: as Mitsuba's `bitmap` (class docstring;
            `to_uv` a 4 x 4 or 3 x 3 matrix, default the identity).
        - `dtype`: the arrays' dtype (float32 for rendering).
        """
        x = np.asarray(rgb, np.float64)
        if x.ndim != 3 or x.shape[2] != 3 or x.shape[0] < 1 or x.shape[1] < 1:
            raise ValueError(f"`rgb` must have shape (h, w, 3), got {x.shape}.")
        if not np.all(np.isfinite(x)) or np.any(x < 0):
            raise ValueError("`rgb` texels must be finite and >= 0.")
        if rgb_spectrum is RGBAlbedoSpectrum:
            scale = np.ones(x.shape[:2])
            x = np.clip(x, 0.0, 1.0)
        elif rgb_spectrum in (RGBUnboundedSpectrum, RGBIlluminantSpectrum):
            scale = 2.0 * x.max(axis=2)
            x = np.where(scale[..., None] > 0, x / np.where(scale > 0, scale, 1.0)[..., None], 0)
        else:
            raise ValueError(f"`rgb_spectrum` must be one of the RGB spectrum classes, got "
                             f"{rgb_spectrum!r}.")  # fmt: skip
        coeffs = np.asarray(get_lut("sRGB").coefficients(device_array(x)), np.float64)
        illuminant = None
        if rgb_spectrum is RGBIlluminantSpectrum:  # s S(rgb/s) D65: white (1, 1, 1) is D65
            d65 = tabulate_spectrum(LinearRGB([1.0, 1.0, 1.0]), RGBIlluminantSpectrum)
            illuminant = SpectrumTable(device_array(d65[None], dtype))
        return cls(
            coeffs=device_array(coeffs, dtype),
            scale=device_array(scale, dtype),
            illuminant=illuminant,
            to_uv=device_array(uv_transform(to_uv), dtype),
            filter_type=filter_type,
            wrap_mode=wrap_mode,
        )

    @property
    def n_rows(self) -> int:
        return 1

    @property
    def resolution(self) -> tuple[int, int]:
        """`(width, height)` in texels."""
        return int(self.coeffs.shape[1]), int(self.coeffs.shape[0])

    def __call__(
        self,
        row: Int[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        uv: Float[Array, "n _"] | None = None,
    ) -> Float[Array, "n k"]:
        if uv is None:
            uv = jnp.zeros(wavelength_nm.shape[:-1] + (2,), wavelength_nm.dtype)
        uv = uv.astype(self.to_uv.dtype)
        u = self.to_uv[0, 0] * uv[..., 0] + self.to_uv[0, 1] * uv[..., 1] + self.to_uv[0, 2]
        v = self.to_uv[1, 0] * uv[..., 0] + self.to_uv[1, 1] * uv[..., 1] + self.to_uv[1, 2]
        w, h = self.resolution

        def texel(i, j):
            i = _wrap(i, w, self.wrap_mode)
            j = _wrap(j, h, self.wrap_mode)
            c = self.coeffs[j, i]
            value = sigmoid_polynomial_jakob2019(c, wavelength_nm.astype(c.dtype))
            return value * self.scale[j, i][..., None]

        if self.filter_type == "nearest":
            out = texel(jnp.floor(u * w).astype(jnp.int32), jnp.floor(v * h).astype(jnp.int32))
        else:
            x, y = u * w - 0.5, v * h - 0.5
            x0, y0 = jnp.floor(x), jnp.floor(y)
            wx, wy = (x - x0)[..., None], (y - y0)[..., None]
            i, j = x0.astype(jnp.int32), y0.astype(jnp.int32)
            top = (1 - wx) * texel(i, j) + wx * texel(i + 1, j)
            bottom = (1 - wx) * texel(i, j + 1) + wx * texel(i + 1, j + 1)
            out = (1 - wy) * top + wy * bottom
        if self.illuminant is not None:
            out = out * self.illuminant(jnp.zeros(out.shape[:-1], jnp.int32), wavelength_nm)
        return out.astype(wavelength_nm.dtype)
