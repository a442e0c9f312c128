"""Mitsuba's `homogeneous` medium as a renderer plugin (thesis 1.3, ch. 4)."""

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array, Float, Int

from ...media import HenyeyGreenstein, HomogeneousMedium
from .._spectral import SpectrumTable
from ._base import AbstractMediumPlugin

__all__ = ["HomogeneousMediumPlugin"]


class HomogeneousMediumPlugin(AbstractMediumPlugin):
    r"""Homogeneous media, one per row: extinction and albedo spectra and a Henyey-Greenstein
    phase function (g = 0 is isotropic).

    **Fields:**

    - `sigma_t`: `SpectrumTable` of the extinction coefficient $\sigma_t$ (Mitsuba's
        `sigma_t` times `scale`), on the renderer's 1 nm grid, >= 0. [scene units^-1]
    - `albedo`: `SpectrumTable` of the single-scattering albedo, in [0, 1]. [1]
    - `g`: `(m,)` mean cosine of each medium's phase function, in (-1, 1). [1]

    !!! note "Thesis"
        Section 1.3 (eq. 1.11-1.12) and chapter 4.

    ??? cite "References"
        `Jakob2022` (`homogeneous`); `Pharr2023` §11.4.
    """

    NAME: ClassVar[str] = "homogeneous"
    sigma_t: SpectrumTable
    albedo: SpectrumTable
    g: Float[Array, " m"]

    def __check_init__(self):
        m = self.sigma_t.values.shape[0]
        if self.albedo.values.shape[0] != m or jnp.shape(self.g) != (m,):
            raise ValueError(
                f"`sigma_t`, `albedo` and `g` must have one row per medium ({m}); got "
                f"{self.albedo.values.shape[0]} albedo rows and g of shape {jnp.shape(self.g)}."
            )

    @property
    def n_rows(self) -> int:
        return int(self.sigma_t.values.shape[0])

    def medium(self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"]):
        sigma_t = jnp.maximum(self.sigma_t(row, wavelength_nm), 0.0)
        albedo = jnp.clip(self.albedo(row, wavelength_nm), 0.0, 1.0)
        return HomogeneousMedium(sigma_t, albedo, HenyeyGreenstein(self.g[row]))
