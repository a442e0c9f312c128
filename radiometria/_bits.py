"""Integer hashes and bit tricks on uint32 arrays (floor 1: imports nothing from radiometria).

The one home of the hashes that the samplers (`montecarlo`, `render`) share: finalisers, bit
reversal, the Laine-Karras / Burley nested scramble, Kensler's hashed permutations, the `pcg4d`
hash and the uint32 -> [0, 1) conversion. All take and return uint32 arrays (JAX or NumPy;
arithmetic wraps modulo 2^32), broadcast, and are pure bit arithmetic, so they run under `jit`
and `vmap` and fuse with their consumers.
"""

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

__all__ = [
    "laine_karras_permutation",
    "mix32",
    "owen_scramble_32",
    "pcg4d",
    "permutation_element",
    "reverse_bits_32",
    "uint32_to_unit_float",
]


def mix32(x: Array) -> Array:
    """Wellons' `lowbias32` integer finaliser (pbrt's `MixBits`, 32-bit): a bijection of uint32
    with strong avalanche (C. Wellons, *hash-prospector*, 2018)."""
    x = x ^ (x >> np.uint32(16))
    x = x * np.uint32(0x7FEB352D)
    x = x ^ (x >> np.uint32(15))
    x = x * np.uint32(0x846CA68B)
    return x ^ (x >> np.uint32(16))


def reverse_bits_32(x: Array) -> Array:
    """Reverse the 32 bits of uint32 values (five mask-and-shift swaps)."""
    for shift, mask in ((1, 0x55555555), (2, 0x33333333), (4, 0x0F0F0F0F), (8, 0x00FF00FF)):
        m = np.uint32(mask)
        x = ((x >> np.uint32(shift)) & m) | ((x & m) << np.uint32(shift))
    return (x >> np.uint32(16)) | (x << np.uint32(16))


def laine_karras_permutation(x: Array, seed: Array) -> Array:
    """Burley's improved Laine-Karras hash: a bijection of uint32 in which bit k depends only on
    bits 0..k, so on bit-reversed values it is a nested (Owen) scramble (`Laine2011`,
    `Burley2020`)."""
    x = x + seed
    x = x ^ (x * np.uint32(0x6C50B47C))
    x = x ^ (x * np.uint32(0xB82F1E52))
    x = x ^ (x * np.uint32(0xC7AFE638))
    x = x ^ (x * np.uint32(0x8D22F6E6))
    return x


def owen_scramble_32(x: Array, seed: Array) -> Array:
    """Nested uniform (Owen) scramble of 32-bit fixed-point values `x` with `seed` (broadcast)
    (`Burley2020`)."""
    return reverse_bits_32(laine_karras_permutation(reverse_bits_32(x), seed))


def uint32_to_unit_float(x: Array, dtype) -> Array:
    """uint32 fixed point -> float in [0, 1): all 32 bits in float64, the top 24 in float32.

    Dropping the low bits in float32 keeps every value strictly below 1 (x * 2^-32 would round
    the largest ones up to 1.0).
    """
    dtype = jnp.dtype(dtype)
    if dtype == jnp.float64:
        return x.astype(jnp.float64) * (2.0**-32)
    mant = jnp.finfo(dtype).nmant + 1
    return (x >> np.uint32(32 - mant)).astype(dtype) * (2.0**-mant)


def permutation_element(i: Array, n: Array, seed: Array) -> Array:
    """Element `i` of a pseudo-random permutation of {0..n-1} chosen by `seed` (`Kensler2013`).

    uint32 in and out, broadcast; a hashed bijection of the next power of two, cycle-walked until
    it lands below `n` (vectorised with `lax.while_loop`).
    """
    i, n, seed = jnp.broadcast_arrays(i, n, seed)
    w = n - np.uint32(1)
    for s in (1, 2, 4, 8, 16):
        w = w | (w >> np.uint32(s))
    p = seed

    def hash_once(i):
        i = i ^ p
        i = i * np.uint32(0xE170893D)
        i = i ^ (p >> np.uint32(16))
        i = i ^ ((i & w) >> np.uint32(4))
        i = i ^ (p >> np.uint32(8))
        i = i * np.uint32(0x0929EB3F)
        i = i ^ (p >> np.uint32(23))
        i = i ^ ((i & w) >> np.uint32(1))
        i = i * (np.uint32(1) | (p >> np.uint32(27)))
        i = i * np.uint32(0x6935FA69)
        i = i ^ ((i & w) >> np.uint32(11))
        i = i * np.uint32(0x74DCB303)
        i = i ^ ((i & w) >> np.uint32(2))
        i = i * np.uint32(0x9E501CC3)
        i = i ^ ((i & w) >> np.uint32(2))
        i = i * np.uint32(0xC860A3DF)
        i = i & w
        return i ^ (i >> np.uint32(5))

    def cond(state):
        _, active = state
        return jnp.any(active)

    def body(state):
        cur, active = state
        nxt = hash_once(cur)
        return jnp.where(active, nxt, cur), active & (nxt >= n)

    first = hash_once(i)
    out, _ = jax.lax.while_loop(cond, body, (first, first >= n))
    return (out + p) % n


def pcg4d(x: Array, y: Array, z: Array, w: Array) -> Array:
    """The `pcg4d` hash of Jarzynski & Olano: four uint32 words in, four out, stacked on a new
    last axis `(..., 4)` (`Jarzynski2020`)."""
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
