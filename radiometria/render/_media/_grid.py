"""Mitsuba's `heterogeneous` medium as a renderer plugin (thesis ch. 4 and 9)."""

from typing import ClassVar

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from ..._checks import device_array
from ...media import GridMedium, HenyeyGreenstein, coarse_majorant_grid
from ...upsampling import RGBAlbedoSpectrum, RGBUnboundedSpectrum
from .._spectral import LinearRGB, SpectrumTable, tabulate_spectrum
from ._base import AbstractMediumPlugin
from ._homogeneous import tabulate_extinction

__all__ = ["GridMediumPlugin"]

_BIG = 1.0e6  # half-size of the box standing for a constvolume's unbounded extent


def _to_world(vol: dict) -> np.ndarray:
    if vol["type"] == "constvolume":
        m = np.diag([2 * _BIG, 2 * _BIG, 2 * _BIG, 1.0])
        m[:3, 3] = -_BIG
        return m
    m = vol.get("to_world")
    m = np.eye(4) if m is None else np.asarray(getattr(m, "matrix", m), np.float64)
    return m.reshape(4, 4)


def _factor_sigma_t(vol: dict, where: str) -> tuple[np.ndarray, object]:
    """`(density (Z, Y, X), spectral value)` with sigma_t = density * spectrum."""
    if vol["type"] == "constvolume":
        return np.ones((1, 1, 1), np.float32), vol["value"]
    data = np.asarray(vol["data"], np.float64)
    if data.shape[-1] == 1:
        return data[..., 0], 1.0
    # RGB: Mitsuba (`gridvolume` in spectral variants) stores per voxel m = 2 max(rgb) and the
    # bounded sigmoid coefficients of rgb / m, and returns the trilinear interpolation of the
    # corner spectra times the interpolated m. With one chromaticity in every voxel the corner
    # spectra are equal, and that is density * (the unbounded spectrum of the densest voxel's
    # RGB `rgb0`), the density being relative to `rgb0` (in [0, 1]).
    k = np.unravel_index(np.argmax(data.sum(-1)), data.shape[:3])
    rgb0 = data[k]
    c = int(np.argmax(rgb0))
    if rgb0[c] <= 0:
        return np.zeros(data.shape[:3]), 0.0
    density = data[..., c] / rgb0[c]
    if not np.allclose(data, density[..., None] * rgb0, rtol=1e-5, atol=1e-7 * rgb0[c]):
        raise ValueError(
            f"{vol.get('where', where)}: an RGB sigma_t grid must have one chromaticity in "
            "every voxel (values proportional to one RGB triple); use a 1-channel density "
            "grid with a spectral scale instead."
        )
    return density, LinearRGB(tuple(float(v) for v in rgb0))


def _factor_albedo(value, where: str) -> tuple[np.ndarray | None, object]:
    if not isinstance(value, dict):
        return None, value
    if value["type"] == "constvolume":
        return None, value["value"]
    data = np.asarray(value["data"], np.float64)
    src = value.get("where", where)
    if np.any(data > 1):
        raise ValueError(f"{src}: albedo grid values must lie in [0, 1], max {data.max()}.")
    if data.shape[-1] == 3 and np.all(data == data[:1, :1, :1]):
        return None, LinearRGB(tuple(float(v) for v in data[0, 0, 0]))
    if data.shape[-1] == 3 and not np.allclose(data, data[..., :1]):
        raise ValueError(
            f"{src}: an RGB albedo grid must be grey (r = g = b) or constant; varying colours "
            "are not supported."
        )
    return data[..., 0], 1.0


class GridMediumPlugin(AbstractMediumPlugin):
    r"""One heterogeneous medium (`<medium type="heterogeneous">`): a `gridvolume` or
    `constvolume` extinction, an albedo value or grid, `scale` and a Henyey-Greenstein phase
    function; each path's medium is a `radiometria.media.GridMedium`.

    **Fields:**

    - `density`: `(Z, Y, X)` the extinction's shape, finite and >= 0. [1]
    - `sigma_t`: `SpectrumTable` of the extinction spectrum (times `scale`), one row.
        [scene units^-1]
    - `albedo`: `SpectrumTable` of the albedo spectrum, one row, in [0, 1]. [1]
    - `albedo_grid`: `(Z', Y', X')` grey albedo grid in [0, 1], or None. [1]
    - `to_local`: `(4, 4)` inverse of the grid's `to_world`. [1/scene units]
    - `max_density`, `min_density`: the extreme densities (the majorant's factor and the
        residual-ratio-tracking control's). [1]
    - `majorant_grid`, `minorant_grid`: `(Rz, Ry, Rx)` conservative per-cell bounds of the
        density (`radiometria.media.coarse_majorant_grid`, built once here), the cells the
        tracking walks through. [1]
    - `g`: `(1,)` the phase function's mean cosine. [1]

    An RGB `sigma_t` grid must have one chromaticity in every voxel (then Mitsuba's
    per-lookup upsampling equals a density times one unbounded spectrum); an RGB albedo grid
    must be grey or constant. Grids differ in shape, so plugins are not concatenated.

    !!! note "Thesis"
        Chapter 4 (energy transport in a medium) and chapter 9 (volume rendering).

    ??? cite "References"
        `Jakob2022` (`heterogeneous`, `gridvolume`, `constvolume`); `Kutz2017`.
    """

    NAME: ClassVar[str] = "heterogeneous"
    CONCATENABLE: ClassVar[bool] = False
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"sigma_t", "albedo", "scale", "g"})
    density: Float[Array, "z y x"]
    sigma_t: SpectrumTable
    albedo: SpectrumTable
    albedo_grid: Float[Array, "z2 y2 x2"] | None
    to_local: Float[Array, "4 4"]
    max_density: Float[Array, ""]
    min_density: Float[Array, ""]
    majorant_grid: Float[Array, "rz ry rx"]
    minorant_grid: Float[Array, "rz ry rx"]
    g: Float[Array, " 1"]

    @classmethod
    def from_properties(cls, params: dict, *, where: str = "scene") -> "GridMediumPlugin":
        """One medium from a scene file's parsed parameters: `sigma_t` a volume description
        (`{"type": "gridvolume", "data": (Z, Y, X, C), "to_world": 4x4}` or
        `{"type": "constvolume", "value": ...}`), `albedo` a spectral value or a volume,
        `scale`, `g`. Errors (`ValueError`) name `where`."""
        unknown = sorted(set(params) - cls.PARAMETERS)
        if unknown:
            raise ValueError(f"{where}: unsupported medium parameter(s) {unknown}.")
        vol = params.get("sigma_t")
        if not isinstance(vol, dict):
            raise ValueError(f"{where}: a heterogeneous medium needs a sigma_t volume.")
        density, spec = _factor_sigma_t(vol, where)
        scale = float(params.get("scale", 1.0))
        if vol["type"] == "constvolume":  # an RGB value: as Mitsuba's homogeneous sigma_t
            sigma_t = tabulate_extinction(spec) * scale
        else:  # a grid's RGB: unbounded (`_factor_sigma_t`)
            sigma_t = tabulate_spectrum(spec, RGBUnboundedSpectrum) * scale
        albedo_grid, albedo_value = _factor_albedo(params.get("albedo", 0.75), where)
        alb = params.get("albedo")
        if albedo_grid is not None and not np.allclose(_to_world(alb), _to_world(vol)):
            raise ValueError(f"{where}: the albedo grid must have the sigma_t grid's to_world.")
        albedo = tabulate_spectrum(albedo_value, RGBAlbedoSpectrum)
        g = float(params.get("g", 0.0))
        for name, v, hi in (
            ("sigma_t", sigma_t, np.inf),
            ("albedo", albedo, 1.0),
            ("density", density, np.inf),
        ):
            if not np.all(np.isfinite(v)) or np.any(v < 0) or np.any(v > hi):
                raise ValueError(
                    f"{where}: medium parameter {name!r} must be finite and in [0, {hi}], got "
                    f"values in [{np.min(v)}, {np.max(v)}]."
                )
        if not -1.0 < g < 1.0:
            raise ValueError(f"{where}: the phase function's g must be in (-1, 1), got {g}.")
        m = _to_world(vol)
        if not np.all(np.isfinite(m)) or abs(np.linalg.det(m[:3, :3])) < 1e-12:
            raise ValueError(f"{where}: the grid's to_world must be finite and invertible.")
        hi, lo = coarse_majorant_grid(np.asarray(density, np.float32))
        return cls(
            density=device_array(density, jnp.float32),
            sigma_t=SpectrumTable(device_array(sigma_t[None], jnp.float32)),
            albedo=SpectrumTable(device_array(albedo[None], jnp.float32)),
            albedo_grid=None if albedo_grid is None else device_array(albedo_grid, jnp.float32),
            to_local=device_array(np.linalg.inv(m), jnp.float32),
            max_density=device_array(np.max(density), jnp.float32),
            min_density=device_array(np.min(density), jnp.float32),
            majorant_grid=device_array(hi, jnp.float32),
            minorant_grid=device_array(lo, jnp.float32),
            g=device_array([g], jnp.float32),
        )

    @property
    def n_rows(self) -> int:
        return 1

    def medium(self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"]) -> GridMedium:
        sigma_t = jnp.maximum(self.sigma_t(row, wavelength_nm), 0.0)
        albedo = jnp.clip(self.albedo(row, wavelength_nm), 0.0, 1.0)
        return GridMedium(
            self.density,
            sigma_t,
            albedo,
            HenyeyGreenstein(self.g[row]),
            albedo_grid=self.albedo_grid,
            max_density=self.max_density,
            to_local=self.to_local,
            min_density=self.min_density,
            majorant_grid=self.majorant_grid,
            minorant_grid=self.minorant_grid,
        )
