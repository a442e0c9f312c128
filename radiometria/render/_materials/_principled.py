"""Mitsuba's `principled` BSDF: the Disney BSDF (`radiometria.scattering.PrincipledBxDF`)."""

import functools
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ..._math import interp_columns
from ...colorimetry import get_cmfs
from ...scattering import PrincipledBxDF, PrincipledThinBxDF, principled_eta
from ...upsampling import RGBAlbedoSpectrum
from .._textures import AbstractTexture, ConstantTexture, texture_parameter
from ._base import AbstractMaterial, Properties, parameter_nonzero, scalar, unknown_parameters
from ._composite import scalar_texture

__all__ = ["Principled", "PrincipledThin"]

# Scalar parameters that Mitsuba reads as textures (`eval_1`), with its defaults.
_SCALARS = {
    "roughness": 0.5, "anisotropic": 0.0, "metallic": 0.0, "spec_trans": 0.0,
    "spec_tint": 0.0, "sheen": 0.0, "sheen_tint": 0.0, "flatness": 0.0, "clearcoat": 0.0,
    "clearcoat_gloss": 0.0,
}  # fmt: skip
_RATES = {
    "main_specular_sampling_rate": 1.0,
    "clearcoat_sampling_rate": 1.0,
    "diffuse_reflectance_sampling_rate": 1.0,
}


@functools.cache
def _ybar() -> tuple[np.ndarray, np.ndarray]:
    """CIE 1931 ybar on its 1 nm grid (NumPy, once)."""
    with jax.ensure_compile_time_eval():  # concrete tables even when first called under jit
        cmfs = get_cmfs("CIE 1931 2 Degree Standard Observer")
    return np.asarray(cmfs.wavelengths_nm), np.asarray(cmfs.values)[:, 1]


def path_luminance(color: Float[Array, "n k"], wavelength_nm: Float[Array, "n k"]) -> Array:
    """Mitsuba's `luminance(value, wavelengths)` in its spectral variants: the mean over a
    path's wavelengths of $\\bar y(\\lambda)\\,C(\\lambda)$ (no division by the wavelength
    density), `(n,)`; the principled BSDF's tints divide by it."""
    wl, y = _ybar()
    ybar = interp_columns(
        wavelength_nm, device_array(wl, color.dtype), device_array(y, color.dtype)
    )
    return jnp.mean(ybar * color, axis=-1)


def _has(params: Properties, name: str) -> bool:
    """Mitsuba's `get_flag`: the parameter is given and is not the number 0."""
    value = params.get(name)
    return value is not None and not (isinstance(value, int | float) and value == 0.0)


def _base_color(params: Properties, where: str) -> AbstractTexture:
    """`base_color` (default 0.5): a texture, or a constant upsampled as an albedo."""
    color = params.get("base_color", 0.5)
    base = texture_parameter(color, RGBAlbedoSpectrum, "base_color", where)
    return ConstantTexture.from_values([color], RGBAlbedoSpectrum) if base is None else base


class Principled(AbstractMaterial):
    """The principled (Disney) BSDF as Mitsuba 3's `principled`.

    Every lobe, the Fresnel blend and the lobe-selection probabilities follow Mitsuba's plugin
    (`PrincipledBxDF`, whose notes list them and where the model gains energy). The tints
    divide `base_color` by its luminance over the path's four wavelengths, as Mitsuba's
    spectral variants do (`path_luminance`).

    **Fields:**

    - `base_color`: texture of the base colour (default 0.5, an `RGBAlbedoSpectrum`). [1]
    - `roughness`, `anisotropic`, `metallic`, `spec_trans`, `spec_tint`, `sheen`,
        `sheen_tint`, `flatness`, `clearcoat`, `clearcoat_gloss`: grey textures (numbers in
        [0, 1], or textures: Mitsuba's `eval_1`, the luminance of the texels). [1]
    - `eta`: `(m,)` relative index, `eta` as given (1 becomes 1.001 when `spec_trans` is
        given, as in Mitsuba) or from `specular` (default 0.5: 1.5) by `principled_eta`. [1]
    - `rates`: `(m, 3)` Mitsuba's specular, clearcoat and diffuse sampling rates. [1]
    - `transmits`: `(m,)` bool, rows with a `spec_trans` lobe (transmitting surfaces).
    - `two_sided`: `(m,)` bool.

    !!! note "Thesis"
        Section 3.1 (diffuse, glossy and specular lobes), eq. 3.4, 3.13-3.18.

    ??? cite "References"
        `Burley2012`; `Burley2015`; `Jakob2022` (`principled`).
    """

    NAME: ClassVar[str] = "principled"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"base_color", "eta", "specular", *_SCALARS, *_RATES}
    )
    USES_UV: ClassVar[bool] = True
    base_color: AbstractTexture
    roughness: AbstractTexture
    anisotropic: AbstractTexture
    metallic: AbstractTexture
    spec_trans: AbstractTexture
    spec_tint: AbstractTexture
    sheen: AbstractTexture
    sheen_tint: AbstractTexture
    flatness: AbstractTexture
    clearcoat: AbstractTexture
    clearcoat_gloss: AbstractTexture
    eta: Float[Array, " m"]
    rates: Float[Array, "m 3"]
    transmits: Bool[Array, " m"]
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        unknown_parameters(params, cls, where)
        base = _base_color(params, where)
        scalars = {
            name: scalar_texture(params.get(name, default), name, where)
            for name, default in _SCALARS.items()
        }
        transmits = _has(params, "spec_trans")
        if "eta" in params and "specular" in params:
            raise ValueError(
                f"{where}: give either 'eta' or 'specular' to the principled BSDF, not both "
                "(they set the same index of refraction, as in Mitsuba)."
            )
        if "eta" in params:
            eta = scalar(params, "eta", 1.5, where)
            if not eta > 0:
                raise ValueError(f"{where}: parameter 'eta' must be > 0, got {eta}.")
            eta = 1.001 if transmits and eta == 1.0 else eta
        else:
            specular = scalar(params, "specular", 0.5, where)
            if not 0.0 <= specular <= 1.0:
                raise ValueError(
                    f"{where}: parameter 'specular' must lie in [0, 1], got {specular}."
                )
            specular = 1e-3 if transmits and specular == 0.0 else specular
            eta = float(principled_eta(specular))
        rates = []
        for name, default in _RATES.items():
            rate = scalar(params, name, default, where)
            if not rate >= 0:
                raise ValueError(f"{where}: parameter {name!r} must be >= 0, got {rate}.")
            rates.append(rate)
        return cls(
            base,
            *scalars.values(),
            device_array([eta], jnp.float32),
            device_array([rates], jnp.float32),
            device_array([transmits], bool),
            device_array([two_sided], bool),
        )

    @property
    def transmissive_rows(self) -> Bool[Array, " m"]:
        return self.transmits

    @property
    def tangent_frame(self) -> bool:
        """Rows with `anisotropic` > 0 turn with dp/du."""
        return parameter_nonzero(self.anisotropic)

    def bxdf(
        self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"], uv=None
    ) -> PrincipledBxDF:
        color = self.base_color(row, wavelength_nm, uv)
        grey = {name: getattr(self, name)(row, wavelength_nm, uv)[..., 0] for name in _SCALARS}
        rates = self.rates[row]
        return PrincipledBxDF(
            jnp.clip(color, 0.0, 1.0),
            grey.pop("roughness"),
            **grey,
            eta=self.eta[row],
            luminance=path_luminance(color, wavelength_nm),
            specular_sampling_rate=rates[:, 0],
            clearcoat_sampling_rate=rates[:, 1],
            diffuse_sampling_rate=rates[:, 2],
        )


_THIN_SCALARS = {
    "roughness": 0.5, "anisotropic": 0.0, "spec_trans": 0.0, "spec_tint": 0.0, "sheen": 0.0,
    "sheen_tint": 0.0, "flatness": 0.0,
}  # fmt: skip
_THIN_RATES = {
    "specular_reflectance_sampling_rate": 1.0,
    "specular_transmittance_sampling_rate": 1.0,
    "diffuse_reflectance_sampling_rate": 1.0,
    "diffuse_transmittance_sampling_rate": 1.0,
}


class PrincipledThin(AbstractMaterial):
    """The thin principled BSDF as Mitsuba 3's `principledthin` (`PrincipledThinBxDF`): a
    two-dimensional sheet, the same from both sides (always two-sided, as in Mitsuba), that
    transmits when `spec_trans` or `diff_trans` is given.

    **Fields:**

    - `base_color`: as `Principled`. [1]
    - `roughness`, `anisotropic`, `spec_trans`, `spec_tint`, `sheen`, `sheen_tint`,
        `flatness`: grey textures in [0, 1]; `diff_trans`: grey texture in [0, 2]; `eta`:
        grey texture > 0 (default 1.5; a texture too, as in Mitsuba). [1]
    - `rates`: `(m, 4)` Mitsuba's specular reflection and transmission, diffuse reflection
        and transmission sampling rates. [1]
    - `transmits`, `two_sided`: `(m,)` bool.

    !!! note "Thesis"
        Section 3.1 (diffuse and glossy reflection and transmission), eq. 3.4, 3.13-3.18.

    ??? cite "References"
        `Burley2015`; `Jakob2022` (`principledthin`).
    """

    NAME: ClassVar[str] = "principledthin"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"base_color", "eta", "diff_trans", *_THIN_SCALARS, *_THIN_RATES}
    )
    USES_UV: ClassVar[bool] = True
    base_color: AbstractTexture
    roughness: AbstractTexture
    anisotropic: AbstractTexture
    spec_trans: AbstractTexture
    spec_tint: AbstractTexture
    sheen: AbstractTexture
    sheen_tint: AbstractTexture
    flatness: AbstractTexture
    diff_trans: AbstractTexture
    eta: AbstractTexture
    rates: Float[Array, "m 4"]
    transmits: Bool[Array, " m"]
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=True, where="scene"):
        unknown_parameters(params, cls, where)
        base = _base_color(params, where)
        scalars = [
            scalar_texture(params.get(name, default), name, where)
            for name, default in _THIN_SCALARS.items()
        ]
        diff = scalar_texture(params.get("diff_trans", 0.0), "diff_trans", where, upper=2.0)
        eta = params.get("eta", 1.5)
        if isinstance(eta, int | float) and not isinstance(eta, bool) and not eta > 0:
            raise ValueError(f"{where}: parameter 'eta' must be > 0, got {eta}.")
        eta = scalar_texture(eta, "eta", where, lower=1e-6, upper=float("inf"))
        rates = []
        for name, default in _THIN_RATES.items():
            rate = scalar(params, name, default, where)
            if not rate >= 0:
                raise ValueError(f"{where}: parameter {name!r} must be >= 0, got {rate}.")
            rates.append(rate)
        transmits = _has(params, "spec_trans") or _has(params, "diff_trans")
        return cls(
            base,
            *scalars,
            diff,
            eta,
            device_array([rates], jnp.float32),
            device_array([transmits], bool),
            device_array([True], bool),  # both sides scatter, whatever `twosided` says
        )

    @property
    def transmissive_rows(self) -> Bool[Array, " m"]:
        return self.transmits

    @property
    def tangent_frame(self) -> bool:
        """Rows with `anisotropic` > 0 turn with dp/du."""
        return parameter_nonzero(self.anisotropic)

    def bxdf(
        self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"], uv=None
    ) -> PrincipledThinBxDF:
        color = self.base_color(row, wavelength_nm, uv)
        grey = {
            name: getattr(self, name)(row, wavelength_nm, uv)[..., 0]
            for name in (*_THIN_SCALARS, "diff_trans", "eta")
        }
        rates = self.rates[row]
        return PrincipledThinBxDF(
            jnp.clip(color, 0.0, 1.0),
            grey.pop("roughness"),
            **grey,
            luminance=path_luminance(color, wavelength_nm),
            specular_reflectance_sampling_rate=rates[:, 0],
            specular_transmittance_sampling_rate=rates[:, 1],
            diffuse_reflectance_sampling_rate=rates[:, 2],
            diffuse_transmittance_sampling_rate=rates[:, 3],
        )
