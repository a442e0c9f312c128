"""The sampler interface of the render driver: the variates of sample `s` of pixel `p`."""

import abc
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float, Int, UInt32

__all__ = ["AbstractSampler", "sampler_seed"]


def sampler_seed(key) -> UInt32[Array, "2"]:
    """The two uint32 words that seed the samplers, derived from a `jax.random` key.

    **Arguments:**

    - `key`: a `jax.random` key (the render's seed). [key]

    **Returns:**

    `(2,)` uint32 words, computed once per render outside the loops. [1]

    !!! note "Thesis"
        Appendix C (pseudo-random numbers): the seed of the counter-based samplers.
    """
    return jax.random.key_data(jax.random.fold_in(key, 0x50B01)).reshape(-1)[:2].astype(jnp.uint32)


class AbstractSampler(eqx.Module):
    """A counter-based pixel sampler: the variates of one (pixel, sample) pair depend only on
    the seed, the sample index `s` and the pixel index `p`, never on how the driver batches
    the work or how many devices it uses, so every batching and sharding gives the same image.

    Dimensions `0 .. 3` serve the camera (film position, wavelength); integrators number their
    own after those (`AbstractIntegrator`).

    **Subclasses provide:**

    - `NAME`: the sampler's name on the command line (Mitsuba's where one exists).
    - `sample(seed, pixel, pass_index, first_dim, n_dims, dtype)`.

    !!! note "Thesis"
        Chapters 5-7 (quasi-random sampling, Monte Carlo integration, variance reduction).

    ??? cite "References"
        `Pharr2023` ch. 8 (samplers); `Jakob2022` (Mitsuba 3's sampler plugins).
    """

    NAME: ClassVar[str]

    @abc.abstractmethod
    def sample(
        self,
        seed: UInt32[Array, "2"],
        pixel: Int[Array, "*batch"],
        pass_index: Int[Array, "*batch"],
        first_dim,
        n_dims: int,
        dtype=jnp.float32,
    ) -> Float[Array, "*batch d"]:
        """Variates `first_dim .. first_dim + n_dims - 1` of sample `pass_index` of pixel
        `pixel`, in [0, 1), shape `pixel.shape + (n_dims,)`.

        **Arguments:**

        - `seed`: the two words of `sampler_seed(key)` (computed once, outside loops).
        - `pixel`, `pass_index`: int32 arrays of one shape: flat pixel indices
            `y * width + x` and sample indices within the pixel.
        - `first_dim`: the first dimension, a multiple of 4 (may be traced).
        - `n_dims`: how many dimensions, a static multiple of 4.
        - `dtype`: float dtype of the result.
        """


def check_dims(n_dims: int) -> None:
    if n_dims % 4:
        raise ValueError(f"`n_dims` must be a multiple of 4, got {n_dims}.")
