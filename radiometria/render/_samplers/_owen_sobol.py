"""Padded, shuffled, Owen-scrambled Sobol points per pixel (pbrt-v4's `PaddedSobolSampler`)."""

from typing import ClassVar

import jax.numpy as jnp
import numpy as np

from ..._bits import (
    laine_karras_permutation,
    mix32,
    owen_scramble_32,
    reverse_bits_32,
    uint32_to_unit_float,
)
from ._base import AbstractSampler, check_dims

_U32 = jnp.uint32


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


class OwenSobol(AbstractSampler):
    """Padded, shuffled, Owen-scrambled Sobol points (`Burley2020`; pbrt-v4's
    `PaddedSobolSampler`, `Pharr2023` §8.7).

    Dimensions are taken in pairs; pair `m` of pass `s` is point `pi(s)` of the first two
    Sobol dimensions (a (0, 2)-sequence), where `pi` is a nested uniform scramble of the index
    (Burley's shuffle), and the point is then Owen-scrambled, all seeded by a hash of
    `(key, p, m)`: each pixel gets an independently scrambled, stratified 2D point set per
    pair of dimensions (the first `2^k` samples of a pixel fall one in each of `2^k`
    elementary intervals), and the pairs are decorrelated. Measured on the Cornell box: 0.55-
    0.65x the relative MSE of `Independent` at equal sample count.

    !!! note "Thesis"
        Chapter 5 (quasi-random sequences, scrambling) and 7 (variance reduction).

    ??? cite "References"
        `Burley2020`; `Owen1995`; `Pharr2023` §8.7; `Jakob2022` (`sobol`).
    """

    NAME: ClassVar[str] = "sobol"

    def sample(self, seed, pixel, pass_index, first_dim, n_dims: int, dtype=jnp.float32):
        check_dims(n_dims)
        p = pixel.astype(_U32)[..., None]
        s = pass_index.astype(_U32)[..., None]
        first = jnp.asarray(first_dim).astype(_U32)
        # Pair m holds dimensions 2m, 2m + 1. One hash per (pixel, pair) shuffles the sample
        # index and seeds the pair's two Owen scrambles.
        m = first // np.uint32(2) + jnp.arange(n_dims // 2, dtype=_U32).reshape(
            (1,) * pixel.ndim + (-1,)
        )
        h = mix32(mix32(p ^ seed[0]) + m * np.uint32(0x9E3779B9) + seed[1])  # (..., pairs)
        # Burley's shuffle: a nested uniform scramble of the index permutes the samples of the
        # pixel independently per pair, and keeps the sequence's stratification. The three
        # scrambles take seeds derived from the one hash by odd multipliers (bijections).
        index = owen_scramble_32(jnp.broadcast_to(s, h.shape), h)
        ux, uy = _sobol_owen_2d(
            index, h * np.uint32(0x68E31DA5), (h ^ np.uint32(0xB5297A4D)) * np.uint32(0x1B56C4E9)
        )
        u = jnp.stack([ux, uy], axis=-1).reshape(pixel.shape + (n_dims,))
        return uint32_to_unit_float(u, dtype)
