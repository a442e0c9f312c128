"""Pixel samplers of the render driver: the variates `u` of sample `s` of pixel `p`.

Both samplers are counter-based: the variates of one (pass, pixel) pair depend only on the
key, the pass index `s` and the pixel index `p`, never on how the driver batches the work or
how many devices it uses, so every batching and sharding gives the same image.

- `"independent"`: `jax.random.uniform(fold_in(fold_in(key, s), p), (d,))`.
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
    if sampler == "independent":

        def one(p, s):
            k = jax.random.fold_in(jax.random.fold_in(key, s), p)
            return jax.random.uniform(k, (n_dims,), dtype=jnp.float32)

        u = jax.vmap(lambda p: jax.vmap(lambda s: one(p, s))(pass_index))(pixel_index)
        return u.astype(dtype)
    if sampler == "sobol":
        n_pairs = (n_dims + 1) // 2
        salt = jax.random.key_data(jax.random.fold_in(key, 0x50B01)).reshape(-1)[:2]
        salt = salt.astype(_U32)
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
