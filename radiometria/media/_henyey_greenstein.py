r"""The Henyey-Greenstein phase function (Henyey & Greenstein 1941; thesis ch. 4).

$$p_{HG}(\cos\theta) = \frac{1}{4\pi}\,\frac{1 - g^2}{(1 + g^2 - 2g\cos\theta)^{3/2}},$$

with $\theta$ the scattering angle and $g \in (-1, 1)$ its mean cosine. In pbrt's convention
(`wo` back along the incoming ray) $\cos\theta = -\omega_o\cdot\omega_i$, so pbrt writes the
denominator $1 + g^2 + 2g\,\omega_o\cdot\omega_i$ (`HenyeyGreenstein`, `Pharr2023` §11.3.1).

Sampling inverts the CDF of $\cos\theta$ (pbrt's `SampleHenyeyGreenstein`). pbrt evaluates
$\cos\theta = (1 + g^2 - s^2)/(2g)$, $s = (1 - g^2)/(1 + g - 2gu)$, which divides by $g$
(pbrt switches to $1 - 2u$ below $|g| = 10^{-3}$ and clamps $|g| <= 0.99$). Here the same
inverse is factored exactly into
$$1 - \cos\theta = \frac{(1 - g)^2\,u\,(2 + 2g(1 - u))}{(1 + g(1 - 2u))^2}, \qquad
1 + \cos\theta = \frac{(1 + g)^2\,(1 - u)\,(2 - 2gu)}{(1 + g(1 - 2u))^2},$$
which has no division by $g$ and no cancellation, so the sampler is exact and smooth in $g$
over the whole open interval (and $\sin^2\theta$ is their product). $u = 0$ gives backward and
$u \to 1$ forward scattering for $g > 0$.
"""

import math

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_last_axis, check_unit_interval
from .._math import align_ranks, dot
from ._phase import AbstractPhaseFunction, PhaseSample, _direction_about
from ._validation import check_coefficient


def _hg(cos_theta: Array, g: Array) -> Array:
    """p_HG as a function of the scattering-angle cosine (not of wo . wi)."""
    g2 = g * g
    denom = 1.0 + g2 - 2.0 * g * cos_theta  # >= (1 - |g|)^2 > 0
    return (1.0 - g2) / (4.0 * math.pi * denom * jnp.sqrt(denom))


class HenyeyGreenstein(AbstractPhaseFunction):
    r"""The Henyey-Greenstein phase function with mean cosine $g$.

    $g > 0$ scatters forward (clouds: about 0.85), $g < 0$ backward, and $g = 0$ is isotropic.
    `g` may hold a batch of values that broadcasts against the directions' batch shape; it is a
    differentiable array field.

    **Arguments:**

    - `g`: the asymmetry parameter, in the open interval (-1, 1); finite. A concrete value
        outside raises `ValueError` naming `g`; a traced one raises
        `equinox.EquinoxRuntimeError`. [dimensionless]

    ```python
    phase = HenyeyGreenstein(0.7)
    s = phase.sample_p(wo, u)           # u (..., 2) in [0, 1)
    phase.p(wo, s.wi) == s.value == s.pdf
    ```

    !!! note "Thesis"
        Chapter 4 (energy transport in a medium; title only in the text).

    ??? cite "References"
        `HenyeyGreenstein1941`; `Pharr2023` §11.3.1 (`HGPhaseFunction`,
        `SampleHenyeyGreenstein`).
    """

    g: Float[Array, "*gbatch"]

    def __init__(self, g: Float[ArrayLike, "*gbatch"]):
        self.g = check_coefficient(g, "g", lower=-1.0, upper=1.0, open_lower=True, open_upper=True)

    def p(
        self, wo: Float[Array, "*#batch 3"], wi: Float[Array, "*#batch 3"]
    ) -> Float[Array, "..."]:
        """$p_{HG}(-\\omega_o\\cdot\\omega_i)$; symmetric in `wo`, `wi`. [sr^-1]"""
        c = dot(as_float_array(wo, "wo"), as_float_array(wi, "wi"))
        c, g = align_ranks(c, self.g)
        return _hg(-c, g)

    def pdf(
        self, wo: Float[Array, "*#batch 3"], wi: Float[Array, "*#batch 3"]
    ) -> Float[Array, "..."]:
        """The density of `sample_p`, equal to `p` (the sampling is exact). [sr^-1]"""
        return self.p(wo, wi)

    def sample_p(self, wo: Float[Array, "*#batch 3"], u: Float[Array, "*#batch 2"]) -> PhaseSample:
        """Sample `wi` from `p(wo, .)`: $\\cos\\theta$ from `u[..., 0]` by the exact inverse
        CDF (module docstring), azimuth $2\\pi$ `u[..., 1]` about $-\\omega_o$."""
        wo = check_last_axis(as_float_array(wo, "wo"), "wo", 3)
        u = check_unit_interval(check_last_axis(as_float_array(u, "u"), "u", 2))
        wo, u = align_ranks(wo, u)
        shape = jnp.broadcast_shapes(wo.shape[:-1], u.shape[:-1])
        u0, g = align_ranks(jnp.broadcast_to(u[..., 0], shape), self.g)
        u1 = u[..., 1]
        a = 1.0 + g * (1.0 - 2.0 * u0)
        a2 = a * a
        one_minus = (1.0 - g) ** 2 * u0 * (2.0 + 2.0 * g * (1.0 - u0)) / a2
        one_plus = (1.0 + g) ** 2 * (1.0 - u0) * (2.0 - 2.0 * g * u0) / a2
        # cos(theta) from the smaller of the two factors: no cancellation near +-1.
        cos_theta = jnp.where(one_minus < one_plus, 1.0 - one_minus, one_plus - 1.0)
        shape = jnp.broadcast_shapes(shape, cos_theta.shape)
        cos_theta = jnp.broadcast_to(cos_theta, shape)
        forward = jnp.broadcast_to(-wo, shape + (3,))
        wi = _direction_about(forward, cos_theta, jnp.broadcast_to(u1, shape))
        val = jnp.broadcast_to(_hg(cos_theta, g), shape)
        return PhaseSample(wi=wi, value=val, pdf=val)

    def mean_cosine(self) -> Float[Array, "*gbatch"]:
        """The parameter $g$: $\\int p_{HG}\\cos\\theta\\,\\mathrm d\\omega = g$. [1]"""
        return self.g
