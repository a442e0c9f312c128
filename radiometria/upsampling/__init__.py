"""RGB to spectrum (thesis section 2.2.3): sigmoid-polynomial spectra and coefficient tables."""

from ._fit import FitResult as FitResult, fit_rgb as fit_rgb
from ._forward import ForwardModel as ForwardModel, forward_model as forward_model
from ._sigmoid_polynomial import (
    AbstractSpectrum as AbstractSpectrum,
    SigmoidPolynomialSpectrum as SigmoidPolynomialSpectrum,
    nm_to_normalised_coefficients as nm_to_normalised_coefficients,
    normalised_to_nm_coefficients as normalised_to_nm_coefficients,
    sigmoid_jakob2019 as sigmoid_jakob2019,
    sigmoid_polynomial_jakob2019 as sigmoid_polynomial_jakob2019,
)
