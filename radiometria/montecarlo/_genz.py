"""Genz's test integrands on the unit cube, with their exact integrals (thesis ch. 6).

Genz (1984) proposed six families to test multidimensional integration rules, each with a
difficulty vector `a` (larger is harder) and a shift `w` in [0, 1]^d. They are smooth
(oscillatory, product peak, corner peak, Gaussian), continuous with kinks, or discontinuous, and
show where QMC's fast convergence holds and where it fails.
"""

import math
from collections.abc import Callable
from itertools import product

import jax.numpy as jnp
import numpy as np
from jax import Array

from .._checks import check_choice

GENZ_FAMILIES = (
    "oscillatory",
    "product_peak",
    "corner_peak",
    "gaussian",
    "continuous",
    "discontinuous",
)


def genz(kind: str, a, w) -> tuple[Callable[[Array], Array], float]:
    r"""One of Genz's six test integrands on $[0,1]^d$ and its exact integral.

    - `"oscillatory"`: $\cos(2\pi w_1 + \sum a_i x_i)$
    - `"product_peak"`: $\prod (a_i^{-2} + (x_i - w_i)^2)^{-1}$
    - `"corner_peak"`: $(1 + \sum a_i x_i)^{-(d+1)}$
    - `"gaussian"`: $\exp(-\sum a_i^2 (x_i - w_i)^2)$
    - `"continuous"`: $\exp(-\sum a_i |x_i - w_i|)$
    - `"discontinuous"`: $\exp(\sum a_i x_i)$ where $x_1 < w_1$ and $x_2 < w_2$, else 0

    **Arguments:**

    - `kind`: one of the names above.
    - `a`: difficulty parameters `(d,)`, > 0. [dimensionless]
    - `w`: shift parameters `(d,)` in [0, 1]. [dimensionless]

    **Returns:**

    `(f, exact)`: the vectorised integrand `f(x (n, d)) -> (n,)` and its integral (a float).
    [dimensionless]

    ??? cite "References"
        `Genz1984`; `Owen2013` ch. 17.
        Thesis ch. 6.
    """
    check_choice(kind, "kind", GENZ_FAMILIES)
    a = np.asarray(a, dtype=np.float64)
    w = np.asarray(w, dtype=np.float64)
    if a.ndim != 1 or w.shape != a.shape or a.size == 0:
        raise ValueError(f"`a` and `w` must be 1D of equal length, got {a.shape}, {w.shape}.")
    if np.any(a <= 0):
        raise ValueError("`a` must be > 0.")
    d = a.size
    if kind == "discontinuous" and d < 2:
        raise ValueError("the discontinuous family needs d >= 2.")

    def row(v):
        return jnp.asarray(v)[None, :]

    if kind == "oscillatory":
        exact = (np.exp(2j * np.pi * w[0]) * np.prod((np.exp(1j * a) - 1) / (1j * a))).real

        def f(x):
            return jnp.cos(2 * math.pi * w[0] + jnp.sum(row(a) * x, axis=-1))

    elif kind == "product_peak":
        exact = np.prod(a * (np.arctan(a * (1 - w)) + np.arctan(a * w)))

        def f(x):
            return jnp.prod(1.0 / (row(a**-2.0) + (x - row(w)) ** 2), axis=-1)

    elif kind == "corner_peak":
        total = 0.0
        for v in product((0, 1), repeat=d):
            total += (-1) ** sum(v) / (1 + float(np.dot(a, v)))
        exact = total / (math.factorial(d) * np.prod(a))

        def f(x):
            return (1.0 + jnp.sum(row(a) * x, axis=-1)) ** (-(d + 1.0))

    elif kind == "gaussian":
        erf = np.vectorize(math.erf)
        exact = np.prod(math.sqrt(math.pi) / (2 * a) * (erf(a * (1 - w)) + erf(a * w)))

        def f(x):
            return jnp.exp(-jnp.sum(row(a**2) * (x - row(w)) ** 2, axis=-1))

    elif kind == "continuous":
        exact = np.prod((2 - np.exp(-a * w) - np.exp(-a * (1 - w))) / a)

        def f(x):
            return jnp.exp(-jnp.sum(row(a) * jnp.abs(x - row(w)), axis=-1))

    else:
        exact = np.prod((np.exp(a[:2] * w[:2]) - 1) / a[:2]) * np.prod((np.exp(a[2:]) - 1) / a[2:])

        def f(x):
            inside = (x[:, 0] < w[0]) & (x[:, 1] < w[1])
            return jnp.where(inside, jnp.exp(jnp.sum(row(a) * x, axis=-1)), 0.0)

    return f, float(exact)
