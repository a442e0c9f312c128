"""Mitsuba's `roughdielectric` BSDF: a microfacet dielectric interface (thesis ch. 3)."""

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ...scattering import RoughDielectricBxDF
from .._textures import AbstractTexture
from ._base import AbstractMaterial, Properties, ScaledBxDF, parameters_differ, unknown_parameters
from ._dielectric import dielectric_textures
from ._rough_conductor import distribution, roughness


class RoughDielectric(AbstractMaterial):
    """Rough dielectric interfaces (Mitsuba's `roughdielectric`) with the Beckmann distribution
    (Mitsuba's default); `distribution="ggx"` gives `GGXRoughDielectric` (Trowbridge-Reitz),
    as `RoughConductor`. `sample_visible` is read; visible normals are always sampled.
    Shadowing-masking is Smith's separable form, as in Mitsuba 3 (`RoughConductor`).

    **Fields:**

    - `eta`, `specular_reflectance`, `specular_transmittance`: as `Dielectric`. [1]
    - `alpha_u`, `alpha_v`: grey textures of the roughness (default `alpha` = 0.1; numbers,
        or textures looked up at the hit's uv). [1]
    - `two_sided`: `(m,)` bool.

    !!! note "Thesis"
        Chapter 3 (glossy transmission), eq. 3.13-3.18.

    ??? cite "References"
        `Walter2007`; `HeitzDEon2014`; `Jakob2022` (`roughdielectric`); `Pharr2023` §9.7.
    """

    NAME: ClassVar[str] = "roughdielectric"
    DISTRIBUTION: ClassVar[str] = "beckmann"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"int_ior", "ext_ior", "specular_reflectance", "specular_transmittance",
         "distribution", "alpha", "alpha_u", "alpha_v", "sample_visible"}
    )  # fmt: skip
    TRANSMISSIVE: ClassVar[bool] = True
    USES_UV: ClassVar[bool] = True
    eta: AbstractTexture
    specular_reflectance: AbstractTexture
    specular_transmittance: AbstractTexture
    alpha_u: AbstractTexture
    alpha_v: AbstractTexture
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        unknown_parameters(params, cls, where)
        kind = {"beckmann": RoughDielectric, "ggx": GGXRoughDielectric}[distribution(params, where)]
        return kind(
            *dielectric_textures(params, where),
            *roughness(params, where),
            device_array([two_sided], bool),
        )

    @property
    def tangent_frame(self) -> bool:
        """Anisotropic rows (`alpha_u` differs from `alpha_v`) turn with dp/du."""
        return parameters_differ(self.alpha_u, self.alpha_v)

    def bxdf(
        self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"], uv=None
    ) -> ScaledBxDF:
        eta = jnp.maximum(self.eta(row, wavelength_nm), 1e-3)
        alpha_u, alpha_v = (
            jnp.maximum(a(row, wavelength_nm, uv)[..., 0], 1e-4)
            for a in (self.alpha_u, self.alpha_v)
        )
        return ScaledBxDF(
            RoughDielectricBxDF(
                alpha_u, eta, alpha_v, distribution=self.DISTRIBUTION, masking="separable"
            ),
            self.specular_reflectance(row, wavelength_nm, uv),
            self.specular_transmittance(row, wavelength_nm, uv),
        )


class GGXRoughDielectric(RoughDielectric):
    """`RoughDielectric` with the Trowbridge-Reitz (GGX) distribution (`distribution="ggx"`)."""

    DISTRIBUTION: ClassVar[str] = "ggx"
