"""Helpers shared by the light plugins: illuminant spectra of scene values, picking one of a
plugin's rows by power, the checks of scene parameters, and the base of the delta lights."""

import jax.numpy as jnp
import numpy as np

from ..._checks import device_array
from ..._math import dot
from ...upsampling import RGBIlluminantSpectrum
from .._spectral import LinearRGB, SpectrumTable, tabulate_spectrum
from ._base import AbstractLight

__all__ = [
    "AbstractDeltaLight",
    "AbstractSurfacelessLight",
    "direction_to_points",
    "illuminant_table",
    "pick_row",
    "row_cdf",
    "spectral_param",
    "to_world_param",
    "vector_or_to_world_param",
    "vector_param",
]


def check_spectral_values(values, what: str) -> None:
    """Spectral values are finite and >= 0 (else a `ValueError` naming `what`; the scene
    loaders turn it into a `SceneError`)."""
    v = np.asarray(values, np.float64)
    if not np.all(np.isfinite(v)) or np.any(v < 0):
        raise ValueError(f"{what}: values must be finite and >= 0, got {v.tolist()}.")


def spectral_param(params: dict, name: str, where: str, default: float = 1.0) -> np.ndarray:
    """A light's spectral parameter (RGB, spectrum or number) tabulated on the renderer's grid
    as an emission spectrum (thesis 2.2.3: RGB x D65 with Y = 1), finite and >= 0."""
    value = params.get(name, default)
    if isinstance(value, LinearRGB):
        check_spectral_values(value.rgb, f"{where}: parameter '{name}'")
    elif isinstance(value, int | float):
        check_spectral_values(value, f"{where}: parameter '{name}'")
    try:
        row = tabulate_spectrum(value, RGBIlluminantSpectrum)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{where}: parameter '{name}': {e}") from None
    check_spectral_values(row, f"{where}: parameter '{name}'")
    return row


def vector_param(params: dict, name: str, where: str) -> np.ndarray:
    """A 3-vector parameter (a `<point>` or `<vector>`), finite."""
    v = np.asarray(params[name], np.float64)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{where}: parameter '{name}' must be 3 finite numbers, got {v}.")
    return v


def to_world_param(params: dict, where: str) -> np.ndarray:
    """The `to_world` matrix `(4, 4)` (identity by default), with an invertible 3x3 part."""
    m = np.asarray(params.get("to_world", np.eye(4)), np.float64)
    if m.shape != (4, 4) or not np.all(np.isfinite(m)):
        raise ValueError(f"{where}: parameter 'to_world' must be a finite 4x4 matrix.")
    if not abs(np.linalg.det(m[:3, :3])) > 1e-12:
        raise ValueError(f"{where}: parameter 'to_world' is degenerate (singular 3x3 part).")
    return m


def vector_or_to_world_param(params: dict, name: str, where: str, column: int) -> np.ndarray:
    """The 3-vector parameter `name` or, without it, column `column` of `to_world` (3: its
    translation, 2: its +z axis); giving both is an error."""
    if name in params and "to_world" in params:
        raise ValueError(f"{where}: give '{name}' or 'to_world', not both.")
    if name in params:
        return vector_param(params, name, where)
    return to_world_param(params, where)[:3, column]


def direction_to_points(position, p):
    """Unit directions `wi` (n, 3) from the shading points `p` (n, 3) to the light positions
    `position` (n, 3) [scene units], the distances and their squares (n,), and `ok` where the
    distance is > 0 (there `wi` is 0)."""
    to_light = position - p
    dist2 = dot(to_light, to_light)
    dist = jnp.sqrt(dist2)
    ok = dist > 0
    return to_light / jnp.where(ok, dist, 1.0)[:, None], dist, dist2, ok


class AbstractSurfacelessLight(AbstractLight):
    """Lights with no surface in the scene (all but the area lights): no emission at surface
    hits, and a zero density for `sample_li` picking a surface point."""

    def pdf_li(self, face, dist, cos_light, origin=None):
        return jnp.zeros(face.shape, dist.dtype)

    def emitted(self, face, cos_o, valid, wavelength_nm, uv=None):
        return jnp.zeros(wavelength_nm.shape, cos_o.dtype)


class AbstractDeltaLight(AbstractSurfacelessLight):
    """Lights that no ray can hit (point, spot, directional): no emission at surface hits or
    along escaped rays, and zero solid-angle densities for MIS."""

    def emitted_escaped(self, directions, escaped, wavelength_nm):
        return jnp.zeros(wavelength_nm.shape, directions.dtype)

    def pdf_escaped(self, directions):
        return jnp.zeros(directions.shape[:-1], directions.dtype)


def illuminant_table(rows: list[np.ndarray], dtype) -> SpectrumTable:
    """Rows tabulated on the renderer's grid as one `SpectrumTable`."""
    return SpectrumTable(device_array(np.stack(rows), dtype))


def row_cdf(weights: np.ndarray) -> np.ndarray:
    """Cumulative probabilities of picking rows by `weights` (uniform if all are 0)."""
    w = np.asarray(weights, np.float64)
    w = np.ones_like(w) if not np.any(w > 0) else w
    cdf = np.cumsum(w / w.sum())
    cdf[-1] = 1.0
    return cdf


def pick_row(cdf, u):
    """Row `j` with `cdf[j-1] <= u < cdf[j]`, its probability and `u` remapped to [0, 1)
    within the row's slot (`Pharr2023` §A.1, `SampleDiscrete`)."""
    n = cdf.shape[0]
    method = "compare_all" if n <= 64 else "scan_unrolled"
    j = jnp.clip(jnp.searchsorted(cdf, u, side="right", method=method), 0, n - 1)
    hi = cdf[j]
    lo = jnp.where(j > 0, cdf[jnp.maximum(j - 1, 0)], 0.0)
    prob = hi - lo
    u_new = jnp.where(prob > 0, (u - lo) / jnp.where(prob > 0, prob, 1.0), 0.0)
    return j, prob, jnp.clip(u_new, 0.0, 1.0 - jnp.finfo(u.dtype).epsneg)
