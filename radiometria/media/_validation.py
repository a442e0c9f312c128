"""Argument checks shared by the media modules (style.md section 9).

Coefficients and phase-function parameters are checked once, where a medium or a phase
function is built, not in the tracer's inner loop. A concrete value outside its domain raises
`ValueError` naming the argument; a traced value (inside `jit` or `vmap`) goes through
`equinox.error_if`, so it raises `equinox.EquinoxRuntimeError` with the same message.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._checks import as_float_array


def _is_concrete(x) -> bool:
    return not isinstance(x, jax.core.Tracer)


def check_coefficient(
    x,
    name: str,
    *,
    lower: float = 0.0,
    upper: float = np.inf,
    open_lower: bool = False,
    open_upper: bool = False,
    unit: str = "",
) -> Array:
    """`x` as a float array with every element finite and in the given interval.

    Concrete input raises `ValueError` naming `name`; traced input is checked with
    `equinox.error_if`. Infinite bounds only allow finite values (NaN and inf always fail).
    """
    x = as_float_array(x, name)
    lb = "(" if open_lower else "["
    ub = ")" if open_upper else "]"
    u = f" [{unit}]" if unit else ""
    what = f"`{name}` must be finite and lie in {lb}{lower}, {upper}{ub}{u}"

    def bad(v, xp):
        below = v <= lower if open_lower else v < lower
        above = v >= upper if open_upper else v > upper
        return ~xp.isfinite(v) | below | above

    if _is_concrete(x):
        v = np.asarray(x)
        mask = bad(v, np)
        if np.any(mask):
            raise ValueError(f"{what}; got {v[mask].ravel()[:4].tolist()}.")
        return x
    return eqx.error_if(x, bad(x, jnp), f"{what}; got a value outside.")
