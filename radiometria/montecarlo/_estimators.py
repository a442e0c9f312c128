"""Monte Carlo estimators and variance reduction (thesis ch. 6-7, eq. 2.32-2.35).

Every estimator returns an `Estimate`: the estimate of the integral (`mean`), the estimated
variance of that estimate, the number of samples and the standard error. The integrand code is
the same for MC and QMC: estimators take either a `key` (independent samples) or an explicit
array `u` of uniform variates (e.g. from `sobol` or `halton`).
`integrate` and `convergence_study`, which build on `Estimate`, are in `_integrate.py`.

References: `Owen2013` (ch. 2 plain MC, 8 control and antithetic variates, 9 importance
sampling, 10 stratification, 17 randomised QMC), `Veach1997` (ch. 9, multiple importance
sampling), `Pharr2023` (ch. 2, 8 and 13.7 Russian roulette and splitting).
"""

from collections.abc import Callable, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import Array

from .._checks import as_float_array, check_choice, check_positive_int, check_unit_interval
from .._types import Key
from ._heuristics import mis_weights


class Estimate(eqx.Module):
    """A Monte Carlo estimate with its uncertainty (a pytree, so it jits and vmaps).

    **Fields:**

    - `mean`: the estimate of the integral (or expectation). [unit of the integral]
    - `variance`: estimated variance of `mean` (the sample variance of the terms over `n`).
      [unit^2]
    - `n`: number of samples (or of independent replicates for randomised QMC). [dimensionless]
    - `standard_error`: `sqrt(variance)`. [unit]

    `confidence_interval(level)` gives a normal-theory interval.

    ??? cite "References"
        `Owen2013` §2.1-2.3.
        Thesis ch. 6.
    """

    mean: Array
    variance: Array
    n: Array
    standard_error: Array

    def __init__(self, mean, variance, n):
        self.mean = jnp.asarray(mean)
        self.variance = jnp.asarray(variance)
        self.n = jnp.asarray(n)
        self.standard_error = jnp.sqrt(jnp.maximum(self.variance, 0.0))

    def confidence_interval(self, level: float = 0.95) -> tuple[Array, Array]:
        """Normal-theory interval `mean -/+ z se` covering the integral with probability `level`.

        **Arguments:**

        - `level`: coverage in (0, 1). [dimensionless]
        """
        if not 0 < level < 1:
            raise ValueError(f"`level` must lie in (0, 1), got {level!r}.")
        z = float(jax.scipy.special.ndtri(0.5 + level / 2))
        return self.mean - z * self.standard_error, self.mean + z * self.standard_error


def _terms_estimate(terms: Array, axis: int = 0) -> Estimate:
    n = terms.shape[axis]
    mean = jnp.mean(terms, axis=axis)
    var = jnp.var(terms, axis=axis, ddof=1) / n if n > 1 else jnp.full_like(mean, jnp.inf)
    return Estimate(mean, var, n)


def estimate_mean(values, *, axis: int = 0) -> Estimate:
    r"""Plain Monte Carlo: the sample mean of i.i.d. terms, with its variance $s^2/n$.

    $$\hat I = \frac1n \sum_i Y_i, \qquad \widehat{\mathrm{Var}}(\hat I) = \frac{s^2}{n}$$

    **Arguments:**

    - `values`: the terms `Y_i = f(X_i)/p(X_i)`, samples along `axis`. [unit of the integral]
    - `axis`: the sample axis.

    **Returns:**

    An `Estimate` (other axes are kept, e.g. colour channels).

    !!! note "Thesis"
        Eq. 2.32, the Monte Carlo estimator; with uniform samples on a region A
        (`Y_i = |A| f(X_i)`) it is Eq. 2.33; ch. 6.

    ??? cite "References"
        `Owen2013` §2.1; `Pharr2023` §2.1.3.
    """
    v = as_float_array(values, "values")
    if v.ndim == 0 or v.shape[axis] == 0:
        raise ValueError(f"`values` needs a non-empty sample axis {axis}, got shape {v.shape}.")
    return _terms_estimate(v, axis)


def _variates(n: int | None, dim: int, key: Key | None, u) -> Array:
    if u is not None:
        if key is not None:
            raise ValueError("Pass either `key` or `u`, not both.")
        u = as_float_array(u, "u")
        if u.ndim != 2 or u.shape[1] != dim:
            raise ValueError(f"`u` must have shape (n, {dim}), got {u.shape}.")
        return check_unit_interval(u)
    if key is None:
        raise ValueError("A `key` (or explicit variates `u`) is required.")
    return jax.random.uniform(key, (check_positive_int(n, "n"), dim))


def _values(f: Callable, x) -> Array:
    y = jnp.asarray(f(x))
    n = jax.tree_util.tree_leaves(x)[0].shape[0]
    if y.ndim == 0 or y.shape[0] != n:
        raise ValueError(
            f"The integrand must return one value per sample (leading axis {n}), got {y.shape}."
        )
    return y


def _bcast(w: Array, y: Array) -> Array:
    """Give a per-sample weight `(n,)` the trailing axes of the values `(n, ...)`."""
    return w.reshape(w.shape + (1,) * (y.ndim - w.ndim))


def importance_sampling(
    f: Callable,
    sample: Callable,
    pdf: Callable,
    n: int | None = None,
    *,
    u_dim: int,
    key: Key | None = None,
    u=None,
) -> Estimate:
    r"""Importance-sampled estimate $\frac1n \sum_i f(X_i)/p(X_i)$ with $X_i = $ `sample(u_i)`.

    **Arguments:**

    - `f`: integrand, vectorised: `f(x) -> (n, ...)`. [unit of f]
    - `sample`: warp from variates `(n, u_dim)` to samples `x`.
    - `pdf`: density of the samples, `pdf(x) -> (n,)`. [1/measure]
    - `n`: number of samples (with `key`). [dimensionless]
    - `u_dim`: dimension of the variates. [dimensionless]
    - `key` or `u`: a `jax.random` key, or variates `(n, u_dim)` in [0, 1) (e.g. Sobol points).

    **Returns:**

    An `Estimate` of the integral of f. Samples with `pdf = 0` contribute 0. [unit of f x measure]

    !!! note "Thesis"
        Eq. 2.32; ch. 6-7 (importance sampling).

    ??? cite "References"
        `Owen2013` §9.1; `Pharr2023` §2.2.2.
    """
    x = sample(_variates(n, u_dim, key, u))
    p = jnp.asarray(pdf(x))
    y = _values(f, x)
    ok = p > 0
    terms = jnp.where(_bcast(ok, y), y / _bcast(jnp.where(ok, p, 1.0), y), 0.0)
    return _terms_estimate(terms)


def mis_estimate(
    f: Callable,
    strategies: Sequence[tuple[Callable, Callable, int]],
    *,
    u_dim: int,
    key: Key,
    heuristic: str = "power",
) -> Estimate:
    r"""Multi-sample multiple importance sampling (Veach's combined estimator).

    $$F = \sum_i \frac{1}{n_i}\sum_{j=1}^{n_i} w_i(X_{ij}) \frac{f(X_{ij})}{p_i(X_{ij})}$$

    with balance or power heuristic weights computed from every strategy's density.

    **Arguments:**

    - `f`: integrand, vectorised. [unit of f]
    - `strategies`: `(sample, pdf, n_i)` triples; `sample(u (n_i, u_dim)) -> x`,
      `pdf(x) -> (n_i,)` [1/measure]. Every strategy's pdf is evaluated on every sample.
    - `u_dim`: variates per sample. [dimensionless]
    - `key`: `jax.random` key.
    - `heuristic`: `"balance"` or `"power"` (beta = 2).

    **Returns:**

    An `Estimate`; its variance is the sum of the per-strategy variances.

    ??? cite "References"
        `Veach1995`; `Veach1997` §9.2; `Pharr2023` §2.2.3.
        Thesis ch. 7.
    """
    check_choice(heuristic, "heuristic", ["balance", "power"])
    beta = 1.0 if heuristic == "balance" else 2.0
    if len(strategies) == 0:
        raise ValueError("`strategies` must not be empty.")
    counts = jnp.asarray([float(check_positive_int(s[2], "n_i")) for s in strategies])
    keys = jax.random.split(key, len(strategies))
    mean = 0.0
    var = 0.0
    for i, (sample, _, n_i) in enumerate(strategies):
        x = sample(jax.random.uniform(keys[i], (n_i, u_dim)))
        pdfs = jnp.stack([jnp.asarray(s[1](x)) for s in strategies], axis=-1)  # (n_i, k)
        w = mis_weights(pdfs, counts, beta=beta)[:, i]
        y = _values(f, x)
        p_i = pdfs[:, i]
        ok = p_i > 0
        terms = jnp.where(_bcast(ok, y), _bcast(w, y) * y / _bcast(jnp.where(ok, p_i, 1.0), y), 0.0)
        est = _terms_estimate(terms)
        mean = mean + est.mean
        var = var + est.variance
    return Estimate(mean, var, int(sum(s[2] for s in strategies)))


def one_sample_mis(
    f: Callable,
    strategies: Sequence[tuple[Callable, Callable]],
    probabilities,
    n: int,
    *,
    u_dim: int,
    key: Key,
    heuristic: str = "balance",
) -> Estimate:
    r"""One-sample MIS: each sample picks strategy i with probability $c_i$, then
    $F = w_i(X) f(X) / (c_i p_i(X))$.

    With the balance heuristic this is $f(X) / \sum_j c_j p_j(X)$, sampling from the mixture.

    **Arguments:**

    - `f`: integrand, vectorised. [unit of f]
    - `strategies`: `(sample, pdf)` pairs, as in `mis_estimate`. [pdf: 1/measure]
    - `probabilities`: selection probabilities `(k,)`, positive, summing to 1. [dimensionless]
    - `n`: number of samples. [dimensionless]
    - `u_dim`: variates per sample. [dimensionless]
    - `key`: `jax.random` key.
    - `heuristic`: `"balance"` or `"power"`.

    **Returns:**

    An `Estimate`.

    ??? cite "References"
        `Veach1997` §9.2.4.
        Thesis ch. 7.
    """
    check_choice(heuristic, "heuristic", ["balance", "power"])
    c = as_float_array(probabilities, "probabilities")
    if c.shape != (len(strategies),):
        raise ValueError(f"`probabilities` must have shape ({len(strategies)},), got {c.shape}.")
    c = eqx.error_if(
        c, (c <= 0) | (jnp.abs(jnp.sum(c) - 1) > 1e-6), "`probabilities` must be > 0 and sum to 1."
    )
    k_sel, k_u = jax.random.split(key)
    sel = jax.random.choice(k_sel, len(strategies), (n,), p=c)
    u = jax.random.uniform(k_u, (n, u_dim))
    # Evaluate every strategy's warp and keep the selected one (k is small).
    xs = jnp.stack([jnp.asarray(s[0](u)) for s in strategies])  # (k, n, ...)
    x = xs[sel, jnp.arange(n)]
    pdfs = jnp.stack([jnp.asarray(s[1](x)) for s in strategies], axis=-1)
    w = mis_weights(pdfs, c, beta=1.0 if heuristic == "balance" else 2.0)
    w_sel = jnp.take_along_axis(w, sel[:, None], axis=1)[:, 0]
    p_sel = jnp.take_along_axis(pdfs, sel[:, None], axis=1)[:, 0]
    y = _values(f, x)
    denom = c[sel] * p_sel
    ok = denom > 0
    terms = jnp.where(
        _bcast(ok, y), _bcast(w_sel, y) * y / _bcast(jnp.where(ok, denom, 1.0), y), 0.0
    )
    return _terms_estimate(terms)


def stratified_estimate(
    f: Callable, strata: Sequence[int], n_per_stratum: int, *, key: Key
) -> Estimate:
    r"""Stratified estimate of $\int_{[0,1)^d} f$: `n_per_stratum` uniform points in each cell.

    $$\hat I = \sum_h V_h \bar Y_h, \qquad \widehat{\mathrm{Var}} = \sum_h V_h^2 s_h^2 / n_h$$

    **Arguments:**

    - `f`: integrand on the unit cube, vectorised: `f(x (n, d)) -> (n, ...)`. [unit of f]
    - `strata`: cells per axis `(s_1, ..., s_d)`. [dimensionless]
    - `n_per_stratum`: samples per cell, >= 2 for a variance estimate. [dimensionless]
    - `key`: `jax.random` key.

    **Returns:**

    An `Estimate`.

    ??? cite "References"
        `Owen2013` §10.1; `Pharr2023` §8.5.
        Thesis ch. 7.
    """
    strata = tuple(check_positive_int(s, "strata") for s in strata)
    m = check_positive_int(n_per_stratum, "n_per_stratum")
    d = len(strata)
    grids = jnp.meshgrid(*[jnp.arange(s, dtype=float) for s in strata], indexing="ij")
    cells = jnp.stack([g.reshape(-1) for g in grids], axis=-1)  # (H, d)
    h = cells.shape[0]
    offs = jax.random.uniform(key, (h, m, d))
    x = (cells[:, None, :] + offs) / jnp.asarray(strata, dtype=float)[None, None, :]
    y = _values(f, x.reshape(h * m, d))
    y = y.reshape((h, m) + y.shape[1:])
    vol = 1.0 / h
    mean = vol * jnp.sum(jnp.mean(y, axis=1), axis=0)
    if m > 1:
        var = vol**2 * jnp.sum(jnp.var(y, axis=1, ddof=1) / m, axis=0)
    else:
        var = jnp.full_like(mean, jnp.inf)
    return Estimate(mean, var, h * m)


def control_variate(values, control_values, control_mean, *, beta=None) -> Estimate:
    r"""Control-variate estimate $\bar Y - \hat\beta(\bar G - \mu_G)$ with the estimated optimal
    coefficient $\hat\beta = \widehat{\mathrm{Cov}}(Y, G)/\widehat{\mathrm{Var}}(G)$.

    **Arguments:**

    - `values`: terms `Y_i` `(n, ...)`. [unit of the integral]
    - `control_values`: control terms `G_i` `(n, ...)` on the same samples. [unit of G]
    - `control_mean`: the known expectation of G. [unit of G]
    - `beta`: a fixed coefficient instead of the estimated optimum. [unit of Y / unit of G]

    **Returns:**

    An `Estimate`; the variance is that of the residual `Y - beta G` over `n` (asymptotically
    `(1 - rho^2) Var(Y)/n`).

    ??? cite "References"
        `Owen2013` §8.9.
        Thesis ch. 7.
    """
    y = as_float_array(values, "values")
    g = as_float_array(control_values, "control_values")
    if y.shape != g.shape or y.ndim == 0 or y.shape[0] < 3:
        raise ValueError(
            "`values` and `control_values` must share a shape with >= 3 samples, got "
            f"{y.shape}, {g.shape}."
        )
    mu = as_float_array(control_mean, "control_mean")
    n = y.shape[0]
    if beta is None:
        yc = y - jnp.mean(y, axis=0)
        gc = g - jnp.mean(g, axis=0)
        var_g = jnp.sum(gc * gc, axis=0)
        beta = jnp.where(
            var_g > 0, jnp.sum(yc * gc, axis=0) / jnp.where(var_g > 0, var_g, 1.0), 0.0
        )
    else:
        beta = as_float_array(beta, "beta")
    resid = y - beta * g
    mean = jnp.mean(y, axis=0) - beta * (jnp.mean(g, axis=0) - mu)
    var = jnp.var(resid, axis=0, ddof=2) / n  # one more dof spent on beta
    return Estimate(mean, var, n)


def antithetic(
    f: Callable, n: int | None, *, u_dim: int, key: Key | None = None, u=None
) -> Estimate:
    r"""Antithetic-variates estimate of $\int_{[0,1)^d} f$: pairs $(u, 1-u)$ averaged.

    **Arguments:**

    - `f`: integrand on the unit cube, vectorised. [unit of f]
    - `n`: number of pairs (2n evaluations). [dimensionless]
    - `u_dim`: dimension. [dimensionless]
    - `key` or `u`: key, or variates `(n, u_dim)` for the first member of each pair.

    **Returns:**

    An `Estimate` over the `n` pair means (variance reduced for monotone f).

    ??? cite "References"
        `Owen2013` §8.2.
        Thesis ch. 7.
    """
    u = _variates(n, u_dim, key, u)
    u2 = jnp.minimum(1.0 - u, 1.0 - jnp.finfo(u.dtype).epsneg)
    terms = 0.5 * (_values(f, u) + _values(f, u2))
    return _terms_estimate(terms)


def russian_roulette(value, survival_probability, u):
    r"""Russian roulette: keep `value / q` with probability `q`, else 0 (unbiased).

    **Arguments:**

    - `value`: the contribution, any shape. [any unit]
    - `survival_probability`: q in (0, 1]; broadcast. [dimensionless]
    - `u`: uniform variates in [0, 1), broadcast. [dimensionless]

    **Returns:**

    `value / q` where `u < q`, else 0 (same unit as `value`). Paths are killed by zeroing, never
    by branching, so it runs in a `lax.scan` bounce loop.

    ??? cite "References"
        `Arvo1990`; `Pharr2023` §2.2.4, §13.7.
        Thesis ch. 7.
    """
    v = as_float_array(value, "value")
    q = as_float_array(survival_probability, "survival_probability")
    u = as_float_array(u, "u")
    alive = u < q
    return jnp.where(alive, v / jnp.where(alive, q, 1.0), 0.0)


def roulette_and_split(weight, target, u) -> tuple[Array, Array]:
    r"""Weight-window Russian roulette and splitting towards a `target` weight.

    A weight below the target survives with probability `weight/target` and becomes `target`;
    a weight above it splits into `floor(r)` or `ceil(r)` copies (r = weight/target, rounded up
    with probability `frac(r)`), each carrying `weight/r`. The expected total weight equals the
    input weight, so estimators stay unbiased.

    **Arguments:**

    - `weight`: current path or sample weights, >= 0. [any unit]
    - `target`: the desired weight, > 0. [same unit]
    - `u`: uniform variates in [0, 1), broadcast. [dimensionless]

    **Returns:**

    `(copies, new_weight)`: int32 number of copies (0 means killed) and the weight of each.

    ??? cite "References"
        `Vorba2016`; `Pharr2023` §2.2.4.
        Thesis ch. 7.
    """
    w = as_float_array(weight, "weight")
    t = as_float_array(target, "target")
    u = as_float_array(u, "u")
    r = w / t
    fl = jnp.floor(r)
    # Below the target: survive with probability r. Above: floor(r) or ceil(r) copies, E = r.
    copies = jnp.where(r < 1, (u < r).astype(r.dtype), fl + (u < r - fl).astype(r.dtype))
    # Either way each surviving copy carries weight / E[copies] = target.
    return copies.astype(jnp.int32), jnp.broadcast_to(t, copies.shape).astype(w.dtype)


def weighted_importance_sampling(values, weights, *, axis: int = 0) -> Estimate:
    r"""Self-normalised (weighted) importance sampling $\sum_i w_i r_i / \sum_i w_i$.

    With filter weights $w_i = f(x - x_i)$ for uniform samples this is the pixel reconstruction
    of thesis eq. 2.34; with $w_i = f/p$ for filter-importance-sampled points it is eq. 2.35.
    The estimator is consistent but biased at O(1/n); its variance is estimated by the delta
    method, $\sum_i w_i^2 (r_i - \hat I)^2 / (\sum_i w_i)^2$.

    **Arguments:**

    - `values`: the values `r_i` (e.g. radiance samples) `(n, ...)`. [unit of r]
    - `weights`: weights `w_i` `(n,)`, not all 0. [any unit]
    - `axis`: the sample axis (0).

    **Returns:**

    An `Estimate` of the weighted mean.

    !!! note "Thesis"
        Eq. 2.34 and eq. 2.35.

    ??? cite "References"
        `Owen2013` §9.2; `Pharr2023` §5.4.3, §8.8.
        Thesis sec. 2.3.2.
    """
    if axis != 0:
        raise ValueError("only `axis=0` is supported.")
    r = as_float_array(values, "values")
    w = as_float_array(weights, "weights")
    if r.ndim == 0 or w.shape != r.shape[:1]:
        raise ValueError(
            f"`weights` must have shape ({r.shape[0] if r.ndim else '?'},), got {w.shape}."
        )
    sw = jnp.sum(w)
    sw = eqx.error_if(sw, sw == 0, "`weights` sum to 0: the weighted estimate is undefined.")
    mean = jnp.sum(_bcast(w, r) * r, axis=0) / sw
    var = jnp.sum(_bcast(w * w, r) * (r - mean) ** 2, axis=0) / sw**2
    return Estimate(mean, var, r.shape[0])


def filter_importance_sampling(
    r: Callable,
    filter_fn: Callable,
    filter_sample: Callable,
    filter_pdf: Callable,
    n: int,
    *,
    key: Key | None = None,
    u=None,
    weighted: bool = False,
) -> Estimate:
    r"""Filtered pixel value $\int f(x') r(x') dx'$ by filter importance sampling.

    Offsets are drawn from a density p close to the filter f (`filter_sample(u) -> (n, 2)`),
    so the terms are $f/p \cdot r$: for p proportional to |f| this is
    $(\int |f|) \operatorname{sgn}(f) r$ (thesis, after eq. 2.34). With `weighted=True` the
    terms are self-normalised by the weights $w = f/p$, eq. 2.35.

    **Arguments:**

    - `r`: the image function at offsets, vectorised `r(x (n, 2)) -> (n, ...)`. [e.g. radiance]
    - `filter_fn`: filter `f(x (n, 2)) -> (n,)`. [1/area]
    - `filter_sample`: warp `u (n, 2) -> x (n, 2)` [pixels]; `filter_pdf(x) -> (n,)` its density.
      [1/area]
    - `n`: number of samples. [dimensionless]
    - `key` or `u`: key or variates `(n, 2)`.
    - `weighted`: use eq. 2.35 instead of the plain estimator (2.32 with p ~ f).

    **Returns:**

    An `Estimate`.

    !!! note "Thesis"
        Eq. 2.32, 2.35, section 2.3.2.

    ??? cite "References"
        `Ernst2006`; `Pharr2023` §8.8.
        Thesis sec. 2.3.2.
    """
    x = filter_sample(_variates(n, 2, key, u))
    p = jnp.asarray(filter_pdf(x))
    fv = jnp.asarray(filter_fn(x))
    ok = p > 0
    w = jnp.where(ok, fv / jnp.where(ok, p, 1.0), 0.0)
    y = _values(r, x)
    if weighted:
        return weighted_importance_sampling(y, w)
    return _terms_estimate(_bcast(w, y) * y)
