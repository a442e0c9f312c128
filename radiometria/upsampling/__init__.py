"""RGB to spectrum (thesis section 2.2.3): sigmoid-polynomial spectra and coefficient tables.

- The model (eq. 2.25-2.26): `sigmoid_jakob2019`, `sigmoid_polynomial_jakob2019`,
  `SigmoidPolynomialSpectrum`, and the nm <-> normalised-wavelength coefficient conversions.
- The fit (eq. 2.27): `forward_model` (the colorimetry: CIE 1931 2°, 1 nm, the colour space's
  illuminant and matrices), `fit_rgb` (optimistix Levenberg-Marquardt, one colour at a time),
  `fit_lut` (the whole table: a warm-started batched Gauss-Newton sweep, per-entry results).
- The table: `RGBToSpectrumLUT` (pbrt-v4 layout and lookup), `get_lut` (the packaged sRGB
  table, or any other space fitted on first use), `save_lut` / `load_lut` (`.npz` and rgb2spec
  `.coeff`, both generations).
- Spectra for rendering: `RGBAlbedoSpectrum`, `RGBUnboundedSpectrum`, `RGBIlluminantSpectrum`.
- Accuracy: `roundtrip_delta_E` and the standard test sets `roundtrip_grid_rgb`,
  `roundtrip_random_rgb`, `roundtrip_statistics`.

The fit (`fit_rgb`, `FitResult`, `fit_lut`, `LUTFitResult`, `RESULTS`) is imported on first
use (PEP 562), so that a renderer that only looks colours up in a packaged table does not
import the fitter and its solvers (optimistix, lineax: about 0.15 s of start-up).
"""

import importlib
from typing import TYPE_CHECKING

from ._data import get_lut as get_lut
from ._forward import ForwardModel as ForwardModel, forward_model as forward_model
from ._io import LUTFileError as LUTFileError, load_lut as load_lut, save_lut as save_lut
from ._lut import RGBToSpectrumLUT as RGBToSpectrumLUT, brightness_scale as brightness_scale
from ._roundtrip import (
    roundtrip_delta_E as roundtrip_delta_E,
    roundtrip_grid_rgb as roundtrip_grid_rgb,
    roundtrip_random_rgb as roundtrip_random_rgb,
    roundtrip_statistics as roundtrip_statistics,
)
from ._sigmoid_polynomial import (
    SigmoidPolynomialSpectrum as SigmoidPolynomialSpectrum,
    nm_to_normalised_coefficients as nm_to_normalised_coefficients,
    normalised_to_nm_coefficients as normalised_to_nm_coefficients,
    sigmoid_jakob2019 as sigmoid_jakob2019,
    sigmoid_polynomial_jakob2019 as sigmoid_polynomial_jakob2019,
)
from ._spectra import (
    RGBAlbedoSpectrum as RGBAlbedoSpectrum,
    RGBIlluminantSpectrum as RGBIlluminantSpectrum,
    RGBUnboundedSpectrum as RGBUnboundedSpectrum,
)

# name -> private module that defines it, imported on first access.
_LAZY = {
    "FitResult": "_fit",
    "fit_rgb": "_fit",
    "RESULTS": "_fit_lut",
    "LUTFitResult": "_fit_lut",
    "fit_lut": "_fit_lut",
}

if TYPE_CHECKING:
    from ._fit import FitResult as FitResult, fit_rgb as fit_rgb
    from ._fit_lut import RESULTS as RESULTS, LUTFitResult as LUTFitResult, fit_lut as fit_lut


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
