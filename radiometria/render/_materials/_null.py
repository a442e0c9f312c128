"""Mitsuba's `null` BSDF: an index-matched boundary that light passes straight through."""

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ...scattering import AbstractBxDF, BSDFSample
from ._base import AbstractMaterial, Properties, unknown_parameters

__all__ = ["Null", "NullBxDF", "has_null", "is_null"]


class NullBxDF(AbstractBxDF):
    """Straight transmission, $f = \\delta(\\omega_i + \\omega_o)/|\\cos\\theta_i|$: every
    sample continues the ray unchanged with weight 1 (a delta lobe: no MIS with lights).

    **Fields:**

    - `like`: an array of the paths' spectral shape `(n, k)` and dtype (its values unused).

    ??? cite "References"
        `Jakob2022` (`null`); `Pharr2023` §14.1.2 (interfaces without a BSDF).
    """

    like: Float[Array, "n k"]  # any array of the paths' spectral shape and dtype

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        return jnp.zeros_like(self.like)

    def pdf(self, wo, wi) -> Array:
        return jnp.zeros(self.like.shape[:-1], self.like.dtype)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        cos = jnp.abs(wo[..., 2:3])
        one = jnp.ones(self.like.shape[:-1], self.like.dtype)
        return BSDFSample(
            f=jnp.ones_like(self.like) / jnp.where(cos > 0, cos, 1.0),
            wi=-wo,
            pdf=one,
            is_delta=jnp.ones_like(one, bool),
            is_transmission=jnp.ones_like(one, bool),
            eta=one,
            terminate_secondary=jnp.zeros_like(one, bool),
        )


class Null(AbstractMaterial):
    """Mitsuba's `null` BSDF: the surface is invisible, a boundary of the media on its sides
    (thesis ch. 9). `volpath` crosses such surfaces without counting a bounce; `path` treats
    them as a delta transmission of weight 1.

    **Fields:**

    - `two_sided`: `(m,)` bool (both sides always pass light).

    !!! note "Thesis"
        Chapter 9 (volume rendering; title only in the text): index-matched medium boundaries.

    ??? cite "References"
        `Jakob2022` (`null`); `Pharr2023` §14.1.2.
    """

    NAME: ClassVar[str] = "null"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset()
    TRANSMISSIVE: ClassVar[bool] = True
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        unknown_parameters(params, cls, where)
        return cls(device_array([True], bool))

    def bxdf(self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"]) -> NullBxDF:
        return NullBxDF(jnp.zeros_like(wavelength_nm))


def is_null(materials) -> Array:
    """`(m,)` bool: which materials of a `MaterialSet` are `null` (from the plugins' kinds,
    a constant under `jit`)."""
    kinds = device_array([isinstance(p, Null) for p in materials.plugins], bool)
    return kinds[materials.plugin_of]


def has_null(materials) -> bool:
    """Whether a `MaterialSet` holds any `null` material (static: from the plugins' kinds)."""
    return any(isinstance(p, Null) for p in materials.plugins)
