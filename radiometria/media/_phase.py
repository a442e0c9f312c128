"""The phase-function interface: angular distribution of light scattered in a medium."""

import abc

import equinox as eqx
from jaxtyping import Array, Float


class PhaseSample(eqx.Module):
    """A sampled scattering direction (arrays with the batch shape of the query).

    **Fields:**

    - `wi`: the sampled direction `(..., 3)`, pointing away from the scattering point.
        [unit vector]
    - `value`: the phase function $p(\\omega_o, \\omega_i)$ `(...)`. [sr^-1]
    - `pdf`: the solid-angle density of `wi` `(...)`. [sr^-1]

    ??? cite "References"
        `Pharr2023` §11.3.1 (`PhaseFunctionSample`).
    """

    wi: Float[Array, "*batch 3"]
    value: Float[Array, "*batch"]
    pdf: Float[Array, "*batch"]


class AbstractPhaseFunction(eqx.Module):
    """A phase function $p(\\omega_o, \\omega_i)$, normalised to 1 over the sphere, with its
    sampling triad (pbrt's `PhaseFunction`: `p`, `sample_p`, `pdf`).

    Directions follow pbrt's convention: `wo` points back along the incoming ray and `wi`
    away from the scattering point, so forward scattering means $\\omega_o\\cdot\\omega_i
    \\approx -1$. Implementations are final `equinox` Modules; their parameters (such as the
    mean cosine $g$) are arrays and may be differentiated.

    !!! note "Thesis"
        Chapter 4 (energy transport in a medium; title only in the text).

    ??? cite "References"
        `Pharr2023` §11.3 (phase functions).
    """

    @abc.abstractmethod
    def p(
        self, wo: Float[Array, "*batch 3"], wi: Float[Array, "*batch 3"]
    ) -> Float[Array, "*batch"]:
        """The phase function's value for the pair of unit directions. [sr^-1]"""

    @abc.abstractmethod
    def sample_p(self, wo: Float[Array, "*batch 3"], u: Float[Array, "*batch 2"]) -> PhaseSample:
        """Sample `wi` given `wo` from uniform variates `u` in [0, 1)^2."""

    @abc.abstractmethod
    def pdf(
        self, wo: Float[Array, "*batch 3"], wi: Float[Array, "*batch 3"]
    ) -> Float[Array, "*batch"]:
        """The solid-angle density with which `sample_p` returns `wi`. [sr^-1]"""
