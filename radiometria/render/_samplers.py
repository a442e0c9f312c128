"""Pixel samplers of the render driver: the variates `u` of sample `s` of pixel `p`.

Both samplers are counter-based: the variates of one (pass, pixel) pair depend only on the
key, the pass index `s` and the pixel index `p`, never on how the driver batches the work or
how many devices it uses, so every batching and sharding gives the same image.

- `"independent"`: `jax.random.uniform(fold_in(fold_in(key, s), p), (d,))`.
- `"sobol"`: pbrt-v4's `PaddedSobolSampler`: dimensions are taken in pairs; pair `m` of pass
  `s` is point `s` of the first two Sobol dimensions (a (0, 2)-sequence), Owen-scrambled with
  a seed hashed from `(key, p, m)` (the Laine-Karras style hash of Burley 2020), so each
  pixel gets an independently scrambled, well stratified 2D sequence per pair of dimensions.
  The index is first shuffled per `(p, m)` inside the enclosing power-of-two block of the
  sample count (an XOR with a hashed mask, a permutation of that block), which decorrelates
  the pairs as pbrt's `PermutationElement` does.
"""

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["SAMPLERS", "pixel_samples"]

SAMPLERS = ("independent", "sobol")

_U32 = jnp.uint32
_ONE_MINUS_EPS = float(np.nextafter(np.float32(1.0), np.float32(0.0)))  # largest float32 < 1


def _c(x: int):
    return np.uint32(x)


def _mix32(h):
    """MurmurHash3's 32-bit finaliser (an avalanche bijection on uint32)."""
    h = h ^ (h >> _c(16))
    h = h * _c(0x85EBCA6B)
    h = h ^ (h >> _c(13))
    h = h * _c(0xC2B2AE35)
    return h ^ (h >> _c(16))


def _reverse_bits(v):
    v = ((v >> _c(1)) & _c(0x55555555)) | ((v & _c(0x55555555)) << _c(1))
    v = ((v >> _c(2)) & _c(0x33333333)) | ((v & _c(0x33333333)) << _c(2))
    v = ((v >> _c(4)) & _c(0x0F0F0F0F)) | ((v & _c(0x0F0F0F0F)) << _c(4))
    v = ((v >> _c(8)) & _c(0x00FF00FF)) | ((v & _c(0x00FF00FF)) << _c(8))
    return (v >> _c(16)) | (v << _c(16))


def _owen_scramble(v, seed):
    """Owen scrambling of 32-bit fixed-point values (pbrt-v4's `FastOwenScrambler`)."""
    v = _reverse_bits(v)
    v = v ^ (v * _c(0x3D20ADEA))
    v = v + seed
    v = v * ((seed >> _c(16)) | _c(1))
    v = v ^ (v * _c(0x05526C56))
    v = v ^ (v * _c(0x53A22864))
    return _reverse_bits(v)


def _sobol_2d(index):
    """First two Sobol dimensions of `index` (uint32) as 32-bit fixed point, shape (..., 2)."""
    x = _reverse_bits(index)  # dimension 0: the van der Corput sequence
    y = jnp.zeros_like(index)
    c = np.uint32(1 << 31)  # dimension 1: generator columns c_k = c_{k-1} ^ (c_{k-1} >> 1)
    for k in range(32):
        y = y ^ jnp.where((index >> _c(k)) & _c(1), c, _c(0))
        c = c ^ (c >> np.uint32(1))
    return jnp.stack([x, y], axis=-1)


def _to_unit(v, dtype):
    u = v.astype(jnp.float32) * np.float32(2.0**-32)
    return jnp.minimum(u, _ONE_MINUS_EPS).astype(dtype)


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
        # One scramble seed per (pixel, pair of dimensions).
        p = pixel_index.astype(_U32)[:, None]
        m = jnp.arange(n_pairs, dtype=_U32)[None, :]
        seed = _mix32(_mix32(p ^ salt[0]) + m * _c(0x9E3779B9) + salt[1])  # (t, pairs)
        seed_x = seed[:, None, :]
        seed_y = _mix32(seed ^ _c(0x68E31DA4))[:, None, :]
        block = np.uint32((1 << max(int(spp) - 1, 0).bit_length()) - 1)
        shuffle = _mix32(seed ^ _c(0x2C1B3C6D))[:, None, :] & block
        index = pass_index.astype(_U32)[None, :, None] ^ shuffle  # (t, k, pairs)
        pts = _sobol_2d(index)  # (t, k, pairs, 2)
        ux = _owen_scramble(pts[..., 0], seed_x)
        uy = _owen_scramble(pts[..., 1], seed_y)
        u = jnp.stack([ux, uy], axis=-1).reshape(pixel_index.shape[0], pass_index.shape[0], -1)
        return _to_unit(u[..., :n_dims], dtype)
    raise ValueError(f"Unknown sampler {sampler!r}; valid values are: {', '.join(map(repr, SAMPLERS))}.")
