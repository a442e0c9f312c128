"""Indices of refraction as scene files give them: Mitsuba's named constants, numbers, spectra,
and the measured conductors of `radiometria.scattering` (thesis 3.1.1, footnote 18)."""

import numpy as np

from ..._checks import device_array
from ...scattering import CONDUCTORS, get_conductor
from ...upsampling import RGBAlbedoSpectrum, RGBUnboundedSpectrum
from .._spectral import LinearRGB, tabulate_spectrum, wavelength_grid_nm
from ._base import Properties

__all__ = ["MITSUBA_IOR", "conductor_ior", "dielectric_ior"]

# Mitsuba 3's named indices of refraction (documentation of the `dielectric` plugin).
MITSUBA_IOR = {
    "vacuum": 1.0,
    "helium": 1.00004,
    "hydrogen": 1.00013,
    "air": 1.00028,
    "carbon dioxide": 1.00045,
    "water": 1.3330,
    "acetone": 1.36,
    "ethanol": 1.361,
    "carbon tetrachloride": 1.461,
    "glycerol": 1.4729,
    "benzene": 1.501,
    "silicone oil": 1.52045,
    "bromine": 1.661,
    "water ice": 1.31,
    "fused quartz": 1.458,
    "pyrex": 1.470,
    "acrylic glass": 1.49,
    "polypropylene": 1.49,
    "bk7": 1.5046,
    "sodium chloride": 1.544,
    "amber": 1.55,
    "pet": 1.5750,
    "diamond": 2.419,
}
_PERFECT_MIRROR_K = 1e3  # eta = 1, k = 1e3: Fresnel reflectance 1 - 4e-6 (Mitsuba's "none")


def _ior(value, where: str) -> np.ndarray:
    """One index of refraction tabulated on the renderer's grid."""
    if isinstance(value, str):
        key = value.lower()
        if key not in MITSUBA_IOR:
            raise ValueError(
                f"{where}: unknown index of refraction {value!r}; known: {', '.join(MITSUBA_IOR)}."
            )
        return np.full(wavelength_grid_nm().shape, MITSUBA_IOR[key])
    rgb = RGBUnboundedSpectrum if isinstance(value, LinearRGB) else RGBAlbedoSpectrum
    values = tabulate_spectrum(value, rgb)
    if np.any(values[(values != 0)] <= 0) or np.all(values == 0):
        raise ValueError(f"{where}: indices of refraction must be > 0.")
    return values


def dielectric_ior(params: Properties, where: str) -> np.ndarray:
    """`int_ior / ext_ior` on the renderer's grid (Mitsuba's defaults: BK7 in air)."""
    return _ior(params.get("int_ior", "bk7"), where) / _ior(params.get("ext_ior", "air"), where)


def conductor_ior(params: Properties, where: str) -> tuple[np.ndarray, np.ndarray]:
    """`(eta, k)` on the renderer's grid: given spectra, a measured conductor by name
    (`radiometria.scattering.CONDUCTORS`), or `"none"` (Mitsuba's default: a perfect mirror)."""
    grid = wavelength_grid_nm()
    if "eta" in params or "k" in params:
        return (
            tabulate_spectrum(params.get("eta", 0.0), RGBUnboundedSpectrum),
            tabulate_spectrum(params.get("k", 1.0), RGBUnboundedSpectrum),
        )
    material = params.get("material", "none")
    if material == "none":
        return np.ones(grid.shape), np.full(grid.shape, _PERFECT_MIRROR_K)
    if material not in CONDUCTORS:
        raise ValueError(
            f"{where}: unknown conductor {material!r}; known: 'none', "
            f"{', '.join(map(repr, CONDUCTORS))}."
        )
    eta, k = get_conductor(material)(device_array(grid))
    return np.asarray(eta, np.float64), np.asarray(k, np.float64)
