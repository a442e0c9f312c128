"""Integration over boxes and directions, and convergence studies (thesis ch. 6).

`integrate` estimates an integral over a box, the hemisphere or the sphere with plain MC or a
randomised QMC point set (stratified, Latin hypercube, Owen-scrambled Sobol and Halton, shifted
rank-1 lattice) and reports an honest error from independent replicates; `convergence_study`
measures the RMSE of those estimates against the number of points and fits the log-log slope.
Both build on the `Estimate` of `_estimators.py`.

References: `Owen2013` (ch. 2 plain MC, 17 randomised QMC), `Owen1997`, `Pharr2023` (§2.1).
"""

import functools
from collections.abc import Callable, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import Array

from .._checks import check_choice, check_positive_int
from .._types import Key
from ._estimators import Estimate, _terms_estimate, _values
from ._halton import halton
from ._samplers import hash_uniform, latin_hypercube, rank1_lattice, stratified
from ._sobol import sobol
from ._warps import sample_uniform_hemisphere, sample_uniform_sphere

_METHODS = ("mc", "stratified", "lhs", "sobol", "halton", "lattice")


def _unit_points(method: str, n: int, d: int, key: Key) -> Array:
    dtype = jnp.result_type(float)
    if method == "mc":
        # Counter-based hash uniforms: independent, and fused with the integrand by XLA.
        return hash_uniform(key, n, d, dtype)
    if method == "lhs":
        return latin_hypercube(n, d, key=key)
    if method == "sobol":
        return sobol(n, d, scramble="owen", key=key, allow_unbalanced=True)
    if method == "halton":
        return halton(n, d, scramble="owen", key=key)
    if method == "lattice":
        return rank1_lattice(n, d, key=key)
    # stratified: a jittered grid of s^d cells, one point each.
    s = max(1, int(round(n ** (1.0 / d))))
    if s**d != n:
        raise ValueError(
            f"method='stratified' needs n = s^d; got n = {n}, d = {d} (try n = {s**d})."
        )
    return stratified((s,) * d, key=key)


def _domain_map(domain, d_box: int | None):
    """-> (dim of variates, map u -> points, volume or 1/pdf factor).

    The variates come from this module's own point sets, so the warps skip their check."""
    if isinstance(domain, str):
        check_choice(domain, "domain", ["hemisphere", "sphere", "unit_cube"])
        if domain == "hemisphere":
            return 2, lambda u: sample_uniform_hemisphere(u, check=False), 2 * jnp.pi
        if domain == "sphere":
            return 2, lambda u: sample_uniform_sphere(u, check=False), 4 * jnp.pi
        if d_box is None:
            raise ValueError("domain='unit_cube' needs `dim`.")
        return d_box, lambda u: u, 1.0
    box = jnp.asarray(domain, dtype=jnp.result_type(float))
    if box.ndim != 2 or box.shape[1] != 2:
        raise ValueError(
            "`domain` must be 'hemisphere', 'sphere', 'unit_cube' or a box ((a, b), ...), "
            f"got {domain!r}."
        )
    lo, hi = box[:, 0], box[:, 1]
    return box.shape[0], lambda u: lo[None, :] + u * (hi - lo)[None, :], jnp.prod(hi - lo)


@eqx.filter_jit
def integrate(
    f: Callable,
    domain,
    n: int,
    *,
    method: str = "mc",
    key: Key,
    n_replicates: int = 16,
    dim: int | None = None,
) -> Estimate:
    r"""Integrate `f` over a box, the unit hemisphere or the unit sphere.

    Plain MC (`method="mc"`, independent points from `independent(..., generator="hash")`)
    reports the sample standard error of its `n` points. The other
    methods (`"stratified"` jittered grid, `"lhs"`, `"sobol"` Owen-scrambled, `"halton"`
    Owen-scrambled, `"lattice"` randomly shifted) are randomised: the estimate is the mean of
    `n_replicates` independent replicates of `n` points each and its variance comes from the
    spread of the replicates (`Owen2013` §17), so the error estimate is honest for QMC too.

    **Arguments:**

    - `f`: integrand, vectorised: points `(n, d)` (for a box) or unit directions `(n, 3)` (for
      `"hemisphere"` (+z) / `"sphere"`, solid-angle measure) -> `(n,)` or `(n, ...)`. [unit of f]
    - `domain`: `"hemisphere"`, `"sphere"`, `"unit_cube"` (with `dim`) or a box
      `((a_1, b_1), ..., (a_d, b_d))`. [unit of the coordinates]
    - `n`: points per replicate. [dimensionless]
    - `method`: one of `"mc"`, `"stratified"`, `"lhs"`, `"sobol"`, `"halton"`, `"lattice"`.
    - `key`: `jax.random` key.
    - `n_replicates`: independent randomisations for the non-MC methods, >= 2. [dimensionless]
    - `dim`: dimension for `"unit_cube"`. [dimensionless]

    **Returns:**

    An `Estimate` of the integral (`n` is the number of samples for MC, the number of
    replicates otherwise). [unit of f x measure (volume or sr)]

    ??? cite "References"
        `Owen2013` ch. 2, 17; `Pharr2023` §2.1.
        Thesis ch. 6.
    """
    check_choice(method, "method", _METHODS)
    n = check_positive_int(n, "n")
    dim_u, to_domain, scale = _domain_map(domain, dim)
    if method == "mc":
        x = to_domain(_unit_points("mc", n, dim_u, key))
        return _terms_estimate(scale * _values(f, x))
    r = check_positive_int(n_replicates, "n_replicates", minimum=2)

    def replicate(k):
        x = to_domain(_unit_points(method, n, dim_u, k))
        return scale * jnp.mean(_values(f, x), axis=0)

    return _terms_estimate(jax.vmap(replicate)(jax.random.split(key, r)))


class ConvergenceStudy(eqx.Module):
    """Result of `convergence_study`: RMSE against n and its log-log fit.

    **Fields:**

    - `ns`: sample counts `(k,)`. [dimensionless]
    - `rmse`: root-mean-square error over the replicates at each n `(k,)`. [unit of the integral]
    - `slope`, `intercept`: least-squares fit of `log(rmse) = intercept + slope log(n)`;
      plain MC gives about -1/2, Owen-scrambled Sobol about -3/2 for smooth integrands.

    ??? cite "References"
        `Owen2013` §17.3.
        Thesis ch. 6.
    """

    ns: Array
    rmse: Array
    slope: Array
    intercept: Array


def convergence_study(
    f: Callable,
    exact: float,
    ns: Sequence[int],
    *,
    method: str = "mc",
    dim: int,
    key: Key,
    n_replicates: int = 32,
) -> ConvergenceStudy:
    r"""RMSE of `integrate(f, "unit_cube", n, method=...)` against n, with a log-log fit.

    **Arguments:**

    - `f`: integrand on the unit cube `[0, 1)^dim`, vectorised. [unit of f]
    - `exact`: the exact integral. [unit of f]
    - `ns`: sample counts (powers of two for Sobol). [dimensionless]
    - `method`: as in `integrate`.
    - `dim`: dimension. [dimensionless]
    - `key`: `jax.random` key; each n gets independent replicates.
    - `n_replicates`: independent estimates per n. [dimensionless]

    **Returns:**

    A `ConvergenceStudy`.

    ??? cite "References"
        `Owen2013` §17.3; `Owen1997`.
        Thesis ch. 6.
    """
    check_choice(method, "method", _METHODS)
    ns = [check_positive_int(m, "ns") for m in ns]
    if len(ns) < 2:
        raise ValueError("`ns` needs at least two sample counts.")
    r = check_positive_int(n_replicates, "n_replicates")
    d = check_positive_int(dim, "dim")
    keys = jax.random.split(key, r)
    if method in ("mc", "sobol", "halton"):
        # Extensible sequences: the first m points of one long replicate are a replicate of
        # size m (for Sobol, a scrambled (t, m, d)-net when m is a power of two).
        n_max = max(ns)

        def prefix_errors(k):
            y = _values(f, _unit_points(method, n_max, d, k))
            c = jnp.cumsum(y, axis=0)
            return jnp.stack([c[m - 1] / m for m in ns]) - exact

        # Replicates in vmapped batches of 8: the points of all r replicates at once would
        # hold r x n_max x dim scrambled coordinates and their intermediates (GBs at 2^14).
        errs = jax.lax.map(prefix_errors, keys, batch_size=min(r, 8))  # (r, len(ns))
    else:
        # One compiled program per n (the point sets differ in shape), replicates in batches.
        @functools.partial(jax.jit, static_argnums=0)
        def means(m, keys):
            def one(k):
                return jnp.mean(_values(f, _unit_points(method, m, d, k)))

            return jax.lax.map(one, keys, batch_size=min(r, 8))

        errs = jnp.stack([means(m, keys) for m in ns], axis=1) - exact
    rmse = jnp.sqrt(jnp.mean(errs**2, axis=0))
    logn = jnp.log(jnp.asarray(ns, dtype=rmse.dtype))
    slope, intercept = jnp.polyfit(logn, jnp.log(rmse), 1)
    return ConvergenceStudy(jnp.asarray(ns), rmse, slope, intercept)
