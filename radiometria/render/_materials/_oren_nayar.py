"""Rough diffuse reflection: the Oren-Nayar model (thesis section 3.1)."""

import math
from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ...scattering import OrenNayarBxDF
from ...upsampling import RGBAlbedoSpectrum
from .._textures import AbstractTexture, ConstantTexture
from ._base import AbstractMaterial, Properties, scalar, unknown_parameters


class OrenNayar(AbstractMaterial):
    r"""Rough Lambertian V-cavities (Mitsuba 0.6's `roughdiffuse`, the qualitative model).

    The facet slope angle has standard deviation $\sigma = \alpha/\sqrt2$ [rad], where
    $\alpha$ is the RMS surface slope a scene file gives (Mitsuba 0.6's convention); the BxDF
    is `radiometria.scattering.OrenNayarBxDF` (the qualitative model of `Oren1994`, Mitsuba
    0.6's `useFastApprox`).

    **Fields:**

    - `reflectance`: texture of the facet albedo $R$ in [0, 1] (default 0.5). [1]
    - `sigma`: `(m,)` slope-angle standard deviation in [0, pi/2]. [rad]
    - `two_sided`: `(m,)` bool, scatter on both sides.

    !!! note "Thesis"
        Section 3.1 (diffuse and retroreflective reflection), eq. 3.4.

    ??? cite "References"
        `Oren1994`; `Pharr2016` §8.4.2.
    """

    NAME: ClassVar[str] = "roughdiffuse"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"reflectance", "alpha"})
    reflectance: AbstractTexture
    sigma: Float[Array, " m"]
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene") -> "OrenNayar":
        unknown_parameters(params, cls, where)
        alpha = scalar(params, "alpha", 0.2, where)
        sigma = alpha / math.sqrt(2.0)
        if not 0.0 <= sigma <= math.pi / 2:
            raise ValueError(
                f"{where}: 'alpha' of a roughdiffuse BSDF must give a slope-angle deviation "
                f"alpha / sqrt(2) in [0, pi/2] [rad], got alpha = {alpha}."
            )
        return cls(
            ConstantTexture.from_values([params.get("reflectance", 0.5)], RGBAlbedoSpectrum),
            device_array([sigma], jnp.float32),
            device_array([two_sided], bool),
        )

    def bxdf(self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"]) -> OrenNayarBxDF:
        return OrenNayarBxDF(self.reflectance(row, wavelength_nm), self.sigma[row])
