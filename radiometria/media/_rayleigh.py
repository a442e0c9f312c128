r"""The Rayleigh phase function $p = \frac{3}{16\pi}(1 + \cos^2\theta)$ (thesis ch. 4).

Scattering by particles much smaller than the wavelength (air molecules), for unpolarised
light (`Chandrasekhar1960` §17). It is symmetric in $\cos\theta$, so the mean cosine is 0.
The CDF of $\mu = \cos\theta$ is $F(\mu) = (\mu^3 + 3\mu + 4)/8$; its inverse is the single
real root of the depressed cubic $\mu^3 + 3\mu + 4 - 8u = 0$, by Cardano's formula
$\mu = A - 1/A$ with $A = \sqrt[3]{z + \sqrt{z^2 + 1}}$, $z = 4u - 2$ (`Frisvad2011`),
evaluated on $|z|$ and odd-extended so it never subtracts nearly equal numbers.
"""

import math

import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import as_float_array, check_last_axis, check_unit_interval
from .._math import align_ranks, dot
from ._phase import AbstractPhaseFunction, PhaseSample, _direction_about

_C = 3.0 / (16.0 * math.pi)


class RayleighPhaseFunction(AbstractPhaseFunction):
    r"""The Rayleigh phase function for unpolarised light,
    $p(\omega_o, \omega_i) = \frac{3}{16\pi}(1 + (\omega_o\cdot\omega_i)^2)$, sampled exactly.

    ```python
    phase = RayleighPhaseFunction()
    s = phase.sample_p(wo, u)   # s.value == s.pdf == phase.p(wo, s.wi)
    ```

    !!! note "Thesis"
        Chapter 4 (energy transport in a medium; title only in the text).

    ??? cite "References"
        `Chandrasekhar1960` §17 (eq. 220); `Frisvad2011` (sampling); `Pharr2023` §11.3.
    """

    def p(
        self, wo: Float[Array, "*#batch 3"], wi: Float[Array, "*#batch 3"]
    ) -> Float[Array, "..."]:
        """$\\frac{3}{16\\pi}(1 + \\cos^2\\theta)$, symmetric in `wo`, `wi`. [sr^-1]"""
        c = dot(as_float_array(wo, "wo"), as_float_array(wi, "wi"))
        return _C * (1.0 + c * c)

    def pdf(
        self, wo: Float[Array, "*#batch 3"], wi: Float[Array, "*#batch 3"]
    ) -> Float[Array, "..."]:
        """The density of `sample_p`, equal to `p`. [sr^-1]"""
        return self.p(wo, wi)

    def sample_p(self, wo: Float[Array, "*#batch 3"], u: Float[Array, "*#batch 2"]) -> PhaseSample:
        """Sample `wi`: $\\cos\\theta$ from `u[..., 0]` by the inverse CDF (module docstring),
        azimuth $2\\pi$ `u[..., 1]` about $-\\omega_o$."""
        wo = check_last_axis(as_float_array(wo, "wo"), "wo", 3)
        u = check_unit_interval(check_last_axis(as_float_array(u, "u"), "u", 2))
        wo, u = align_ranks(wo, u)
        shape = jnp.broadcast_shapes(wo.shape[:-1], u.shape[:-1])
        u = jnp.broadcast_to(u, shape + (2,))
        z = 4.0 * u[..., 0] - 2.0
        za = jnp.abs(z)
        a = jnp.cbrt(za + jnp.sqrt(za * za + 1.0))  # >= 1
        mu = jnp.sign(z) * (a - 1.0 / a)
        mu = jnp.clip(mu, -1.0, 1.0)
        forward = jnp.broadcast_to(-wo, shape + (3,))
        wi = _direction_about(forward, mu, u[..., 1])
        val = _C * (1.0 + mu * mu)
        return PhaseSample(wi=wi, value=val, pdf=val)

    def mean_cosine(self) -> Float[Array, ""]:
        """0: the function is even in $\\cos\\theta$. [1]"""
        return jnp.asarray(0.0)
