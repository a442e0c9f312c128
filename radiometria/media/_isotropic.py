r"""The isotropic phase function $p = 1/(4\pi)$ (thesis ch. 4)."""

import math

import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import as_float_array, check_last_axis, check_unit_interval
from .._math import align_ranks, dot
from ._phase import AbstractPhaseFunction, PhaseSample, _direction_about

_INV_4PI = 1.0 / (4.0 * math.pi)


class IsotropicPhaseFunction(AbstractPhaseFunction):
    r"""Isotropic scattering: every direction equally likely, $p(\omega_o, \omega_i) =
    1/(4\pi)$, sampled exactly (uniform sphere). The mean cosine is 0.

    ```python
    phase = IsotropicPhaseFunction()
    s = phase.sample_p(wo, u)   # s.value == s.pdf == 1 / (4 pi)
    ```

    !!! note "Thesis"
        Chapter 4 (energy transport in a medium; title only in the text).

    ??? cite "References"
        `Pharr2023` §11.3; `Chandrasekhar1960` §1.
    """

    def p(
        self, wo: Float[Array, "*#batch 3"], wi: Float[Array, "*#batch 3"]
    ) -> Float[Array, "..."]:
        """The constant $1/(4\\pi)$, broadcast over the directions. [sr^-1]"""
        c = dot(as_float_array(wo, "wo"), as_float_array(wi, "wi"))
        return jnp.full_like(c, _INV_4PI)

    def pdf(
        self, wo: Float[Array, "*#batch 3"], wi: Float[Array, "*#batch 3"]
    ) -> Float[Array, "..."]:
        """The density of `sample_p`, equal to `p`. [sr^-1]"""
        return self.p(wo, wi)

    def sample_p(self, wo: Float[Array, "*#batch 3"], u: Float[Array, "*#batch 2"]) -> PhaseSample:
        """A uniform direction on the sphere from `u (..., 2)` in [0, 1)^2: scattering-angle
        cosine $1 - 2u_0$ about $-\\omega_o$ and azimuth $2\\pi u_1$, as
        `HenyeyGreenstein(0.0)` draws them; `value == pdf == 1/(4 pi)`."""
        wo = check_last_axis(as_float_array(wo, "wo"), "wo", 3)
        u = check_unit_interval(check_last_axis(as_float_array(u, "u"), "u", 2))
        wo, u = align_ranks(wo, u)
        shape = jnp.broadcast_shapes(wo.shape[:-1], u.shape[:-1])
        wo = jnp.broadcast_to(wo, shape + (3,))
        u = jnp.broadcast_to(u, shape + (2,))
        cos_theta = 1.0 - 2.0 * u[..., 0]
        wi = _direction_about(-wo, cos_theta, u[..., 1])
        val = jnp.full(shape, _INV_4PI, dtype=wi.dtype)
        return PhaseSample(wi=wi, value=val, pdf=val)

    def mean_cosine(self) -> Float[Array, ""]:
        """0: forward and backward scattering balance. [1]"""
        return jnp.asarray(0.0)
