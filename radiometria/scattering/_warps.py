"""Private sampling warps tuned for XLA's CPU backend (used by the BxDF samplers).

`radiometria.montecarlo` holds the public, validated warps; these unchecked versions avoid
`sin`/`cos`, which XLA's CPU backend lowers to scalar library calls (about 10 ns per element
against about 1 ns for the polynomials of `radiometria._math.sincos_reduced`), because the
BxDF samplers run in the renderer's inner loop.
"""

import jax.numpy as jnp
from jax import Array

from .._math import sincos_reduced


def _sample_disk_concentric(u0: Array, u1: Array) -> tuple[Array, Array]:
    """Shirley-Chiu concentric mapping of [0,1)^2 to the unit disk (`Shirley1997`)."""
    a = 2.0 * u0 - 1.0
    b = 2.0 * u1 - 1.0
    use_a = jnp.abs(a) > jnp.abs(b)
    r = jnp.where(use_a, a, b)
    # phi in [-pi/4, pi/4]; the angle is phi (branch a) or pi/2 - phi (branch b).
    num = jnp.where(use_a, b, a)
    den = jnp.where(r == 0, 1.0, r)
    s, c = sincos_reduced((jnp.pi / 4.0) * (num / den))
    x = r * jnp.where(use_a, c, s)
    y = r * jnp.where(use_a, s, c)
    return x, y
