"""Mitsuba's `roughconductor` BSDF: microfacet metal (thesis ch. 3; Beckmann or GGX)."""

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ...scattering import RoughConductorBxDF
from .._textures import AbstractTexture
from ._base import AbstractMaterial, Properties, ScaledBxDF, parameters_differ, unknown_parameters
from ._composite import scalar_texture
from ._conductor import conductor_textures, valid_ior

DISTRIBUTIONS = ("beckmann", "ggx")


def distribution(params: Properties, where: str) -> str:
    """The scene's `distribution`: Mitsuba's default is `"beckmann"` for `roughconductor`
    and `roughdielectric` (`Jakob2022`); `"ggx"` is the other one supported."""
    value = params.get("distribution", "beckmann")
    if value not in DISTRIBUTIONS:
        raise ValueError(
            f"{where}: unknown microfacet distribution {value!r}; valid: "
            f"{', '.join(map(repr, DISTRIBUTIONS))} (default 'beckmann')."
        )
    return value


def roughness(params: Properties, where: str) -> tuple[AbstractTexture, AbstractTexture]:
    """`(alpha_u, alpha_v)` as one-row grey textures: numbers >= 0 or textures (Mitsuba's
    default `alpha` = 0.1; `alpha_u`, `alpha_v` default to `alpha`)."""
    alpha = params.get("alpha", 0.1)
    inf = float("inf")
    return tuple(
        scalar_texture(params.get(name, alpha), name, where, lower=0.0, upper=inf)
        for name in ("alpha_u", "alpha_v")
    )


class RoughConductor(AbstractMaterial):
    """Rough conductors (Mitsuba's `roughconductor`) with the Beckmann distribution (Mitsuba's
    default) and anisotropic `alpha_u`/`alpha_v` as given; `distribution="ggx"` gives
    `GGXRoughConductor`, the same plugin with the Trowbridge-Reitz (GGX) distribution (a
    separate kind, so that scenes may mix the two). An unknown `distribution` is an error.
    `sample_visible` is read and visible normals are always sampled (the estimate's
    expectation is the same; only the noise differs). Shadowing-masking is Smith's separable
    G1(wo) G1(wi), as in Mitsuba 3 (pbrt-v4's height-correlated form is the
    BxDF's default, `masking="height_correlated"`).

    **Fields:**

    - `eta`, `k`, `specular_reflectance`: as `Conductor`. [1]
    - `alpha_u`, `alpha_v`: grey textures of the roughness along the tangent and bitangent
        (numbers, or textures looked up at the hit's uv). [1]
    - `two_sided`: `(m,)` bool.

    !!! note "Thesis"
        Chapter 3 (glossy reflection), eq. 3.13-3.18.

    ??? cite "References"
        `Walter2007`; `Heitz2018`; `HeitzDEon2014`; `Jakob2022` (`roughconductor`);
        `Pharr2023` §9.6.
    """

    NAME: ClassVar[str] = "roughconductor"
    DISTRIBUTION: ClassVar[str] = "beckmann"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"material", "eta", "k", "specular_reflectance", "distribution", "alpha", "alpha_u",
         "alpha_v", "sample_visible"}
    )  # fmt: skip
    USES_UV: ClassVar[bool] = True
    eta: AbstractTexture
    k: AbstractTexture
    specular_reflectance: AbstractTexture
    alpha_u: AbstractTexture
    alpha_v: AbstractTexture
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        unknown_parameters(params, cls, where)
        kind = {"beckmann": RoughConductor, "ggx": GGXRoughConductor}[distribution(params, where)]
        return kind(
            *conductor_textures(params, where),
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
        refl = self.specular_reflectance(row, wavelength_nm, uv)
        eta, k = valid_ior(self.eta(row, wavelength_nm, uv), self.k(row, wavelength_nm, uv))
        alpha_u, alpha_v = (
            jnp.maximum(a(row, wavelength_nm, uv)[..., 0], 1e-4)
            for a in (self.alpha_u, self.alpha_v)
        )
        bxdf = RoughConductorBxDF(
            alpha_u, eta, k, alpha_v, distribution=self.DISTRIBUTION, masking="separable"
        )
        return ScaledBxDF(bxdf, refl, refl)


class GGXRoughConductor(RoughConductor):
    """`RoughConductor` with the Trowbridge-Reitz (GGX) distribution (`distribution="ggx"`)."""

    DISTRIBUTION: ClassVar[str] = "ggx"
