"""Participating media (thesis section 1.3 and ch. 4): the interfaces of media and phase functions.

Floor 4 of the house, beside `scattering`: absorption, scattering and extinction coefficients,
phase functions with sampling, free-flight sampling and transmittance estimators. This floor
holds the two interfaces the renderer's volumetric integrators will call
(`AbstractPhaseFunction`, `AbstractMedium`); the implementations (isotropic, Henyey-Greenstein
and Rayleigh phase functions; homogeneous and grid media; delta and ratio tracking) arrive
with the participating-media work. Absorption alone is `radiometria.radiometry.
beer_lambert_transmittance` (thesis eq. 1.12).
"""

from ._medium import AbstractMedium as AbstractMedium, MediumInteraction as MediumInteraction
from ._phase import AbstractPhaseFunction as AbstractPhaseFunction, PhaseSample as PhaseSample
