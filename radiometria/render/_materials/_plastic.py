"""Mitsuba's `plastic` and `roughplastic` BSDFs: a dielectric coating over a diffuse base."""

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ...scattering import PlasticBxDF, RoughPlasticBxDF, rough_plastic_tables
from ...upsampling import RGBAlbedoSpectrum, RGBUnboundedSpectrum
from .._textures import AbstractTexture, ConstantTexture, texture_parameter
from ._base import AbstractMaterial, Properties, scalar, unknown_parameters
from ._ior import MITSUBA_IOR

__all__ = ["Plastic", "RoughPlastic"]


def _named_ior(params: Properties, name: str, default: str, where: str) -> float:
    """A scalar index (a number or one of Mitsuba's names), as Mitsuba's `lookup_ior`."""
    value = params.get(name, default)
    if isinstance(value, str):
        if value.lower() not in MITSUBA_IOR:
            raise ValueError(
                f"{where}: parameter {name!r}: unknown index of refraction {value!r}; known: "
                f"{', '.join(MITSUBA_IOR)}."
            )
        return float(MITSUBA_IOR[value.lower()])
    if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
        raise ValueError(
            f"{where}: parameter {name!r} must be a number > 0 or a named index of refraction "
            f"(the plastic BSDFs take no spectra, as in Mitsuba), got {value!r}."
        )
    return float(value)


def _coating(params: Properties, where: str, cls: type) -> dict:
    """The parameters both plastics share, as rows."""
    unknown_parameters(params, cls, where)
    diffuse = params.get("diffuse_reflectance", 0.5)
    d = texture_parameter(diffuse, RGBAlbedoSpectrum, "diffuse_reflectance", where)
    if d is None:
        d = ConstantTexture.from_values([diffuse], RGBAlbedoSpectrum)
    specular = params.get("specular_reflectance", 1.0)
    s = texture_parameter(specular, RGBUnboundedSpectrum, "specular_reflectance", where)
    if s is None:
        s = ConstantTexture.from_values([specular], RGBUnboundedSpectrum)
    eta = _named_ior(params, "int_ior", "polypropylene", where) / _named_ior(
        params, "ext_ior", "air", where
    )
    nonlinear = params.get("nonlinear", False)
    if not isinstance(nonlinear, bool):
        raise ValueError(f"{where}: parameter 'nonlinear' must be a boolean, got {nonlinear!r}.")
    return {"d": d, "s": s, "eta": eta, "nonlinear": nonlinear}


class Plastic(AbstractMaterial):
    """Smooth plastic (Mitsuba's `plastic`): a smooth dielectric coating over a Lambertian
    base, with Mitsuba's internal-scattering factor and lobe-sampling weights
    (`radiometria.scattering.PlasticBxDF`).

    **Fields:**

    - `diffuse_reflectance`: texture of the base albedo (default 0.5, upsampled as a bounded
        `RGBAlbedoSpectrum`). [1]
    - `specular_reflectance`: texture of the factor on the coating reflection (default 1). [1]
    - `eta`: `(m,)` `int_ior / ext_ior` (numbers or Mitsuba's names; defaults polypropylene
        over air). [1]
    - `nonlinear`: `(m,)` bool, Mitsuba's `nonlinear` (internal scattering darkens and
        saturates the base colour).
    - `two_sided`: `(m,)` bool.

    !!! note "Thesis"
        Section 3.1 (diffuse and specular reflection), eq. 3.13-3.18.

    ??? cite "References"
        `Jakob2022` (`plastic`); `Weidlich2007`.
    """

    NAME: ClassVar[str] = "plastic"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"diffuse_reflectance", "specular_reflectance", "int_ior", "ext_ior", "nonlinear"}
    )
    USES_UV: ClassVar[bool] = True
    diffuse_reflectance: AbstractTexture
    specular_reflectance: AbstractTexture
    eta: Float[Array, " m"]
    nonlinear: Bool[Array, " m"]
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        c = _coating(params, where, cls)
        return cls(
            c["d"],
            c["s"],
            device_array([c["eta"]], jnp.float32),
            device_array([c["nonlinear"]], bool),
            device_array([two_sided], bool),
        )

    def bxdf(self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"], uv=None):
        d = self.diffuse_reflectance(row, wavelength_nm, uv)
        s = self.specular_reflectance(row, wavelength_nm, uv)
        return PlasticBxDF(d, self.eta[row], s, nonlinear=self.nonlinear[row])


class RoughPlastic(AbstractMaterial):
    """Rough plastic (Mitsuba's `roughplastic`): a microfacet dielectric coating over a
    Lambertian base (`radiometria.scattering.RoughPlasticBxDF`); the coating's transmittance
    table and internal reflectance are precomputed per material as Mitsuba does
    (`rough_plastic_tables`).

    **Fields:**

    - `diffuse_reflectance`, `specular_reflectance`, `eta`, `nonlinear`, `two_sided`: as in
        `Plastic`.
    - `alpha`: `(m,)` roughness (default 0.1). [1]
    - `external_transmittance`: `(m, 64)`; `internal_reflectance`: `(m,)`. [1]
    - `distribution`: static, the microfacet distribution of every row (`"beckmann"`, Mitsuba's
        default, or `"ggx"`); all rough plastics of a scene share one (mixing them is refused
        when the scene's materials are grouped).

    !!! note "Thesis"
        Section 3.1 (glossy and diffuse reflection), eq. 3.13-3.18.

    ??? cite "References"
        `Jakob2022` (`roughplastic`); `Walter2007`; `Weidlich2007`.
    """

    NAME: ClassVar[str] = "roughplastic"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {
            "diffuse_reflectance",
            "specular_reflectance",
            "int_ior",
            "ext_ior",
            "nonlinear",
            "alpha",
            "distribution",
            "sample_visible",
        }
    )
    USES_UV: ClassVar[bool] = True
    diffuse_reflectance: AbstractTexture
    specular_reflectance: AbstractTexture
    eta: Float[Array, " m"]
    nonlinear: Bool[Array, " m"]
    alpha: Float[Array, " m"]
    external_transmittance: Float[Array, "m 64"]
    internal_reflectance: Float[Array, " m"]
    two_sided: Bool[Array, " m"]
    distribution: str = eqx.field(static=True, default="beckmann")

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        c = _coating(params, where, cls)
        alpha = scalar(params, "alpha", 0.1, where)
        if not 0.0 < alpha <= 1.0:
            raise ValueError(f"{where}: parameter 'alpha' must lie in (0, 1], got {alpha}.")
        distribution = params.get("distribution", "beckmann")
        if distribution not in ("beckmann", "ggx"):
            raise ValueError(
                f"{where}: parameter 'distribution' must be 'beckmann' or 'ggx', got "
                f"{distribution!r}."
            )
        if params.get("sample_visible", True) is not True:
            raise ValueError(
                f"{where}: parameter 'sample_visible' must be true (visible-normal sampling; "
                "Mitsuba's rough-coating tables need it too)."
            )
        if c["eta"] == 1.0:
            raise ValueError(f"{where}: int_ior and ext_ior must differ (Mitsuba's rule).")
        t, r = rough_plastic_tables(alpha, c["eta"], distribution)
        return cls(
            c["d"],
            c["s"],
            device_array([c["eta"]], jnp.float32),
            device_array([c["nonlinear"]], bool),
            device_array([alpha], jnp.float32),
            device_array(t, jnp.float32)[None],
            device_array([r], jnp.float32),
            device_array([two_sided], bool),
            distribution,
        )

    def bxdf(self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"], uv=None):
        d = self.diffuse_reflectance(row, wavelength_nm, uv)
        s = self.specular_reflectance(row, wavelength_nm, uv)
        tables = (self.external_transmittance[row], self.internal_reflectance[row])
        return RoughPlasticBxDF(
            d, self.alpha[row], self.eta[row], s, distribution=self.distribution,
            nonlinear=self.nonlinear[row], tables=tables,
        )  # fmt: skip
