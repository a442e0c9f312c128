"""Mitsuba's `homogeneous` medium as a renderer plugin (thesis 1.3, ch. 4)."""

from typing import ClassVar

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from ..._checks import device_array
from ...media import HenyeyGreenstein, HomogeneousMedium
from ...upsampling import RGBAlbedoSpectrum, RGBUnboundedSpectrum
from .._spectral import LinearRGB, SpectrumTable, tabulate_spectrum
from ._base import AbstractMediumPlugin

__all__ = ["HomogeneousMediumPlugin", "tabulate_extinction"]


def tabulate_extinction(value) -> np.ndarray:
    """An extinction value from a scene file tabulated on the renderer's grid: an RGB triple
    with every component <= 1 as Mitsuba 3 reads it (a bounded reflectance spectrum,
    `RGBAlbedoSpectrum`; Mitsuba refuses larger components), a larger one as an unbounded
    spectrum (`RGBUnboundedSpectrum`, our extension); spectra and numbers as given.
    [scene units^-1]"""
    if isinstance(value, LinearRGB) and max(value.rgb) <= 1.0:
        return tabulate_spectrum(value, RGBAlbedoSpectrum)
    return tabulate_spectrum(value, RGBUnboundedSpectrum)


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
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"sigma_t", "albedo", "scale", "g"})
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

    @classmethod
    def from_properties(cls, params: dict, *, where: str = "scene") -> "HomogeneousMediumPlugin":
        """One medium from a scene file's parameters (Mitsuba's defaults: `sigma_t` 1,
        `albedo` 0.75, `scale` 1, isotropic): an RGB `sigma_t` is upsampled as Mitsuba 3 does,
        a bounded spectrum, when its components are <= 1 (`tabulate_extinction`), an RGB
        `albedo` is an albedo spectrum (thesis 2.2.3). Errors name `where`."""
        unknown = sorted(set(params) - cls.PARAMETERS)
        if unknown:
            raise ValueError(f"{where}: unsupported medium parameter(s) {unknown}.")
        scale = float(params.get("scale", 1.0))
        sigma_t = tabulate_extinction(params.get("sigma_t", 1.0)) * scale
        albedo = tabulate_spectrum(params.get("albedo", 0.75), RGBAlbedoSpectrum)
        g = float(params.get("g", 0.0))
        for name, v, hi in (("sigma_t", sigma_t, np.inf), ("albedo", albedo, 1.0)):
            if not np.all(np.isfinite(v)) or np.any(v < 0) or np.any(v > hi):
                raise ValueError(
                    f"{where}: medium parameter {name!r} must be finite and in [0, {hi}] at "
                    f"every wavelength, got values in [{np.min(v)}, {np.max(v)}]."
                )
        if not -1.0 < g < 1.0:
            raise ValueError(f"{where}: the phase function's g must be in (-1, 1), got {g}.")
        return cls(
            SpectrumTable(device_array(sigma_t[None], jnp.float32)),
            SpectrumTable(device_array(albedo[None], jnp.float32)),
            device_array([g], jnp.float32),
        )

    @property
    def n_rows(self) -> int:
        return int(self.sigma_t.values.shape[0])

    def medium(self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"]):
        sigma_t = jnp.maximum(self.sigma_t(row, wavelength_nm), 0.0)
        albedo = jnp.clip(self.albedo(row, wavelength_nm), 0.0, 1.0)
        return HomogeneousMedium(sigma_t, albedo, HenyeyGreenstein(self.g[row]))
