"""Pixel samplers of the render driver: the variates `u` of sample `s` of pixel `p`.

Both samplers are counter-based: the variates of one (pass, pixel) pair depend only on the
key, the pass index `s` and the pixel index `p`, never on how the driver batches the work or
how many devices it uses, so every batching and sharding gives the same image.

- `"independent"`: a counter-based generator: the 32-bit words of `(p, s, block, seed)` are
  hashed with `pcg4d` (`Jarzynski2020`), four variates per call, seeded from the
  `jax.random` key. It costs about eight integer operations per variate, a seventh of
  threefry's, and passes the statistical tests of that paper for structured inputs.
- `"sobol"`: pbrt-v4's `PaddedSobolSampler` (`Pharr2023` §8.7): dimensions are taken in pairs; pair `m` of pass
  `s` is point `pi(s)` of the first two Sobol dimensions (a (0, 2)-sequence), where `pi` is a
  random permutation of the pixel's `spp` sample indices (`Kensler2013`), Owen-scrambled
  (`Burley2020`), both seeded by a hash of `(key, p, m)`: each pixel gets an independently
  scrambled, well stratified 2D point set per pair of dimensions, and the pairs are
  decorrelated from each other.
"""

import jax
import jax.numpy as jnp
import numpy as np

from ..montecarlo._halton import _mix32, permutation_element
from ..montecarlo._sobol import direction_numbers, owen_scramble_32, uint32_to_unit_float

__all__ = ["SAMPLERS", "sample_block"]

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


def _sobol_2d(index):
    """Points `index` (uint32) of the first two Sobol dimensions, 32-bit fixed point, (..., 2)."""
    v = direction_numbers(2)  # (2, 32): generator-matrix columns of each dimension
    out = jnp.zeros(index.shape + (2,), _U32)
    for b in range(32):
        bit = ((index >> np.uint32(b)) & np.uint32(1)).astype(bool)
        out = out ^ jnp.where(bit[..., None], v[:, b], np.uint32(0))
    return out


def sample_block(
    key, sampler: str, pixel, pass_index, first_dim, n_dims: int, *, spp=1, dtype=jnp.float32
):
    """Variates `first_dim .. first_dim + n_dims - 1` of sample `pass_index` of pixel `pixel`.

    **Arguments:**

    - `key`: a `jax.random` key (the render's seed).
    - `sampler`: `"independent"` or `"sobol"` (static).
    - `pixel`, `pass_index`: int32 arrays of one shape `(...)`: flat pixel indices
        `y * width + x` and sample indices within the pixel.
    - `first_dim`: the first dimension, a multiple of 4 (may be traced).
    - `n_dims`: how many dimensions, a multiple of 4 (static).
    - `spp`: samples per pixel of the whole render (may be traced; Sobol permutes the sample
        indices within it).

    **Returns:**

    `u` in [0, 1), shape `(..., n_dims)`, of `dtype`.
    """
    if n_dims % 4:
        raise ValueError(f"`n_dims` must be a multiple of 4, got {n_dims}.")
    salt = jax.random.key_data(jax.random.fold_in(key, 0x50B01)).reshape(-1)[:2].astype(_U32)
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
        # Pair m holds dimensions 2m, 2m + 1. One hash per (pixel, pair) permutes the sample
        # index within the pixel's spp samples and seeds the pair's two Owen scrambles.
        m = first // np.uint32(2) + jnp.arange(n_dims // 2, dtype=_U32).reshape(
            (1,) * pixel.ndim + (-1,)
        )
        h = _mix32(_mix32(_mix32(p ^ salt[0]) ^ m) + salt[1])  # (..., pairs)
        s = jnp.broadcast_to(s, h.shape)
        pts = _sobol_2d(permutation_element(s, jnp.asarray(spp).astype(_U32), h))  # (..., pairs, 2)
        ux = owen_scramble_32(pts[..., 0], _mix32(h ^ np.uint32(0x68E31DA4)))
        uy = owen_scramble_32(pts[..., 1], _mix32(h ^ np.uint32(0xB5297A4D)))
        u = jnp.stack([ux, uy], axis=-1).reshape(pixel.shape + (n_dims,))
        return uint32_to_unit_float(u, dtype)
    raise ValueError(
        f"Unknown sampler {sampler!r}; valid values are: {', '.join(map(repr, SAMPLERS))}."
    )
