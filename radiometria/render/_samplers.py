"""Pixel samplers of the render driver: the variates `u` of sample `s` of pixel `p`.

Both samplers are counter-based: the variates of one (pass, pixel) pair depend only on the
key, the pass index `s` and the pixel index `p`, never on how the driver batches the work or
how many devices it uses, so every batching and sharding gives the same image.

- `"independent"`: a counter-based generator: the 32-bit words of `(p, s, block, seed)` are
  hashed with `pcg4d` (Jarzynski & Olano 2020), four variates per call, seeded from the
  `jax.random` key. It costs about eight integer operations per variate, a seventh of
  threefry's, and passes the statistical tests of that paper for structured inputs.
- `"sobol"`: pbrt-v4's `PaddedSobolSampler`: dimensions are taken in pairs; pair `m` of pass
  `s` is point `pi(s)` of the first two Sobol dimensions (a (0, 2)-sequence), where `pi` is a
  random permutation of the pixel's `spp` sample indices (Kensler 2013), Owen-scrambled
  (Burley 2020), both seeded by a hash of `(key, p, m)`: each pixel gets an independently
  scrambled, well stratified 2D point set per pair of dimensions, and the pairs are
  decorrelated from each other.
"""

import jax
import jax.numpy as jnp
import numpy as np

from ..montecarlo._halton import _mix32, permutation_element
from ..montecarlo._sobol import direction_numbers, owen_scramble_32, uint32_to_unit_float

__all__ = ["SAMPLERS", "pixel_samples"]

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


def pixel_samples(
    key, sampler: str, pass_index, pixel_index, n_dims: int, *, spp: int = 1, dtype=jnp.float32
):
    """Uniform variates for every (pixel, pass) pair, shape `(pixels, passes, n_dims)`.

    **Arguments:**

    - `key`: a `jax.random` key (the render's seed).
    - `sampler`: `"independent"` or `"sobol"` (static).
    - `pass_index`: `(k,)` int32 sample indices within each pixel.
    - `pixel_index`: `(t,)` int32 flat pixel indices `y * width + x`.
    - `n_dims`: variates per sample (static).
    - `spp`: samples per pixel of the whole render (static; the Sobol index shuffle block).

    **Returns:**

    `u` in [0, 1), `(t, k, n_dims)`, of `dtype`.
    """
    salt = jax.random.key_data(jax.random.fold_in(key, 0x50B01)).reshape(-1)[:2]
    salt = salt.astype(_U32)
    if sampler == "independent":
        n_blocks = -(-n_dims // 4)
        shape = (pixel_index.shape[0], pass_index.shape[0], n_blocks)
        p = jnp.broadcast_to(pixel_index.astype(_U32)[:, None, None], shape)
        s = jnp.broadcast_to(pass_index.astype(_U32)[None, :, None], shape)
        b = jnp.broadcast_to(jnp.arange(n_blocks, dtype=_U32)[None, None, :], shape)
        words = _pcg4d(p, s, b ^ salt[0], _mix32(b + salt[1]))  # (t, k, blocks, 4)
        u = words.reshape(shape[0], shape[1], 4 * n_blocks)[..., :n_dims]
        return uint32_to_unit_float(u, dtype)
    if sampler == "sobol":
        n_pairs = (n_dims + 1) // 2
        # One hash per (pixel, pair of dimensions): it permutes the sample index within the
        # pixel's spp samples and seeds the two Owen scrambles.
        p = pixel_index.astype(_U32)[:, None, None]
        m = jnp.arange(n_pairs, dtype=_U32)[None, None, :]
        h = _mix32(_mix32(_mix32(p ^ salt[0]) ^ m) + salt[1])  # (t, 1, pairs)
        s = jnp.broadcast_to(
            pass_index.astype(_U32)[None, :, None], (h.shape[0], pass_index.shape[0], n_pairs)
        )
        index = permutation_element(s, np.uint32(spp), h)  # (t, k, pairs)
        pts = _sobol_2d(index)
        ux = owen_scramble_32(pts[..., 0], _mix32(h ^ np.uint32(0x68E31DA4)))
        uy = owen_scramble_32(pts[..., 1], _mix32(h ^ np.uint32(0xB5297A4D)))
        u = jnp.stack([ux, uy], axis=-1).reshape(pixel_index.shape[0], pass_index.shape[0], -1)
        return uint32_to_unit_float(u[..., :n_dims], dtype)
    raise ValueError(
        f"Unknown sampler {sampler!r}; valid values are: {', '.join(map(repr, SAMPLERS))}."
    )
