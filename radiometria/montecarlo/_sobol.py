"""Sobol points with the Joe-Kuo direction numbers, and their scrambles (thesis ch. 5).

The i-th point's coordinate j is the digital (XOR) combination of the direction numbers of
dimension j selected by the bits of the Gray code of i, exactly as SciPy's `qmc.Sobol` orders
the points. Instead of the sequential Gray-code recursion the generator evaluates it directly and
in parallel, as pure uint32 bit arithmetic: the Gray code g(i) = i ^ (i >> 1) is linear over
GF(2), so x(i) = XOR_b bit_b(i) w_b with w_b = v_b ^ v_{b-1}. Splitting i = 2^L hi + lo makes
x(i) = X_hi[hi] ^ X_lo[lo]: two small tables (about sqrt(n) rows each) and one broadcast XOR, so
the whole point set costs one fused pass over the output.

Scrambles (`Owen2013` ch. 17, `Owen1995`, `Matousek1998`, `Burley2020`):

- `None`: the plain sequence, equal to `scipy.stats.qmc.Sobol(d, scramble=False)`;
- `"shift"`: a random digital shift (XOR with one random uint32 per dimension);
- `"lms"`: Matousek's random linear matrix scramble (random lower-triangular binary matrices,
  applied to the direction numbers) followed by a digital shift: what SciPy's `scramble=True` does;
- `"owen"`: nested uniform (Owen) scrambling by the Laine-Karras hash as improved by Burley
  (`Laine2011`, `Burley2020`): reverse the bits, hash with a per-dimension seed, reverse back.
  Each output digit depends only on the input digits above it, so (t, m, s)-net properties are
  kept while the points are randomised.
"""

import functools
import math
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from .._bits import (
    laine_karras_permutation,
    reverse_bits_32,
    uint32_to_unit_float,
)
from .._checks import check_positive_int
from .._types import Float, Key
from ._samplers import _check_sequence_options

DATA = Path(__file__).parent / "data" / "sobol_joe_kuo_6_21201.npz"
MAX_DIMENSION = 21201
BITS = 32
SCRAMBLES = (None, "none", "shift", "lms", "owen")


@functools.cache
def _compact_table() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`(s, a, m)`: degrees, polynomial coefficients and concatenated initial integers."""
    with np.load(DATA) as z:
        s = z["s"].astype(np.int64)
        a = z["a"].astype(np.uint32)
        packed = z["m_bits"]
    starts = np.concatenate([[0], np.cumsum(s)[:-1]])
    total = int(s.sum())
    k = np.arange(total) - np.repeat(starts, s) + 1  # m_k is written with k bits
    offsets = np.concatenate([[0], np.cumsum(k)[:-1]])
    bits = np.unpackbits(packed)[: int(k.sum())].astype(np.uint32)
    m = np.zeros(total, np.uint32)
    for t in range(int(k.max(initial=0))):
        ok = t < k
        m[ok] = (m[ok] << np.uint32(1)) | bits[offsets[ok] + t]
    return s, a, m


@functools.lru_cache(maxsize=16)
def direction_numbers(d: int) -> np.ndarray:
    """The 32-bit direction numbers `v[j, k]` (uint32, shape (d, 32)) of the first d dimensions.

    `v[j, k] = m_{k+1} << (31 - k)` with the Joe-Kuo recurrence
    `m_k = 2 a_1 m_{k-1} ^ 4 a_2 m_{k-2} ^ ... ^ 2^s m_{k-s} ^ m_{k-s}` (`Joe2008`, `Bratley1988`).
    """
    s, a, m_flat = _compact_table()
    s, a = s[:d], a[:d].astype(np.uint64)
    starts = np.concatenate([[0], np.cumsum(s)[:-1]])
    m = np.ones((d, BITS), dtype=np.uint64)  # dimension 1 (s = 0): m_k = 1, van der Corput
    for deg in np.unique(s[s > 0]):
        deg = int(deg)
        idx = np.flatnonzero(s == deg)
        aj = a[idx]
        mm = np.zeros((len(idx), BITS), dtype=np.uint64)
        mm[:, :deg] = m_flat[starts[idx][:, None] + np.arange(deg)[None, :]]
        for k in range(deg, BITS):
            r = mm[:, k - deg] ^ (mm[:, k - deg] << np.uint64(deg))
            for i in range(1, deg):
                a_i = (aj >> np.uint64(deg - 1 - i)) & np.uint64(1)
                r ^= np.where(a_i == 1, mm[:, k - i] << np.uint64(i), np.uint64(0))
            mm[:, k] = r
        m[idx] = mm
    shifts = (BITS - 1 - np.arange(BITS)).astype(np.uint64)
    v = (m << shifts[None, :]) & np.uint64(0xFFFFFFFF)
    return v.astype(np.uint32)


def _xor_table(w: Array, idx: Array, n_bits: int) -> Array:
    """XOR of rows `w[b]` (shape (32, d)) over the set bits b < n_bits of each index in `idx`."""
    out = jnp.zeros(idx.shape + (w.shape[1],), jnp.uint32)
    for b in range(n_bits):
        bit = ((idx >> np.uint32(b)) & np.uint32(1)).astype(bool)
        out = out ^ jnp.where(bit[:, None], w[b][None, :], np.uint32(0))
    return out


@functools.partial(jax.jit, static_argnames=("n", "skip"))
def _sobol_uint32(v: Array, n: int, skip: int) -> Array:
    """Points `skip .. skip+n-1` of the Sobol sequence (Gray-code order) as uint32, (n, d)."""
    d = v.shape[0]
    # Gray-code order in terms of the bits of i: w_b = v_b ^ v_{b-1}.
    vt = v.T  # (32, d)
    w = vt ^ jnp.concatenate([jnp.zeros((1, d), jnp.uint32), vt[:-1]], axis=0)
    end = skip + n
    total_bits = max(1, math.ceil(math.log2(end)))
    lo_bits = min(total_bits, max(4, total_bits // 2))
    block = 1 << lo_bits
    first = skip - skip % block
    n_hi = -(-(end - first) // block)
    lo_idx = jnp.arange(block, dtype=jnp.uint32)
    hi_idx = jnp.asarray(first // block, jnp.uint32) + jnp.arange(n_hi, dtype=jnp.uint32)
    t_lo = _xor_table(w, lo_idx, lo_bits)
    t_hi = _xor_table(w[lo_bits:], hi_idx, BITS - lo_bits)
    # Materialise the two small tables: otherwise XLA may fuse (duplicate) their bit loops into
    # every element of the large output.
    t_lo, t_hi = jax.lax.optimization_barrier((t_lo, t_hi))
    x = (t_hi[:, None, :] ^ t_lo[None, :, :]).reshape(n_hi * block, d)
    return x[skip - first : skip - first + n]


def _lms_direction_numbers(v: Array, key: Key) -> Array:
    """Apply random lower-triangular (unit diagonal) binary matrices to the direction numbers.

    Digit 1 is the most significant bit; an output digit depends on the input digits at and
    above it, so column b of the matrix (the image of input bit b) is bit b plus random bits
    below it (`Matousek1998`; SciPy's `_scramble`).
    """
    d = v.shape[0]
    rnd = jax.random.bits(key, (d, BITS), jnp.uint32)
    b = np.arange(BITS, dtype=np.uint32)
    below = ((np.uint64(1) << b.astype(np.uint64)) - np.uint64(1)).astype(np.uint32)
    cols = (np.uint32(1) << b)[None, :] | (rnd & below[None, :])  # (d, 32): column of input bit b
    out = jnp.zeros_like(v)
    for bit in range(BITS):
        has = ((v >> np.uint32(bit)) & np.uint32(1)).astype(bool)
        out = out ^ jnp.where(has, cols[:, bit][:, None], np.uint32(0))
    return out


def sobol(
    n: int,
    d: int,
    *,
    scramble: str | None = None,
    key: Key | None = None,
    skip: int = 0,
    allow_unbalanced: bool = False,
    dtype=None,
) -> Float[Array, "n d"]:
    r"""The first `n` points of the `d`-dimensional Sobol sequence, optionally scrambled.

    Joe and Kuo's `new-joe-kuo-6.21201` direction numbers (all 21201 dimensions), 32-bit
    precision. Unscrambled points equal `scipy.stats.qmc.Sobol(d, scramble=False)` exactly
    (same Gray-code order, first point 0).

    **Arguments:**

    - `n`: number of points; a power of two unless `allow_unbalanced=True`. [dimensionless]
    - `d`: dimension, 1 <= d <= 21201. [dimensionless]
    - `scramble`: `None` (or `"none"`), `"shift"` (random digital shift), `"lms"` (linear matrix
      scramble + digital shift, as SciPy's `scramble=True`) or `"owen"` (nested uniform
      scrambling, Laine-Karras/Burley hash).
    - `key`: `jax.random` key; required by every scramble, refused without one.
    - `skip`: index of the first point (points `skip .. skip + n - 1`). [dimensionless]
    - `allow_unbalanced`: accept `n` that is not a power of two. The points are then the first
      `n` of the sequence, but they are not a balanced (0, m, d)-net prefix: the integration
      error of an unbalanced prefix can be much larger (`Owen2020`). Without this flag a
      non-power-of-two `n` raises `ValueError`.
    - `dtype`: floating dtype of the result; JAX's default float by default. float64 carries
      all 32 bits, float32 the top 24 (values stay below 1).

    **Returns:**

    Points `(n, d)` in [0, 1). [dimensionless]

    ```python
    u = sobol(1024, 2, scramble="owen", key=jax.random.key(0))
    ```

    ??? cite "References"
        `Sobol1967`; `Joe2008`; `Owen1995`; `Burley2020`; `Pharr2023` §8.7.
        Thesis ch. 5.
    """
    n = check_positive_int(n, "n")
    d = check_positive_int(d, "d")
    if d > MAX_DIMENSION:
        raise ValueError(
            f"`d` = {d} exceeds the {MAX_DIMENSION} dimensions of the Joe-Kuo direction numbers."
        )
    skip = check_positive_int(skip, "skip", minimum=0)
    if skip + n > 2**BITS:
        raise ValueError(f"`skip + n` = {skip + n} exceeds the 2^32 points of a 32-bit sequence.")
    if n & (n - 1) and not allow_unbalanced:
        raise ValueError(
            f"`n` = {n} is not a power of two, so the Sobol points are not balanced; use "
            f"n = {1 << (n - 1).bit_length()} or pass `allow_unbalanced=True`."
        )
    scramble, dtype = _check_sequence_options(scramble, key, dtype, SCRAMBLES)
    return _sobol_points(n, d, scramble, skip, dtype, key)


@functools.partial(jax.jit, static_argnames=("n", "d", "scramble", "skip", "dtype"))
def _sobol_points(n, d, scramble, skip, dtype, key):
    v = jnp.asarray(direction_numbers(d))
    if scramble == "owen":
        # Generate bit-reversed points from bit-reversed direction numbers (XOR commutes with
        # the reversal), hash, and reverse once: one reversal per point instead of two.
        v = reverse_bits_32(v)
    if scramble == "lms":
        k_mat, k_shift = jax.random.split(key)
        v = _lms_direction_numbers(v, k_mat)
    x = _sobol_uint32(v, n, skip)
    if scramble in ("shift", "lms"):
        k_shift = key if scramble == "shift" else k_shift
        x = x ^ jax.random.bits(k_shift, (1, d), jnp.uint32)
    elif scramble == "owen":
        seeds = jax.random.bits(key, (1, d), jnp.uint32)
        x = reverse_bits_32(laine_karras_permutation(x, seeds))
    return uint32_to_unit_float(x, dtype)
