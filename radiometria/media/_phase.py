"""The phase-function interface: angular distribution of light scattered in a medium."""

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._math import safe_sqrt, sincos_pi


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

    wi: Float[Array, "*#batch 3"]
    value: Float[Array, "*batch"]
    pdf: Float[Array, "*batch"]


class AbstractPhaseFunction(eqx.Module):
    """A phase function $p(\\omega_o, \\omega_i)$, normalised to 1 over the sphere, with its
    sampling triad (pbrt's `PhaseFunction`: `p`, `sample_p`, `pdf`).

    Directions follow pbrt's convention: `wo` points back along the incoming ray and `wi`
    away from the scattering point, so forward scattering means $\\omega_o\\cdot\\omega_i
    \\approx -1$. The scattering angle $\\theta$ is the angle between the propagation
    directions before and after the event, $\\cos\\theta = -\\omega_o\\cdot\\omega_i$.
    Implementations are final `equinox` Modules; their parameters (such as the mean cosine $g$)
    are arrays and may be differentiated.

    Besides pbrt's triad the interface asks for `mean_cosine`, the asymmetry parameter
    $\\langle\\cos\\theta\\rangle$: similarity theory (the reduced scattering coefficient
    $\\sigma_s(1 - g)$) and diffusion approximations need it for any phase function, not only for
    Henyey-Greenstein, where it is the parameter $g$.

    !!! note "Thesis"
        Chapter 4 (energy transport in a medium; title only in the text).

    ??? cite "References"
        `Pharr2023` §11.3 (phase functions).
    """

    @abc.abstractmethod
    def p(
        self, wo: Float[Array, "*#batch 3"], wi: Float[Array, "*#batch 3"]
    ) -> Float[Array, "..."]:
        """The phase function's value for the pair of unit directions. [sr^-1]"""

    @abc.abstractmethod
    def sample_p(self, wo: Float[Array, "*#batch 3"], u: Float[Array, "*#batch 2"]) -> PhaseSample:
        """Sample `wi` given `wo` from uniform variates `u` in [0, 1)^2."""

    @abc.abstractmethod
    def pdf(
        self, wo: Float[Array, "*#batch 3"], wi: Float[Array, "*#batch 3"]
    ) -> Float[Array, "..."]:
        """The solid-angle density with which `sample_p` returns `wi`. [sr^-1]"""

    @abc.abstractmethod
    def mean_cosine(self) -> Float[Array, "..."]:
        """The mean cosine of the scattering angle, $\\int p\\,\\cos\\theta\\,\\mathrm d\\omega_i$
        with $\\cos\\theta = -\\omega_o\\cdot\\omega_i$: > 0 for forward scattering. [1]"""


def _coordinate_system(v: Array) -> tuple[Array, Array]:
    """Two unit vectors completing the unit vector `v (..., 3)` to a right-handed orthonormal
    basis (`Duff2017`, pbrt's `CoordinateSystem`), continuous except where v_z = -1 flips."""
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    sign = jnp.where(z >= 0, 1.0, -1.0).astype(v.dtype)
    a = -1.0 / (sign + z)
    b = x * y * a
    s = jnp.stack([1.0 + sign * x * x * a, sign * b, -sign * x], axis=-1)
    t = jnp.stack([b, sign + y * y * a, -y], axis=-1)
    return s, t


def _direction_about(axis: Array, cos_theta: Array, u_phi: Array) -> Array:
    """The unit vector at angle theta from `axis (..., 3)` and azimuth `2 pi u_phi` around it
    (`u_phi` in turns)."""
    s, t = _coordinate_system(axis)
    sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta)
    sin_phi, cos_phi = sincos_pi(2.0 * u_phi)
    return (
        (sin_theta * cos_phi)[..., None] * s
        + (sin_theta * sin_phi)[..., None] * t
        + cos_theta[..., None] * axis
    )
