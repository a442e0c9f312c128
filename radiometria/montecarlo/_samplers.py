"""Point sets in [0, 1)^d other than Sobol and Halton (thesis ch. 5).

Independent uniform points, jittered stratification in any dimension, Latin hypercube samples,
rank-1 lattices and the R_d Kronecker sequence, each with an explicit `jax.random` key where it is
random. All return `(n, d)` arrays in [0, 1) and run under `jit` with `n`, `d` static.
"""

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from .._bits import mix32, uint32_to_unit_float
from .._checks import check_choice, check_positive_int
from .._types import Float, Key


def _dtype(dtype):
    dtype = jnp.result_type(float) if dtype is None else jnp.dtype(dtype)
    if not jnp.issubdtype(dtype, jnp.floating):
        raise TypeError(f"`dtype` must be a floating dtype, got {dtype}.")
    return dtype


def _check_sequence_options(scramble, key, dtype, scrambles: tuple):
    """Validate the `scramble`, `key` and `dtype` arguments shared by `halton` and `sobol`.

    Returns `(scramble, dtype)` with `"none"` mapped to None and `dtype` resolved.
    """
    if scramble is not None:
        check_choice(scramble, "scramble", [s for s in scrambles if s is not None])
    scramble = None if scramble == "none" else scramble
    if scramble is not None and key is None:
        raise ValueError(f"scramble={scramble!r} needs a `key`.")
    if scramble is None and key is not None:
        raise ValueError(
            "A `key` was given but `scramble` is None; pass scramble='owen' (or another)."
        )
    return scramble, _dtype(dtype)


def _below_one(x: Array) -> Array:
    return jnp.minimum(x, 1.0 - jnp.finfo(x.dtype).epsneg)


def hash_uniform(key: Key, n: int, d: int, dtype) -> Array:
    """Counter-based uniforms: two rounds of `lowbias32` over (row, column) with key-derived seeds.

    Every variate is an independent function of its index, so XLA fuses generation with the
    integrand and nothing is written to memory; far cheaper on CPU than threefry.
    """
    seeds = jax.random.bits(key, (2,), jnp.uint32)
    row = jnp.arange(n, dtype=jnp.uint32)[:, None]
    col = jnp.arange(d, dtype=jnp.uint32)[None, :]
    h = mix32(row ^ seeds[0])
    h = mix32(h ^ (col * np.uint32(0x9E3779B9) + seeds[1]))
    return uint32_to_unit_float(h, dtype)


def independent(
    n: int, d: int, *, key: Key, dtype=None, generator: str = "threefry"
) -> Float[Array, "n d"]:
    """`n` independent uniform points in [0, 1)^d (plain Monte Carlo).

    **Arguments:**

    - `n`, `d`: number of points and dimension, >= 1. [dimensionless]
    - `key`: `jax.random` key.
    - `dtype`: floating dtype (JAX's default float by default).
    - `generator`: `"threefry"` (`jax.random.uniform`, the default) or `"hash"`: a
      counter-based hash of the point index (two rounds of Wellons' `lowbias32` with
      key-derived seeds; 32 random bits per variate), which fuses with the integrand and is
      several times faster on CPU.

    **Returns:**

    Points `(n, d)`. [dimensionless]

    ??? cite "References"
        `Owen2013` ch. 2-3; `Pharr2023` §8.3.
        Thesis ch. 6.
    """
    n = check_positive_int(n, "n")
    d = check_positive_int(d, "d")
    if generator == "hash":
        if n * d > 2**32:
            raise ValueError("generator='hash' needs n * d <= 2^32.")
        return hash_uniform(key, n, d, _dtype(dtype))
    if generator != "threefry":
        raise ValueError(f"Unknown generator {generator!r}; valid values are: 'threefry', 'hash'.")
    return jax.random.uniform(key, (n, d), dtype=_dtype(dtype))


def stratified(strata, *, key: Key, jitter: bool = True, dtype=None) -> Array:
    """Jittered stratified points: one point in each cell of a grid over [0, 1)^d.

    **Arguments:**

    - `strata`: cells per axis, an int (1D) or a tuple `(s_1, ..., s_d)`; the number of points
      is the product. [dimensionless]
    - `key`: `jax.random` key (unused when `jitter=False`, but still required for a uniform
      signature).
    - `jitter`: a uniform point per cell (`True`) or the cell centres (`False`).
    - `dtype`: floating dtype.

    **Returns:**

    Points `(prod(strata), d)`, cells in row-major order (the last axis fastest). [dimensionless]

    ??? cite "References"
        `Owen2013` ch. 10; `Pharr2023` §8.5.
        Thesis ch. 7.
    """
    strata = (strata,) if isinstance(strata, int | np.integer) else tuple(strata)
    if len(strata) == 0:
        raise ValueError("`strata` must name at least one axis.")
    strata = tuple(check_positive_int(s, "strata") for s in strata)
    dtype = _dtype(dtype)
    d = len(strata)
    grids = jnp.meshgrid(*[jnp.arange(s, dtype=dtype) for s in strata], indexing="ij")
    cells = jnp.stack([g.reshape(-1) for g in grids], axis=-1)
    n = cells.shape[0]
    offs = jax.random.uniform(key, (n, d), dtype=dtype) if jitter else jnp.full((n, d), 0.5, dtype)
    return _below_one((cells + offs) / jnp.asarray(strata, dtype=dtype)[None, :])


def latin_hypercube(n: int, d: int, *, key: Key, dtype=None) -> Float[Array, "n d"]:
    """Latin hypercube sample: each axis has exactly one point in each of its `n` strata.

    Independent random permutations of the strata per axis, jittered inside each stratum.

    **Arguments:**

    - `n`, `d`: number of points and dimension, >= 1. [dimensionless]
    - `key`: `jax.random` key.
    - `dtype`: floating dtype.

    **Returns:**

    Points `(n, d)`. [dimensionless]

    ??? cite "References"
        `McKay1979`; `Owen2013` ch. 10; `Pharr2023` §8.5.
        Thesis ch. 7.
    """
    n = check_positive_int(n, "n")
    d = check_positive_int(d, "d")
    dtype = _dtype(dtype)
    k_perm, k_jit = jax.random.split(key)
    perms = jnp.argsort(jax.random.uniform(k_perm, (n, d)), axis=0).astype(dtype)
    return _below_one((perms + jax.random.uniform(k_jit, (n, d), dtype=dtype)) / n)


@functools.lru_cache(maxsize=32)
def _rd_alpha(d: int) -> np.ndarray:
    """Roberts' R_d increments: alpha_j = phi_d^-(j+1), phi_d the root > 0 of x^(d+1) = x + 1."""
    x = 2.0
    for _ in range(64):  # Newton iteration, converges from x = 2 for every d
        x -= (x ** (d + 1) - x - 1) / ((d + 1) * x**d - 1)
    return np.array([x ** -(j + 1) for j in range(d)])


def kronecker(
    n: int, d: int, *, alpha=None, key: Key | None = None, skip: int = 0, dtype=None
) -> Float[Array, "n d"]:
    r"""Kronecker (additive recurrence) points $x_i = \{s + i\,\alpha\}$, by default Roberts' R_d.

    Computed in 32-bit fixed point, so `i alpha mod 1` is exact for every `i < 2^32` and the
    points do not degrade with the index as a float evaluation would.

    **Arguments:**

    - `n`, `d`: number of points and dimension, >= 1. [dimensionless]
    - `alpha`: increments `(d,)` in (0, 1); the R_d sequence (generalised golden ratio) by
      default. [dimensionless]
    - `key`: optional `jax.random` key for a uniform random shift `s` (Cranley-Patterson
      rotation); without one, `s = 0`.
    - `skip`: index of the first point. [dimensionless]
    - `dtype`: floating dtype.

    **Returns:**

    Points `(n, d)` in [0, 1). [dimensionless]

    ??? cite "References"
        `Roberts2018`; `Cranley1976`; `Owen2013` ch. 15.
        Thesis ch. 5.
    """
    n = check_positive_int(n, "n")
    d = check_positive_int(d, "d")
    skip = check_positive_int(skip, "skip", minimum=0)
    dtype = _dtype(dtype)
    a = _rd_alpha(d) if alpha is None else np.asarray(alpha, dtype=np.float64)
    if a.shape != (d,):
        raise ValueError(f"`alpha` must have shape ({d},), got {a.shape}.")
    if np.any((a <= 0) | (a >= 1)):
        raise ValueError("`alpha` entries must lie in (0, 1).")
    a_fix = jnp.asarray(np.round(a * 2.0**32).astype(np.uint64).astype(np.uint32))
    return _kronecker(a_fix, key, n, skip, dtype)


@functools.partial(jax.jit, static_argnames=("n", "skip", "dtype"))
def _kronecker(a_fix, key, n, skip, dtype):
    d = a_fix.shape[0]
    i = jnp.asarray(skip, jnp.uint32) + jnp.arange(n, dtype=jnp.uint32)
    x = i[:, None] * a_fix[None, :]  # wraps mod 2^32: the fractional part in fixed point
    if key is not None:
        x = x + jax.random.bits(key, (1, d), jnp.uint32)
    return uint32_to_unit_float(x, dtype)


def _fibonacci(n: int) -> tuple[int, int] | None:
    a, b = 1, 1
    while b < n:
        a, b = b, a + b
    return (a, b) if b == n else None


def rank1_lattice(
    n: int, d: int, *, generating_vector=None, key: Key | None = None, dtype=None
) -> Float[Array, "n d"]:
    r"""Rank-1 lattice points $x_i = \{ i z / n + s \}$, optionally randomly shifted.

    **Arguments:**

    - `n`, `d`: number of points and dimension, >= 1. [dimensionless]
    - `generating_vector`: integers `z` `(d,)` coprime to `n`. By default: for `d = 2` and a
      Fibonacci `n = F_k`, the Fibonacci lattice `z = (1, F_{k-1})`; otherwise the lattice version
      of R_d, `z_j = round(n alpha_j)` (with `z_1 = 1`). [dimensionless]
    - `key`: optional `jax.random` key for a uniform random shift (Cranley-Patterson), which
      makes the estimator unbiased.
    - `dtype`: floating dtype.

    **Returns:**

    Points `(n, d)` in [0, 1). [dimensionless]

    ??? cite "References"
        `Sloan1994`; `Cranley1976`; `Owen2013` ch. 16.
        Thesis ch. 5.
    """
    n = check_positive_int(n, "n")
    d = check_positive_int(d, "d")
    if n >= 2**31:
        raise ValueError(f"`n` = {n} must be below 2^31.")
    dtype = _dtype(dtype)
    if generating_vector is None:
        fib = _fibonacci(n) if d == 2 else None
        if fib is not None:
            z = np.array([1, fib[0]], dtype=np.int64)
        else:
            z = np.round(n * _rd_alpha(d)).astype(np.int64) % n
            z[0] = 1
    else:
        z = np.asarray(generating_vector)
        if z.shape != (d,) or not np.issubdtype(z.dtype, np.integer):
            raise ValueError(f"`generating_vector` must be {d} integers, got {z!r}.")
        z = z.astype(np.int64) % n
    return _lattice(jnp.asarray(z.astype(np.uint32)), key, n, dtype)


@functools.partial(jax.jit, static_argnames=("n", "dtype"))
def _lattice(z, key, n, dtype):
    d = z.shape[0]
    i = jnp.arange(n, dtype=jnp.uint32)
    # i z mod n exactly in uint32 arithmetic, then scaled to [0, 1).
    x = _mulmod(i[:, None], z[None, :], n).astype(dtype) / n
    if key is not None:
        x = x + jax.random.uniform(key, (1, d), dtype=dtype)
        x = x - jnp.floor(x)
    return _below_one(x)


def _mulmod(a: Array, b: Array, n: int) -> Array:
    """(a * b) mod n for uint32 a, b < n < 2^31, by double-and-add over the 31 bits of b."""
    a = a % np.uint32(n)
    out = jnp.zeros(jnp.broadcast_shapes(a.shape, b.shape), jnp.uint32)
    nn = np.uint32(n)
    for bit in range(max(1, math.ceil(math.log2(n + 1)))):
        has = ((b >> np.uint32(bit)) & np.uint32(1)).astype(bool)
        out = jnp.where(has, (out + a) % nn, out)
        a = (a + a) % nn
    return out
