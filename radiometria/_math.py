"""Small array helpers shared by the subpackages (floor 1: imports nothing from radiometria).

Each keeps finite gradients at its singular point with the double-where trick (style.md
section 8): the unsafe operation never sees the value at which its derivative is infinite.
"""

import jax.numpy as jnp
from jax import Array

__all__ = ["align_ranks", "dot", "safe_div", "safe_sqrt"]


def safe_sqrt(x: Array, *, propagate_nan: bool = False) -> Array:
    """sqrt(max(x, 0)) with a zero (not NaN or inf) gradient where x <= 0 (double-where).

    With `propagate_nan=False` a NaN in `x` gives 0 (and a zero gradient); with
    `propagate_nan=True` it gives NaN. Otherwise the two are identical, bit for bit.
    """
    if propagate_nan:
        nonpos = x <= 0
        return jnp.where(nonpos, 0.0, jnp.sqrt(jnp.where(nonpos, 1.0, x)))
    pos = x > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, x, 1.0)), 0.0)


def safe_div(a: Array, b: Array) -> Array:
    """a / b, and 0 where b == 0, with finite gradients there (double-where)."""
    ok = b != 0
    return jnp.where(ok, a / jnp.where(ok, b, 1.0), 0.0)


def align_ranks(*arrays: Array) -> tuple[Array, ...]:
    """Prepend unit axes so every array has the largest rank (explicit rank promotion).

    Broadcasting between ranks is then legal under `jax_numpy_rank_promotion="raise"`.
    """
    nd = max(jnp.ndim(a) for a in arrays)
    return tuple(jnp.reshape(a, (1,) * (nd - jnp.ndim(a)) + jnp.shape(a)) for a in arrays)


def dot(a: Array, b: Array) -> Array:
    """Dot product over the last axis, `sum(a * b, axis=-1)`, after `align_ranks`."""
    a, b = align_ranks(a, b)
    return jnp.sum(a * b, axis=-1)
