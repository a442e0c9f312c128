"""Halton points: radical inverses in prime bases, and their scrambles (thesis ch. 5).

Coordinate j of point i is the radical inverse of i in the j-th prime base b,
phi_b(i) = sum_k d_k(i) b^-(k+1) for the base-b digits d_k(i) of i (`Halton1960`).

Scrambles:

- `None`: the plain sequence, bit-for-bit equal to `scipy.stats.qmc.Halton(d, scramble=False)`
  (the same digit loop in the same floating-point order, first point 0);
- `"permutation"`: an independent uniform random permutation of {0..b-1} for every digit position,
  applied to every digit up to the float precision, trailing zeros included (Owen's
  "randomized Halton", `Owen2017`; what SciPy's `scramble=True` does, with JAX keys);
- `"owen"`: nested uniform scrambling: each digit is permuted by a hashed permutation whose seed
  depends on the dimension, the digit position and all less significant digits of i
  (`Pharr2023` §8.6.3 `OwenScrambledRadicalInverse`, with Kensler's hashed permutations).

The permutation scramble is evaluated with two small tables per dimension: i = q B + r with
B = b^k about sqrt(n) gives phi(i) = T_lo[r] + T_hi[q], since the digits of r and q do not
interact; with a static B per dimension the split is a reshape, so no division is done per point.
"""

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from .._bits import mix32, permutation_element
from .._checks import check_positive_int
from .._types import Float, Key
from ._samplers import _check_sequence_options

SCRAMBLES = (None, "none", "permutation", "owen")


@functools.lru_cache(maxsize=8)
def first_primes(d: int) -> np.ndarray:
    """The first `d` primes (int64), by a sieve of Eratosthenes."""
    if d < 6:
        return np.array([2, 3, 5, 7, 11][:d], dtype=np.int64)
    limit = int(d * (math.log(d) + math.log(math.log(d)))) + 10  # Rosser's bound
    sieve = np.ones(limit + 1, dtype=bool)
    sieve[:2] = False
    for p in range(2, int(limit**0.5) + 1):
        if sieve[p]:
            sieve[p * p :: p] = False
    return np.flatnonzero(sieve)[:d].astype(np.int64)


def _digits_for_precision(bases: np.ndarray, dtype) -> np.ndarray:
    """Digit positions k with b^-k still visible next to 1 in `dtype` (SciPy's count)."""
    bits = jnp.finfo(dtype).nmant + 2  # 54 for float64, as SciPy
    return np.ceil(bits / np.log2(bases)).astype(np.int64) - 1


@functools.partial(jax.jit, static_argnames=("n", "d", "n_digits", "dtype"))
def _halton_plain(start: Array, n: int, d: int, n_digits: int, dtype) -> Array:
    bases = first_primes(d)
    b = jnp.asarray(bases.astype(np.uint32))[None, :]
    bf = jnp.asarray(bases.astype(np.float64)).astype(dtype)[None, :]
    q = jnp.broadcast_to((start + jnp.arange(n, dtype=jnp.uint32))[:, None], (n, d))
    seq = jnp.zeros((n, d), dtype)
    b2r = jnp.ones((1, d), dtype) / bf
    # SciPy's loop: seq += (i mod b) / b^k, most significant power last, same rounding order.
    for _ in range(n_digits):
        rem = q % b
        seq = seq + jnp.where(q > 0, rem.astype(dtype) * b2r, 0.0)
        b2r = b2r / bf
        q = q // b
    return seq


def _permutation_tables(key: Key, bases: np.ndarray, n_digits: np.ndarray) -> Array:
    """Pseudo-random permutations (d, K, max_b) of {0..b_j-1} per dimension j and digit position.

    Kensler's hashed permutations seeded from `key`: one seed per (dimension, digit position).
    """
    d, k_max, b_max = len(bases), int(n_digits.max()), int(bases.max())
    seeds = jax.random.bits(key, (d, k_max, 1), jnp.uint32)
    i = jnp.arange(b_max, dtype=jnp.uint32)[None, None, :]
    b = jnp.asarray(bases.astype(np.uint32))[:, None, None]
    valid = i < b
    perm = permutation_element(jnp.where(valid, i, 0), b, seeds)
    return jnp.where(valid, perm, 0).astype(jnp.int32)


def _split(bases: np.ndarray, skip: int, n: int):
    """Per dimension: digits k_lo in the low table, block b^k_lo, first hi index, hi count."""
    end = skip + n
    out = []
    for base in bases.tolist():
        k_lo = max(1, math.ceil(math.log(max(end, 2), base) / 2))
        block = base**k_lo
        first = skip - skip % block
        out.append((k_lo, block, first // block, -(-(end - first) // block), skip - first))
    return out


@functools.partial(jax.jit, static_argnames=("n", "d", "skip", "dtype"))
def _halton_permuted(key: Key, n: int, d: int, skip: int, dtype) -> Array:
    bases = first_primes(d)
    n_digits = _digits_for_precision(bases, dtype)
    k_total = int(n_digits.max())
    perms = _permutation_tables(key, bases, n_digits)  # (d, K, b_max)
    b_max = perms.shape[-1]
    flat_perms = perms.reshape(d, k_total * b_max)
    split = _split(bases, skip, n)
    k_lo = np.array([s[0] for s in split])
    b_max_block = max(s[1] for s in split)
    h_max = max(s[3] for s in split)
    bu = jnp.asarray(bases.astype(np.uint32))[:, None]
    bf = jnp.asarray(bases.astype(np.float64)).astype(dtype)[:, None]
    k_lo_j = jnp.asarray(k_lo.astype(np.int32))[:, None]
    nd_j = jnp.asarray(n_digits.astype(np.int32))[:, None]

    def add_digits(q, val, scale, pos0, n_steps, limit):
        def body(t, carry):
            q, val, scale = carry
            digit = q % bu
            pos = pos0 + t
            idx = jnp.minimum(pos, k_total - 1) * b_max + digit.astype(jnp.int32)
            p = jnp.take_along_axis(flat_perms, idx, axis=1)
            val = val + jnp.where(pos < limit, p.astype(dtype) * scale, 0.0)
            return q // bu, val, scale / bf

        return jax.lax.fori_loop(0, n_steps, body, (q, val, scale))[1]

    # Low tables T_lo[j, r] over digit positions 0 .. k_lo_j - 1 of r < b_j^k_lo_j.
    r = jnp.broadcast_to(jnp.arange(b_max_block, dtype=jnp.uint32)[None, :], (d, b_max_block))
    zeros_lo = jnp.zeros((d, b_max_block), dtype)
    t_lo = add_digits(r, zeros_lo, 1.0 / bf, 0, int(k_lo.max()), jnp.minimum(k_lo_j, nd_j))
    # High tables T_hi[j, q] over digit positions k_lo_j .. n_digits_j - 1 (trailing zeros too).
    hi0 = jnp.asarray(np.array([s[2] for s in split], dtype=np.uint32))[:, None]
    q = hi0 + jnp.arange(h_max, dtype=jnp.uint32)[None, :]
    scale0 = jnp.power(bf, -(k_lo_j.astype(dtype) + 1.0))
    t_hi = add_digits(q, jnp.zeros((d, h_max), dtype), scale0, k_lo_j, k_total, nd_j)
    # phi(i) = T_lo[j, i mod B_j] + T_hi[j, i div B_j - hi0_j], by two gathers from the flat
    # tables. The division uses a float32 reciprocal and one integer correction, exact for
    # i < 2^24, so no integer division is done per point.
    blocks = np.array([sp[1] for sp in split], dtype=np.int64)
    i = jnp.asarray(skip, jnp.int32) + jnp.arange(n, dtype=jnp.int32)[:, None]  # (n, 1)
    b_row = jnp.asarray(blocks.astype(np.int32))[None, :]
    if skip + n <= 2**24:
        inv_b = jnp.asarray((1.0 / blocks).astype(np.float32))[None, :]
        q = jnp.floor((i.astype(jnp.float32) + 0.5) * inv_b).astype(jnp.int32)
        r = i - q * b_row
        q = jnp.where(r < 0, q - 1, jnp.where(r >= b_row, q + 1, q))
    else:
        q = i // b_row
    r = i - q * b_row
    lo_idx = jnp.arange(d, dtype=jnp.int32)[None, :] * b_max_block + r
    hi_idx = jnp.arange(d, dtype=jnp.int32)[None, :] * h_max + (
        q - hi0[:, 0][None, :].astype(jnp.int32)
    )
    x = t_lo.reshape(-1)[lo_idx] + t_hi.reshape(-1)[hi_idx]
    return jnp.minimum(x, 1.0 - jnp.finfo(dtype).epsneg)


@functools.partial(jax.jit, static_argnames=("n", "d", "skip", "dtype"))
def _halton_owen(key: Key, n: int, d: int, skip: int, dtype) -> Array:
    bases = first_primes(d)
    n_digits = _digits_for_precision(bases, dtype)
    bu = jnp.asarray(bases.astype(np.uint32))[None, :]
    bf = jnp.asarray(bases.astype(np.float64)).astype(dtype)[None, :]
    seeds = jax.random.bits(key, (1, d), jnp.uint32)
    q0 = jnp.broadcast_to(
        (jnp.asarray(skip, jnp.uint32) + jnp.arange(n, dtype=jnp.uint32))[:, None], (n, d)
    )
    nd = jnp.asarray(n_digits.astype(np.int32))[None, :]

    def body(k, carry):
        q, prefix, out, scale = carry
        digit = q % bu
        salt = (k.astype(jnp.uint32) * np.uint32(0x9E3779B9)) ^ prefix
        h = mix32(seeds ^ mix32(salt))
        permuted = permutation_element(digit, bu, h)
        out = out + jnp.where(k < nd, permuted.astype(dtype) * scale, 0.0)
        # The node of the next digit is identified by all digits below it (nested scrambling).
        prefix = mix32(prefix + digit + np.uint32(1))
        return q // bu, prefix, out, scale / bf

    init = (q0, jnp.zeros((n, d), jnp.uint32), jnp.zeros((n, d), dtype), 1.0 / bf)
    out = jax.lax.fori_loop(0, int(n_digits.max()), body, init)[2]
    return jnp.minimum(out, 1.0 - jnp.finfo(dtype).epsneg)


def halton(
    n: int,
    d: int,
    *,
    scramble: str | None = None,
    key: Key | None = None,
    skip: int = 0,
    dtype=None,
) -> Float[Array, "n d"]:
    r"""The first `n` points of the `d`-dimensional Halton sequence, optionally scrambled.

    Dimension j uses the j-th prime as base. Unscrambled points equal
    `scipy.stats.qmc.Halton(d, scramble=False)` bit for bit in float64.

    **Arguments:**

    - `n`: number of points. [dimensionless]
    - `d`: dimension >= 1 (no upper limit; plain Halton is poor in high dimensions).
        [dimensionless]
    - `scramble`: `None` (or `"none"`), `"permutation"` (random digit permutations, Owen 2017,
      as SciPy's `scramble=True`) or `"owen"` (nested uniform scrambling with hashed
      permutations, pbrt-v4's `OwenScrambledRadicalInverse`).
    - `key`: `jax.random` key; required by the scrambles, refused without one.
    - `skip`: index of the first point. [dimensionless]
    - `dtype`: floating dtype of the result (JAX's default float by default).

    **Returns:**

    Points `(n, d)` in [0, 1). [dimensionless]

    ??? cite "References"
        `Halton1960`; `Owen2017`; `Kensler2013`; `Pharr2023` §8.6.
        Thesis ch. 5.
    """
    n = check_positive_int(n, "n")
    d = check_positive_int(d, "d")
    skip = check_positive_int(skip, "skip", minimum=0)
    if skip + n > 2**31:
        raise ValueError(f"`skip + n` = {skip + n} exceeds 2^31 points.")
    scramble, dtype = _check_sequence_options(scramble, key, dtype, SCRAMBLES)
    if scramble is None:
        # `start` is a run-time argument: a fully constant input would be constant-folded by
        # XLA with a different rounding than SciPy's loop.
        n_digits = max(1, math.ceil(math.log2(skip + n)))
        return _halton_plain(jnp.asarray(skip, jnp.uint32), n, d, n_digits, dtype)
    if scramble == "permutation":
        return _halton_permuted(key, n, d, skip, dtype)
    return _halton_owen(key, n, d, skip, dtype)
