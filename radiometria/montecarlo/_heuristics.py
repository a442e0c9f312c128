"""Multiple importance sampling weights (thesis ch. 7): balance and power heuristics.

Veach and Guibas (1995) combine samples from several strategies with weights that sum to one
wherever any strategy can produce the sample; the balance heuristic is provably close to the best
such weighting, the power heuristic (beta = 2) does better when one strategy is much better.
"""

import equinox as eqx
import jax.numpy as jnp
from jax import Array

from .._checks import as_float_array
from .._types import FloatLike


def _ratio(a: Array, b: Array) -> Array:
    """a / (a + b), with 0 where both are 0 and 1 where a is infinite."""
    s = a + b
    ok = s > 0
    r = jnp.where(ok, a / jnp.where(ok, s, 1.0), 0.0)
    return jnp.where(jnp.isinf(a), 1.0, r)


@eqx.filter_jit
def balance_heuristic(
    nf: int | FloatLike, f_pdf: FloatLike, ng: int | FloatLike, g_pdf: FloatLike
) -> Array:
    r"""Balance-heuristic MIS weight of a sample drawn from strategy f, with g as the other one.

    $$w_f = \frac{n_f p_f}{n_f p_f + n_g p_g}$$

    **Arguments:**

    - `nf`, `ng`: numbers of samples taken with each strategy. [dimensionless]
    - `f_pdf`, `g_pdf`: densities of the sample under each strategy, in the same measure.
        [1/measure, e.g. sr^-1]

    **Returns:**

    The weight in [0, 1]; 0 where both densities are 0. [dimensionless]

    ??? cite "References"
        `Veach1995`; `Veach1997` §9.2.2; `Pharr2023` §2.2.3.
        Thesis ch. 7.
    """
    f = as_float_array(nf, "nf") * as_float_array(f_pdf, "f_pdf")
    g = as_float_array(ng, "ng") * as_float_array(g_pdf, "g_pdf")
    return _ratio(f, g)


@eqx.filter_jit
def power_heuristic(
    nf: int | FloatLike, f_pdf: FloatLike, ng: int | FloatLike, g_pdf: FloatLike
) -> Array:
    r"""Power-heuristic (beta = 2) MIS weight of a sample drawn from strategy f.

    $$w_f = \frac{(n_f p_f)^2}{(n_f p_f)^2 + (n_g p_g)^2}$$

    **Arguments:**

    - `nf`, `ng`: numbers of samples taken with each strategy. [dimensionless]
    - `f_pdf`, `g_pdf`: densities of the sample under each strategy, in the same measure.
        [1/measure, e.g. sr^-1]

    **Returns:**

    The weight in [0, 1]; 0 where both densities are 0, 1 where `nf f_pdf` is infinite
    (a delta distribution), as in pbrt. [dimensionless]

    ??? cite "References"
        `Veach1995`; `Veach1997` §9.2.4; `Pharr2023` §2.2.3.
        Thesis ch. 7.
    """
    f = as_float_array(nf, "nf") * as_float_array(f_pdf, "f_pdf")
    g = as_float_array(ng, "ng") * as_float_array(g_pdf, "g_pdf")
    return _ratio(f * f, g * g)


@eqx.filter_jit
def mis_weights(pdfs: FloatLike, counts: FloatLike | None = None, *, beta: float = 1.0) -> Array:
    r"""MIS weights for k strategies at once: $w_i = (n_i p_i)^\beta / \sum_j (n_j p_j)^\beta$.

    **Arguments:**

    - `pdfs`: densities of the same sample under each strategy, strategies on the last axis
        `(..., k)`. [1/measure]
    - `counts`: samples per strategy `(k,)`; all 1 when omitted. [dimensionless]
    - `beta`: the exponent: 1 is the balance heuristic, 2 the power heuristic. [dimensionless]

    **Returns:**

    Weights `(..., k)` summing to 1 along the last axis (all 0 where every density is 0).
    [dimensionless]

    ??? cite "References"
        `Veach1997` §9.2.
        Thesis ch. 7.
    """
    p = as_float_array(pdfs, "pdfs")
    if p.ndim == 0:
        raise ValueError("`pdfs` needs a last axis over strategies, got a scalar.")
    if counts is not None:
        c = as_float_array(counts, "counts")
        if c.shape != (p.shape[-1],):
            raise ValueError(f"`counts` must have shape ({p.shape[-1]},), got {c.shape}.")
        p = p * c.reshape((1,) * (p.ndim - 1) + c.shape)
    q = p**beta
    s = jnp.sum(q, axis=-1, keepdims=True)
    ok = s > 0
    return jnp.where(ok, q / jnp.where(ok, s, 1.0), 0.0)
