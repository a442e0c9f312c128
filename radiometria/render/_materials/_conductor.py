"""Mitsuba's `conductor` BSDF: a smooth metal (thesis eq. 3.13-3.18, complex index)."""

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ...scattering import ConductorBxDF
from ...upsampling import RGBAlbedoSpectrum, RGBUnboundedSpectrum
from .._spectral import SpectrumTable
from .._textures import AbstractTexture, ConstantTexture, TextureSpec, texture_parameter
from ._base import AbstractMaterial, Properties, ScaledBxDF, unknown_parameters
from ._ior import conductor_ior


def conductor_textures(params: Properties, where: str) -> tuple[AbstractTexture, ...]:
    """`(eta, k, specular_reflectance)` textures of one conductor (Mitsuba's defaults); a
    textured `specular_reflectance` is upsampled as a bounded reflectance, as Mitsuba's
    bitmaps are. `eta` and `k` may be textures too (Mitsuba's conductors read them as
    textures): their values upsampled as unbounded spectra, the other one as given."""
    textured = {
        name: texture_parameter(params[name], RGBUnboundedSpectrum, name, where)
        for name in ("eta", "k")
        if isinstance(params.get(name), TextureSpec)
    }
    plain = {n: v for n, v in params.items() if n not in textured}
    if textured:  # a given index: the other part keeps Mitsuba's default (eta 0, k 1)
        plain.setdefault("eta", 0.0)
    eta, k = conductor_ior(plain, where)
    spec = params.get("specular_reflectance", 1.0)
    refl = texture_parameter(spec, RGBAlbedoSpectrum, "specular_reflectance", where)
    if refl is None:
        refl = ConstantTexture.from_values([spec], RGBUnboundedSpectrum)
    table = lambda x: ConstantTexture(SpectrumTable(device_array(x[None], jnp.float32)))
    return textured.get("eta", table(eta)), textured.get("k", table(k)), refl


def valid_ior(eta: Array, k: Array) -> tuple[Array, Array]:
    """Keep the complex index inside the BxDF constructors' ranges (`eta > 0`, `k >= 0`)."""
    return jnp.maximum(eta, 1e-3), jnp.maximum(k, 0.0)


class Conductor(AbstractMaterial):
    """Smooth conductors (Mitsuba's `conductor`): a mirror with the Fresnel reflectance of the
    complex index `eta + i k`, times `specular_reflectance`.

    **Fields:**

    - `eta`, `k`: textures of the real and imaginary parts of the index, relative to the
        outside (from `material`: `"none"`, the default, a perfect mirror; `"Au"`, `"Ag"`,
        `"Cu"`, `"Al"`: measured tables; or given as spectra or textures). [1]
    - `specular_reflectance`: texture of a factor on the reflectance (default 1; a number, a
        spectrum or a bitmap/checkerboard looked up at the hit's uv). [1]
    - `two_sided`: `(m,)` bool.

    !!! note "Thesis"
        Eq. 3.13-3.18 (Fresnel equations), footnote 18 (complex index of a conductor).

    ??? cite "References"
        `Jakob2022` (`conductor`); `Pharr2023` §9.4.
    """

    NAME: ClassVar[str] = "conductor"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"material", "eta", "k", "specular_reflectance"}
    )
    USES_UV: ClassVar[bool] = True
    eta: AbstractTexture
    k: AbstractTexture
    specular_reflectance: AbstractTexture
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        unknown_parameters(params, cls, where)
        return cls(*conductor_textures(params, where), device_array([two_sided], bool))

    def bxdf(
        self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"], uv=None
    ) -> ScaledBxDF:
        refl = self.specular_reflectance(row, wavelength_nm, uv)
        eta, k = valid_ior(self.eta(row, wavelength_nm, uv), self.k(row, wavelength_nm, uv))
        return ScaledBxDF(ConductorBxDF(eta, k), refl, refl)
