"""The medium interface: extinction, free-flight sampling and transmittance along rays."""

import abc

import equinox as eqx
from jaxtyping import Array, Bool, Float

from ._phase import AbstractPhaseFunction


class MediumInteraction(eqx.Module):
    """The outcome of free-flight sampling along a batch of rays (arrays `(n, ...)`).

    **Fields:**

    - `t`: distance to the sampled scattering event along the ray, or the segment's end when
        none was sampled `(n,)`. [scene units]
    - `scattered`: True where a real scattering event was sampled before the segment's end.
    - `weight`: the estimator's throughput weight for the segment `(n, k)`, at the path's
        wavelengths (`sigma_s T / pdf` at a scattering event, `T / P(no event)` past it).
        [1]
    - `pdf`: `(n, k)` the density of the sampled outcome had the distance been sampled at
        wavelength `j` alone (`sigma_t,j T_j(t)` at an event, `T_j(t_max)` past the end), for
        path-level spectral MIS (`Miller2019`); None for estimators without one (tracking).
        [scene units^-1 at an event, 1 past it]

    ??? cite "References"
        `Pharr2023` §11.4 (free-flight sampling); `Novak2018` §4.
    """

    t: Float[Array, " n"]
    scattered: Bool[Array, " n"]
    weight: Float[Array, "n k"]
    pdf: Float[Array, "n k"] | None = None


class AbstractMedium(eqx.Module):
    """A participating medium: absorption and scattering coefficients over space and
    wavelength, a phase function, and the two estimators a volumetric path tracer needs.

    !!! note "Thesis"
        Section 1.3 (absorption, eq. 1.11-1.12) and chapter 4 (energy transport in a medium;
        title only in the text).

    ??? cite "References"
        `Pharr2023` §11.1-11.4 (media, transmittance, free-flight sampling); `Novak2018`
        (Monte Carlo methods for volumetric light transport).
    """

    phase: eqx.AbstractVar[AbstractPhaseFunction]

    @abc.abstractmethod
    def sample_free_flight(
        self,
        origins: Float[Array, "n 3"],
        directions: Float[Array, "n 3"],
        t_max: Float[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        u: Float[Array, "n d"],
    ) -> MediumInteraction:
        """Sample the distance to the next interaction along each ray segment
        `(0, t_max)` [scene units] from variates `u` in [0, 1)."""

    @abc.abstractmethod
    def transmittance(
        self,
        origins: Float[Array, "n 3"],
        directions: Float[Array, "n 3"],
        t_max: Float[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        u: Float[Array, "n d"],
    ) -> Float[Array, "n k"]:
        """An unbiased estimate of the transmittance $T = e^{-\\tau}$ of each segment (exact
        for homogeneous media), at the path's wavelengths [nm]. [1]"""
