"""Mitsuba's `diffuse` BSDF: Lambertian reflection (thesis eq. 3.4, section 3.1)."""

from typing import ClassVar

from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ...scattering import DiffuseBxDF
from ...upsampling import RGBAlbedoSpectrum
from .._textures import AbstractTexture, ConstantTexture, texture_parameter
from ._base import AbstractMaterial, Properties, unknown_parameters


class Diffuse(AbstractMaterial):
    """Lambertian reflectors (Mitsuba's `diffuse`): $f = R/\\pi$.

    **Fields:**

    - `reflectance`: a texture of $R$ in [0, 1] per material (default 0.5; an RGB triple is
        upsampled as a bounded `RGBAlbedoSpectrum`; a scene's `bitmap` or `checkerboard`
        texture, looked up at the hit's uv). [1]
    - `two_sided`: `(m,)` bool, scatter on both sides.

    !!! note "Thesis"
        Eq. 3.4 and section 3.1 (diffuse reflection).

    ??? cite "References"
        `Jakob2022` (`diffuse`); `Pharr2023` §9.2.
    """

    NAME: ClassVar[str] = "diffuse"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"reflectance"})
    USES_UV: ClassVar[bool] = True
    reflectance: AbstractTexture
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene") -> "Diffuse":
        unknown_parameters(params, cls, where)
        reflectance = params.get("reflectance", 0.5)
        texture = texture_parameter(reflectance, RGBAlbedoSpectrum, "reflectance", where)
        if texture is None:
            texture = ConstantTexture.from_values([reflectance], RGBAlbedoSpectrum)
        return cls(texture, device_array([two_sided], bool))

    def bxdf(
        self,
        row: Int[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        uv: Float[Array, "n _"] | None = None,
    ) -> DiffuseBxDF:
        return DiffuseBxDF(self.reflectance(row, wavelength_nm, uv))
