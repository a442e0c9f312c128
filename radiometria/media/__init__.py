"""Participating media (thesis section 1.3 and ch. 4): coefficients, phase functions, free-flight
sampling and transmittance estimators, and media.

Floor 4 of the house, beside `scattering`. The thesis defines absorption in section 1.3 (the
absorption coefficient, eq. 1.11-1.12, the complex wavenumber and refractive index) and gives
chapter 4 (energy transport in a medium) as a title only; `Pharr2023` ch. 11, `Novak2018`,
`Novak2014` and `Woodcock1965` fill it in.

- Coefficients (`_coefficients`): `extinction_coefficient`, `single_scattering_albedo`,
  `coefficients_from_albedo`, `optical_depth` (closed form) and `optical_depth_along_ray`
  (Gauss-Legendre quadrature of a density field), `penetration_depth`, the absorption index
  $\\kappa = \\kappa_a/2k_0$ (`absorption_index_from_coefficient` and inverse), the complex
  refractive index and wavenumber with their inverses.
- Phase functions (`AbstractPhaseFunction`, `PhaseSample`): `IsotropicPhaseFunction`,
  `HenyeyGreenstein`, `RayleighPhaseFunction`, each with `p`, `sample_p`, `pdf` and
  `mean_cosine`, in pbrt's direction convention.
- Free-flight sampling and transmittance (`_estimators`): homogeneous closed forms
  (`sample_homogeneous_free_flight`, `homogeneous_free_flight_pdf`,
  `homogeneous_transmittance`) and, for an extinction field given as a JAX callable, delta
  tracking (`delta_tracking`, `FreeFlightSample`, `delta_tracking_transmittance`), ratio
  tracking and residual ratio tracking.
- Media (`AbstractMedium`, `MediumInteraction`): `HomogeneousMedium` at a path's hero
  wavelengths, and `GridMedium` (density and albedo grids with trilinear lookup in a box
  placed by `to_world`, spectral tracking and ratio tracking under a grey majorant;
  `trilinear_lookup`). Absorption alone is also `radiometria.radiometry.beer_lambert_transmittance`.
"""

from ._coefficients import (
    absorption_coefficient_from_complex_refractive_index as absorption_coefficient_from_complex_refractive_index,  # noqa: E501
    absorption_coefficient_from_complex_wavenumber as absorption_coefficient_from_complex_wavenumber,  # noqa: E501
    absorption_coefficient_from_index as absorption_coefficient_from_index,
    absorption_index_from_coefficient as absorption_index_from_coefficient,
    coefficients_from_albedo as coefficients_from_albedo,
    complex_refractive_index as complex_refractive_index,
    complex_wavenumber as complex_wavenumber,
    extinction_coefficient as extinction_coefficient,
    optical_depth as optical_depth,
    optical_depth_along_ray as optical_depth_along_ray,
    penetration_depth as penetration_depth,
    single_scattering_albedo as single_scattering_albedo,
)
from ._estimators import (
    FreeFlightSample as FreeFlightSample,
    delta_tracking as delta_tracking,
    delta_tracking_transmittance as delta_tracking_transmittance,
    homogeneous_free_flight_pdf as homogeneous_free_flight_pdf,
    homogeneous_transmittance as homogeneous_transmittance,
    ratio_tracking_transmittance as ratio_tracking_transmittance,
    residual_ratio_tracking_transmittance as residual_ratio_tracking_transmittance,
    sample_homogeneous_free_flight as sample_homogeneous_free_flight,
)
from ._grid import (
    GridMedium as GridMedium,
    coarse_majorant_grid as coarse_majorant_grid,
    default_majorant_resolution as default_majorant_resolution,
    trilinear_lookup as trilinear_lookup,
)
from ._henyey_greenstein import HenyeyGreenstein as HenyeyGreenstein
from ._homogeneous import HomogeneousMedium as HomogeneousMedium
from ._isotropic import IsotropicPhaseFunction as IsotropicPhaseFunction
from ._medium import AbstractMedium as AbstractMedium, MediumInteraction as MediumInteraction
from ._phase import AbstractPhaseFunction as AbstractPhaseFunction, PhaseSample as PhaseSample
from ._rayleigh import RayleighPhaseFunction as RayleighPhaseFunction
