"""Radiometry (thesis ch. 1, sections 1.1-1.5): waves, Planck's law, spectra and quantities.

- Monochromatic waves (section 1.1, eq. 1.1-1.6): `period`, `angular_frequency`, vacuum and
  in-medium wavelengths and wavenumbers (`wavenumber_vacuum`, `wavenumber_in_medium`,
  `wavelength_in_medium_nm`), `phase_velocity` and the refractive index
  (`refractive_index_from_permittivity`), with their inverses.
- Blackbody radiation (section 1.5): `planck` (eq. 1.24, per nm), `planck_frequency` (per Hz),
  `planck_exitance` (eq. 1.23), `stefan_boltzmann_exitance` (eq. 1.22), and Wien's
  displacement law `planck_peak_wavelength` / `planck_peak_frequency`.
- Spectra as callables (`Pharr2023` §4.5): `AbstractSpectrum` (the interface and batching rule
  that every spectrum of the package follows), `ConstantSpectrum`, `PiecewiseLinearSpectrum`
  (tabulated, zero outside) and `BlackbodySpectrum` (eq. 1.24, scaled).
- Sampled spectra on nanometre grids: `integrate_spectrum` (trapezoid rule, irregular grids) and
  `resample_spectrum` (linear interpolation with an explicit extrapolation policy).
- Closed-form relations between quantities (sections 1.1-1.4): irradiance from radiance over a
  cone or the hemisphere (eq. 1.13), Lambertian exitance, point sources and the inverse-square
  law, Lambert's cosine law, etendue and basic radiance (eq. 1.14-1.21), photon energy,
  wavelength/frequency and per-nm/per-Hz conversions; the rest of table 1.2, radiant energy
  (`radiant_energy`) and radiosity (`radiosity`).
- Eq. 1.13 for any radiance distribution L(theta, phi) by Gauss-Legendre quadrature
  (`irradiance_from_radiance_distribution`).

Wavelengths are in nm and spectral densities per nm at every boundary; everything else is SI.
"""

from ._irradiance import (
    irradiance_from_radiance_distribution as irradiance_from_radiance_distribution,
)
from ._planck import (
    planck as planck,
    planck_exitance as planck_exitance,
    planck_frequency as planck_frequency,
    planck_peak_frequency as planck_peak_frequency,
    planck_peak_wavelength as planck_peak_wavelength,
    stefan_boltzmann_exitance as stefan_boltzmann_exitance,
)
from ._quantities import (
    basic_radiance as basic_radiance,
    beer_lambert_transmittance as beer_lambert_transmittance,
    etendue as etendue,
    exitance_from_radiance as exitance_from_radiance,
    flux_from_intensity as flux_from_intensity,
    frequency_to_wavelength as frequency_to_wavelength,
    intensity_from_flux as intensity_from_flux,
    irradiance_from_intensity as irradiance_from_intensity,
    irradiance_from_radiance as irradiance_from_radiance,
    lambert_intensity as lambert_intensity,
    photon_energy as photon_energy,
    radiance_from_basic_radiance as radiance_from_basic_radiance,
    radiance_from_exitance as radiance_from_exitance,
    radiance_from_irradiance as radiance_from_irradiance,
    radiant_energy as radiant_energy,
    radiosity as radiosity,
    spectral_density_per_hz_to_per_nm as spectral_density_per_hz_to_per_nm,
    spectral_density_per_nm_to_per_hz as spectral_density_per_nm_to_per_hz,
    wavelength_to_frequency as wavelength_to_frequency,
)
from ._spectra import (
    integrate_spectrum as integrate_spectrum,
    resample_spectrum as resample_spectrum,
)
from ._spectrum import (
    AbstractSpectrum as AbstractSpectrum,
    BlackbodySpectrum as BlackbodySpectrum,
    ConstantSpectrum as ConstantSpectrum,
    PiecewiseLinearSpectrum as PiecewiseLinearSpectrum,
)
from ._waves import (
    angular_frequency as angular_frequency,
    frequency_from_angular_frequency as frequency_from_angular_frequency,
    frequency_from_period as frequency_from_period,
    period as period,
    phase_velocity as phase_velocity,
    refractive_index_from_permittivity as refractive_index_from_permittivity,
    refractive_index_from_phase_velocity as refractive_index_from_phase_velocity,
    wavelength_from_wavenumber as wavelength_from_wavenumber,
    wavelength_in_medium_nm as wavelength_in_medium_nm,
    wavelength_in_vacuum_nm as wavelength_in_vacuum_nm,
    wavenumber_in_medium as wavenumber_in_medium,
    wavenumber_vacuum as wavenumber_vacuum,
)
