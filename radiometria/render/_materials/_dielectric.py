"""Mitsuba's `dielectric` BSDF: a smooth interface between two dielectrics (thesis 3.1.1)."""

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ...scattering import DielectricBxDF
from ...upsampling import RGBAlbedoSpectrum, RGBUnboundedSpectrum
from .._spectral import SpectrumTable
from .._textures import AbstractTexture, ConstantTexture, texture_parameter
from ._base import AbstractMaterial, Properties, ScaledBxDF, unknown_parameters
from ._ior import dielectric_ior


def dielectric_textures(params: Properties, where: str) -> tuple[AbstractTexture, ...]:
    """`(eta, specular_reflectance, specular_transmittance)` textures of one dielectric; the
    two lobe factors may be textures (bitmap, checkerboard, mesh attribute), upsampled as
    bounded reflectances, as Mitsuba's bitmaps are."""
    eta = ConstantTexture(
        SpectrumTable(device_array(dielectric_ior(params, where)[None], jnp.float32))
    )
    factors = [
        texture_parameter(params.get(name), RGBAlbedoSpectrum, name, where)
        or ConstantTexture.from_values([params.get(name, 1.0)], RGBUnboundedSpectrum)
        for name in ("specular_reflectance", "specular_transmittance")
    ]
    return eta, *factors


class _AbstractSmoothDielectric(AbstractMaterial):
    """The parameters, fields and loading that `Dielectric` and `ThinDielectric` share:
    `eta` and the two lobe factors as textures (`dielectric_textures`); with
    `ALWAYS_TWO_SIDED`, both sides scatter whatever the scene's `twosided` says."""

    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"int_ior", "ext_ior", "specular_reflectance", "specular_transmittance"}
    )
    TRANSMISSIVE: ClassVar[bool] = True
    USES_UV: ClassVar[bool] = True
    ALWAYS_TWO_SIDED: ClassVar[bool] = False
    eta: AbstractTexture
    specular_reflectance: AbstractTexture
    specular_transmittance: AbstractTexture
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        unknown_parameters(params, cls, where)
        two_sided = True if cls.ALWAYS_TWO_SIDED else two_sided
        return cls(*dielectric_textures(params, where), device_array([two_sided], bool))


class Dielectric(_AbstractSmoothDielectric):
    """Smooth dielectric interfaces (Mitsuba's `dielectric`): Fresnel reflection and Snell
    refraction, dispersive when the index varies with wavelength.

    **Fields:**

    - `eta`: texture of the relative index `int_ior / ext_ior` (Mitsuba's defaults: BK7 in
        air; named indices are `MITSUBA_IOR`). [1]
    - `specular_reflectance`, `specular_transmittance`: textures of factors on the reflected
        and transmitted parts (default 1). [1]
    - `two_sided`: `(m,)` bool (both sides are always surfaces of the medium).

    !!! note "Thesis"
        Section 3.1.1, eq. 3.13-3.18 (Fresnel equations), Snell's law.

    ??? cite "References"
        `Jakob2022` (`dielectric`); `Pharr2023` §9.3.
    """

    NAME: ClassVar[str] = "dielectric"

    def bxdf(
        self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"], uv=None
    ) -> ScaledBxDF:
        eta = jnp.maximum(self.eta(row, wavelength_nm), 1e-3)
        return ScaledBxDF(
            DielectricBxDF(eta),
            self.specular_reflectance(row, wavelength_nm, uv),
            self.specular_transmittance(row, wavelength_nm, uv),
        )
