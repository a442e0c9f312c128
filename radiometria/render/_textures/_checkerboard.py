"""Mitsuba's `checkerboard` texture: two spectra alternating over the unit square of uv."""

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array, Float, Int

from ..._checks import device_array
from ...upsampling import RGBAlbedoSpectrum
from .._spectral import SpectralValue
from ._base import AbstractTexture
from ._bitmap import uv_transform
from ._constant import ConstantTexture

__all__ = ["CheckerboardTexture"]


class CheckerboardTexture(AbstractTexture):
    r"""A 2 x 2 checkerboard over each unit square of uv (Mitsuba 3's `checkerboard`).

    With $(u', v') = $ `to_uv` $(u, v, 1)$, a point takes `color0` where
    $\mathrm{frac}(u') > 1/2$ and $\mathrm{frac}(v') > 1/2$ agree (both or neither), else
    `color1`; the square $[0, 1/2)^2$ is `color0`.

    **Fields:**

    - `color0`, `color1`: `ConstantTexture`s, one row per material (Mitsuba's defaults 0.4
        and 0.2). [the parameter's unit]
    - `to_uv`: `(m, 3, 3)` affine map of $(u, v, 1)$ of each row. [1]

    ??? cite "References"
        `Jakob2022` (Mitsuba 3's `checkerboard`); `Pharr2023` §10.5.1 (checkerboards).
    """

    NAME: ClassVar[str] = "checkerboard"
    color0: ConstantTexture
    color1: ConstantTexture
    to_uv: Float[Array, "m 3 3"]

    @classmethod
    def from_values(
        cls,
        color0: SpectralValue = 0.4,
        color1: SpectralValue = 0.2,
        rgb_spectrum: type = RGBAlbedoSpectrum,
        *,
        to_uv=None,
        dtype=jnp.float32,
    ) -> "CheckerboardTexture":
        """One row from two scene values (`LinearRGB`, spectra or numbers), upsampled with
        `rgb_spectrum` (`tabulate_spectrum`), and Mitsuba's `to_uv` (4 x 4 or 3 x 3)."""
        c0 = ConstantTexture.from_values([color0], rgb_spectrum, dtype)
        c1 = ConstantTexture.from_values([color1], rgb_spectrum, dtype)
        return cls(c0, c1, device_array(uv_transform(to_uv)[None], dtype))

    def __check_init__(self):
        if self.color0.n_rows != self.color1.n_rows or self.to_uv.shape[0] != self.color0.n_rows:
            raise ValueError("`color0`, `color1` and `to_uv` must have one row per material.")

    @property
    def n_rows(self) -> int:
        return self.color0.n_rows

    def __call__(
        self,
        row: Int[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        uv: Float[Array, "n _"] | None = None,
    ) -> Float[Array, "n k"]:
        if uv is None:
            uv = jnp.zeros(wavelength_nm.shape[:-1] + (2,), wavelength_nm.dtype)
        m = self.to_uv[row]
        uv = uv.astype(m.dtype)
        u = m[..., 0, 0] * uv[..., 0] + m[..., 0, 1] * uv[..., 1] + m[..., 0, 2]
        v = m[..., 1, 0] * uv[..., 0] + m[..., 1, 1] * uv[..., 1] + m[..., 1, 2]
        first = (u - jnp.floor(u) > 0.5) == (v - jnp.floor(v) > 0.5)
        a = self.color0(row, wavelength_nm)
        b = self.color1(row, wavelength_nm)
        return jnp.where(first[..., None], a, b)
