"""Pixel samplers of the render driver: the variates `u` of sample `s` of pixel `p`.

Both samplers are counter-based: the variates of one (pass, pixel) pair depend only on the
key, the pass index `s` and the pixel index `p`, never on how the driver batches the work or
how many devices it uses, so every batching and sharding gives the same image.

- `"independent"`: a counter-based generator: the 32-bit words of `(p, s, block, seed)` are
  hashed with `pcg4d` (`Jarzynski2020`), four variates per call, seeded from the
  `jax.random` key. It costs about eight integer operations per variate, a seventh of
  threefry's, and passes the statistical tests of that paper for structured inputs.
- `"sobol"`: padded, shuffled, Owen-scrambled Sobol points (`Burley2020`; pbrt-v4's
  `PaddedSobolSampler`, `Pharr2023` §8.7): dimensions are taken in pairs; pair `m` of pass
  `s` is point `pi(s)` of the first two Sobol dimensions (a (0, 2)-sequence), where `pi` is
  a nested uniform scramble of the index (Burley's shuffle), and the point is then
  Owen-scrambled, all seeded by a hash of `(key, p, m)`: each pixel gets an independently
  scrambled, stratified 2D point set per pair of dimensions (the first `2^k` samples of a
  pixel fall one in each of `2^k` elementary intervals), and the pairs are decorrelated.
"""

import jax
import jax.numpy as jnp
import numpy as np

from ..montecarlo._halton import _mix32
from ..montecarlo._sobol import (
    laine_karras_permutation,
    owen_scramble_32,
    reverse_bits_32,
    uint32_to_unit_float,
)

__all__ = ["SAMPLERS", "sample_block", "sampler_seed"]

SAMPLERS = ("independent", "sobol")

_U32 = jnp.uint32


def _pcg4d(x, y, z, w):
    """The `pcg4d` hash of Jarzynski & Olano (2020): four uint32 words in, four out, (..., 4)."""
    x = x * np.uint32(1664525) + np.uint32(1013904223)
    y = y * np.uint32(1664525) + np.uint32(1013904223)
    z = z * np.uint32(1664525) + np.uint32(1013904223)
    w = w * np.uint32(1664525) + np.uint32(1013904223)
    for i in range(2):
        x = x + y * w
        y = y + z * x
        z = z + x * y
        w = w + y * z
        if i == 0:
            x, y, z, w = (c ^ (c >> np.uint32(16)) for c in (x, y, z, w))
    return jnp.stack([x, y, z, w], axis=-1)


def _sobol_owen_2d(index, seed_x, seed_y):
    """Owen-scrambled points `index` of the first two Sobol dimensions, 32-bit fixed point.

    Dimension 0 is the van der Corput sequence, `reverse_bits(index)`. Dimension 1 (primitive
    polynomial x + 1) has the Pascal matrix mod 2 as generator: output bit j (from the top) is
    the parity of the index bits k whose position contains j bitwise (Lucas), a subset-sum
    (zeta) transform over the 5-bit positions, done in 5 shift-and-mask steps; its result is
    also in bit-reversed order. Owen scrambling works on bit-reversed values (`Burley2020`),
    so both dimensions are scrambled before their final reversal.
    """
    w = index
    for b, mask in enumerate((0x55555555, 0x33333333, 0x0F0F0F0F, 0x00FF00FF, 0x0000FFFF)):
        w = w ^ ((w >> np.uint32(1 << b)) & np.uint32(mask))
    x = reverse_bits_32(laine_karras_permutation(index, seed_x))
    y = reverse_bits_32(laine_karras_permutation(w, seed_y))
    return x, y


def sampler_seed(key):
    """The two uint32 words that seed the samplers, derived from a `jax.random` key."""
    return jax.random.key_data(jax.random.fold_in(key, 0x50B01)).reshape(-1)[:2].astype(_U32)


def sample_block(
    key, sampler: str, pixel, pass_index, first_dim, n_dims: int, *, dtype=jnp.float32
):
    """Variates `first_dim .. first_dim + n_dims - 1` of sample `pass_index` of pixel `pixel`.

    **Arguments:**

    - `key`: a `jax.random` key (the render's seed), or the two-word seed `sampler_seed(key)`
        (computed once, outside loops).
    - `sampler`: `"independent"` or `"sobol"` (static).
    - `pixel`, `pass_index`: int32 arrays of one shape `(...)`: flat pixel indices
        `y * width + x` and sample indices within the pixel.
    - `first_dim`: the first dimension, a multiple of 4 (may be traced).
    - `n_dims`: how many dimensions, a multiple of 4 (static).

    **Returns:**

    `u` in [0, 1), shape `(..., n_dims)`, of `dtype`.
    """
    if n_dims % 4:
        raise ValueError(f"`n_dims` must be a multiple of 4, got {n_dims}.")
    salt = key if key.dtype == _U32 else sampler_seed(key)
    p = pixel.astype(_U32)[..., None]
    s = pass_index.astype(_U32)[..., None]
    first = jnp.asarray(first_dim).astype(_U32)
    if sampler == "independent":
        # Block j holds dimensions 4j .. 4j + 3: one pcg4d hash per block.
        b = first // np.uint32(4) + jnp.arange(n_dims // 4, dtype=_U32).reshape(
            (1,) * pixel.ndim + (-1,)
        )
        p, s, b = jnp.broadcast_arrays(p, s, b)
        words = _pcg4d(p, s, b ^ salt[0], _mix32(b + salt[1]))  # (..., blocks, 4)
        return uint32_to_unit_float(words.reshape(pixel.shape + (n_dims,)), dtype)
    if sampler == "sobol":
        # Pair m holds dimensions 2m, 2m + 1. One hash per (pixel, pair) shuffles the sample
        # index and seeds the pair's two Owen scrambles.
        m = first // np.uint32(2) + jnp.arange(n_dims // 2, dtype=_U32).reshape(
            (1,) * pixel.ndim + (-1,)
        )
        h = _mix32(_mix32(p ^ salt[0]) + m * np.uint32(0x9E3779B9) + salt[1])  # (..., pairs)
        # Burley's shuffle: a nested uniform scramble of the index permutes the samples of the
        # pixel independently per pair, and keeps the sequence's stratification. The three
        # scrambles take seeds derived from the one hash by odd multipliers (bijections).
        index = owen_scramble_32(jnp.broadcast_to(s, h.shape), h)
        ux, uy = _sobol_owen_2d(
            index, h * np.uint32(0x68E31DA5), (h ^ np.uint32(0xB5297A4D)) * np.uint32(0x1B56C4E9)
        )
        u = jnp.stack([ux, uy], axis=-1).reshape(pixel.shape + (n_dims,))
        return uint32_to_unit_float(u, dtype)
    raise ValueError(
        f"Unknown sampler {sampler!r}; valid values are: {', '.join(map(repr, SAMPLERS))}."
    )
