"""Shared test helpers: tree comparison, convergence slopes, per-dtype tolerances."""

import jax
import jax.numpy as jnp
import numpy as np


def tree_allclose(a, b, *, rtol: float = 1e-10, atol: float = 0.0) -> bool:
    """True when two pytrees have the same structure and all leaves are close."""
    la, ta = jax.tree_util.tree_flatten(a)
    lb, tb = jax.tree_util.tree_flatten(b)
    if ta != tb:
        return False
    return all(
        np.allclose(np.asarray(x), np.asarray(y), rtol=rtol, atol=atol)
        for x, y in zip(la, lb, strict=True)
    )


def convergence_slope(ns, errors) -> float:
    """Least-squares slope of log(error) against log(n)."""
    x = np.log(np.asarray(ns, dtype=float))
    y = np.log(np.asarray(errors, dtype=float))
    return float(np.polyfit(x, y, 1)[0])


def dtype_rtol(dtype) -> float:
    """A relative tolerance for comparing a computation in `dtype` against a float64 reference."""
    return {jnp.dtype(jnp.float32): 1e-5, jnp.dtype(jnp.float64): 1e-12}[jnp.dtype(dtype)]
