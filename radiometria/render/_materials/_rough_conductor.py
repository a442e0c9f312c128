"""Mitsuba's `roughconductor` BSDF: microfacet metal (thesis ch. 3; Trowbridge-Reitz)."""

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from ...scattering import RoughConductorBxDF
from .._textures import AbstractTexture
from ._base import AbstractMaterial, Properties, ScaledBxDF, scalar, unknown_parameters
from ._conductor import conductor_textures, valid_ior


def roughness(params: Properties, where: str) -> tuple[Array, Array]:
    """`(alpha_u, alpha_v)` as `(1,)` float32 arrays (Mitsuba's default `alpha` = 0.1)."""
    alpha = scalar(params, "alpha", 0.1, where)
    alpha_u = scalar(params, "alpha_u", alpha, where)
    alpha_v = scalar(params, "alpha_v", alpha, where)
    return jnp.asarray([alpha_u], jnp.float32), jnp.asarray([alpha_v], jnp.float32)


class RoughConductor(AbstractMaterial):
    """Rough conductors (Mitsuba's `roughconductor`) with the Trowbridge-Reitz (GGX)
    distribution of `radiometria.scattering`, anisotropic `alpha_u`/`alpha_v` as given.

    The scene's `distribution` is read but GGX is used whatever it says (Mitsuba's default is
    Beckmann; the two differ in the tails of the highlight); `sample_visible` is read and
    visible normals are always sampled.

    **Fields:**

    - `eta`, `k`, `specular_reflectance`: as `Conductor`. [1]
    - `alpha_u`, `alpha_v`: `(m,)` roughness along the tangent and bitangent. [1]
    - `two_sided`: `(m,)` bool.

    !!! note "Thesis"
        Chapter 3 (glossy reflection), eq. 3.13-3.18.

    ??? cite "References"
        `Walter2007`; `Heitz2018`; `Jakob2022` (`roughconductor`); `Pharr2023` §9.6.
    """

    NAME: ClassVar[str] = "roughconductor"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"material", "eta", "k", "specular_reflectance", "distribution", "alpha", "alpha_u",
         "alpha_v", "sample_visible"}
    )  # fmt: skip
    eta: AbstractTexture
    k: AbstractTexture
    specular_reflectance: AbstractTexture
    alpha_u: Float[Array, " m"]
    alpha_v: Float[Array, " m"]
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        unknown_parameters(params, cls, where)
        return cls(
            *conductor_textures(params, where),
            *roughness(params, where),
            jnp.asarray([two_sided], bool),
        )

    def bxdf(self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"]) -> ScaledBxDF:
        refl = self.specular_reflectance(row, wavelength_nm)
        eta, k = valid_ior(self.eta(row, wavelength_nm), self.k(row, wavelength_nm))
        bxdf = RoughConductorBxDF(self.alpha_u[row], eta, k, self.alpha_v[row])
        return ScaledBxDF(bxdf, refl, refl)
