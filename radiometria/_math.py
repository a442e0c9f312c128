"""Small array helpers shared by the subpackages (floor 1: imports nothing from radiometria).

Each keeps finite gradients at its singular point with the double-where trick (style.md
section 8): the unsafe operation never sees the value at which its derivative is infinite.
"""

import jax.numpy as jnp
from jax import Array

__all__ = ["align_ranks", "dot", "interpolation_weights", "safe_div", "safe_sqrt"]


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


def interpolation_weights(grid: Array, x: Array, extrapolation: str):
    """Indices `i0`, `i1 = i0 + 1`, weight `t` of `grid[i1]`, and the outside mask for `x`.

    `grid` is 1-D, strictly increasing; `x` has any shape. For "constant" extrapolation `x` is
    clamped into the grid (so `t` is 0 or 1 outside); for "zero" the mask zeroes the result.
    NaN in `x` gives a NaN weight (and is never "outside"), so it propagates.
    """
    n = grid.shape[0]
    below, above = x < grid[0], x > grid[-1]
    # Clamp with `where`, not `clip`: at x == an end sample `clip` passes half the gradient.
    x_in = jnp.where(below, grid[0], jnp.where(above, grid[-1], x))
    i1 = jnp.clip(jnp.searchsorted(grid, x_in, side="right"), 1, n - 1)
    i0 = i1 - 1
    g0, g1 = grid[i0], grid[i1]
    t = (x_in - g0) / (g1 - g0)
    outside = below | above if extrapolation == "zero" else None
    return i0, i1, t, outside
