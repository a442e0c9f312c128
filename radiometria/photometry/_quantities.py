"""Photometric quantities from spectral radiometric ones (thesis section 2.1, eq. 2.1-2.5).

Every photometric quantity is its radiometric spectral density weighted by the spectral
luminous efficiency and integrated over wavelength, times the maximum luminous efficacy:

    X_v = K_m * integral X_e,lambda(lambda) V(lambda) dlambda

with (V, K_m) = (CIE 1924 V, `constants.K_M`) for photopic vision and (CIE 1951 V',
`constants.K_M_SCOTOPIC`) for scotopic vision. The formula is the same for every quantity
(eq. 2.1-2.5); only the units change, so the named functions below are thin, documented
wrappers of `luminous_quantity`.
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_choice, check_wavelength_grid
from ..radiometry import integrate_spectrum
from ._efficiency import EFFICACY, VISIONS, _efficiency_on


def _weighted(values: Array, wavelengths_nm: Array, axis: int, vision: str) -> tuple[Array, int]:
    """`values * V(wavelengths_nm)` with V broadcast along `axis`; returns it and the axis."""
    axis = check_wavelength_grid(values, wavelengths_nm, axis, same_shape_ok=True)
    efficiency = _efficiency_on(wavelengths_nm, vision)
    if efficiency.ndim == 1:
        shape = [1] * values.ndim
        shape[axis] = efficiency.shape[0]
        efficiency = jnp.broadcast_to(efficiency.reshape(shape), values.shape)
    return values * efficiency, axis


def luminous_quantity(
    spectral_values: ArrayLike,
    wavelengths_nm: ArrayLike,
    *,
    vision: str = "photopic",
    axis: int = -1,
) -> Float[Array, "..."]:
    r"""Photometric quantity of a sampled spectral radiometric quantity.

    $$X_v = K_m \int_\Lambda X_{e,\lambda}(\lambda)\, V(\lambda)\,\mathrm d\lambda$$

    V is linearly interpolated onto the given grid (exact where the grid falls on whole
    nanometres) and is 0 outside its table; the integral is the trapezoid rule over the given
    grid (`radiometry.integrate_spectrum`), so no sample outside the grid is assumed.

    **Arguments:**

    - `spectral_values`: the spectral radiometric quantity on the grid, wavelength axis `axis`.
        [W nm^-1, W m^-2 nm^-1, W sr^-1 nm^-1, W sr^-1 m^-2 nm^-1 or J nm^-1]
    - `wavelengths_nm`: strictly increasing grid, 1-D or of the shape of `spectral_values`. [nm]
    - `vision`: `"photopic"` (CIE 1924 V, `K_m` = `constants.K_M` = 683.002 lm W^-1) or
        `"scotopic"` (CIE 1951 V', `K'_m` = `constants.K_M_SCOTOPIC`).
    - `axis`: the wavelength axis of `spectral_values` (static int).

    **Returns:**

    The photometric quantity, with `axis` removed. [lm, lx, cd, cd m^-2 or lm s: the unit of
    the radiometric quantity with W replaced by lm]

    Shape mismatches and unknown `vision` raise `ValueError`, integer arrays `TypeError`, a grid
    that is not strictly increasing `equinox.EquinoxRuntimeError`. NaN samples propagate.

    !!! note "Thesis"
        Thesis eq. (2.1)-(2.5), section 2.1.

    ??? cite "References"
        `CIE2019` (CIE 018:2019); `BIPM2019` (the candela, K_cd).
    """
    check_choice(vision, "vision", VISIONS)
    values = as_float_array(spectral_values, "spectral_values")
    wavelengths_nm = as_float_array(wavelengths_nm, "wavelengths_nm")
    weighted, axis = _weighted(values, wavelengths_nm, axis, vision)
    return EFFICACY[vision] * integrate_spectrum(weighted, wavelengths_nm, axis=axis)


def _named(name: str, quantity: str, equation: str, unit_in: str, unit_out: str, note: str = ""):
    def fn(
        spectral_values: ArrayLike,
        wavelengths_nm: ArrayLike,
        *,
        vision: str = "photopic",
        axis: int = -1,
    ) -> Float[Array, "..."]:
        return luminous_quantity(spectral_values, wavelengths_nm, vision=vision, axis=axis)

    fn.__name__ = fn.__qualname__ = name
    fn.__module__ = __name__
    fn.__doc__ = f"""{quantity} from a sampled spectrum (`luminous_quantity` with these units).

    **Arguments:**

    - `spectral_values`: the spectral radiometric quantity on the grid. [{unit_in}]
    - `wavelengths_nm`: strictly increasing grid, 1-D or of the shape of `spectral_values`. [nm]
    - `vision`: `"photopic"` (V, K_m = 683.002 lm W^-1) or `"scotopic"` (V', `K_M_SCOTOPIC`).
    - `axis`: the wavelength axis of `spectral_values` (static int).

    **Returns:**

    {quantity}, with `axis` removed. [{unit_out}]{note}

    !!! note "Thesis"
        Thesis eq. ({equation}), section 2.1.

    ??? cite "References"
        `CIE2019` (CIE 018:2019).
    """
    return fn


luminous_energy = _named("luminous_energy", "Luminous energy Q_v", "2.1", "J nm^-1", "lm s")
luminous_flux = _named("luminous_flux", "Luminous flux Phi_v", "2.2", "W nm^-1", "lm")
illuminance = _named("illuminance", "Illuminance E_v", "2.3", "W m^-2 nm^-1", "lx = lm m^-2")
luminous_exitance = _named(
    "luminous_exitance", "Luminous exitance M_v", "2.3", "W m^-2 nm^-1", "lm m^-2"
)
luminous_intensity = _named(
    "luminous_intensity", "Luminous intensity I_v", "2.4", "W sr^-1 nm^-1", "cd = lm sr^-1"
)
luminance = _named(
    "luminance",
    "Luminance L_v",
    "2.5",
    "W sr^-1 m^-2 nm^-1",
    "cd m^-2",
    note="\n\n    With photopic vision this equals the emissive Y of the CIE 1931 2 degree\n"
    "    observer, whose y-bar is the CIE 1924 V(lambda) (colour-science's tables agree\n"
    "    to 5e-13).",
)


def luminous_efficacy(
    spectral_values: ArrayLike,
    wavelengths_nm: ArrayLike,
    *,
    vision: str = "photopic",
    axis: int = -1,
) -> Float[Array, "..."]:
    r"""Luminous efficacy of radiation of a spectrum: luminous over radiant quantity.

    $$K = \frac{K_m \int X_{e,\lambda} V\,\mathrm d\lambda}{\int X_{e,\lambda}\,\mathrm d\lambda}$$

    Both integrals run over the given grid (trapezoid rule), so radiation outside the grid is
    not counted. Any spectral radiometric quantity gives the same answer (the units cancel).

    **Arguments:**

    - `spectral_values`: a spectral radiometric quantity on the grid. [W nm^-1, or any spectral
        density per nm]
    - `wavelengths_nm`: strictly increasing grid, 1-D or of the shape of `spectral_values`. [nm]
    - `vision`: `"photopic"` or `"scotopic"`.
    - `axis`: the wavelength axis of `spectral_values` (static int).

    **Returns:**

    Luminous efficacy, at most `K_m`. [lm W^-1] A spectrum whose radiant integral is 0 raises
    `equinox.EquinoxRuntimeError` (the efficacy is undefined).

    !!! note "Thesis"
        Thesis section 2.1 (the efficacy constants K of eq. (2.1)-(2.5)).

    ??? cite "References"
        `CIE2019`; `BIPM2019`.
    """
    check_choice(vision, "vision", VISIONS)
    values = as_float_array(spectral_values, "spectral_values")
    wavelengths_nm = as_float_array(wavelengths_nm, "wavelengths_nm")
    weighted, axis = _weighted(values, wavelengths_nm, axis, vision)
    luminous = integrate_spectrum(weighted, wavelengths_nm, axis=axis)
    radiant = integrate_spectrum(values, wavelengths_nm, axis=axis)
    radiant = eqx.error_if(
        radiant,
        radiant == 0,
        "`spectral_values` integrate to 0 W: the luminous efficacy is undefined.",
    )
    return EFFICACY[vision] * (luminous / radiant)


def luminous_efficiency(
    spectral_values: ArrayLike,
    wavelengths_nm: ArrayLike,
    *,
    vision: str = "photopic",
    axis: int = -1,
) -> Float[Array, "..."]:
    r"""Luminous efficiency of radiation of a spectrum: the luminous efficacy over `K_m`.

    $$\frac{\int X_{e,\lambda} V\,\mathrm d\lambda}{\int X_{e,\lambda}\,\mathrm d\lambda}$$

    This is colour-science's `luminous_efficiency`.

    **Arguments:**

    - `spectral_values`: a spectral radiometric quantity on the grid. [any spectral density per nm]
    - `wavelengths_nm`: strictly increasing grid, 1-D or of the shape of `spectral_values`. [nm]
    - `vision`: `"photopic"` or `"scotopic"`.
    - `axis`: the wavelength axis of `spectral_values` (static int).

    **Returns:**

    Luminous efficiency in [0, 1] for a non-negative spectrum. [dimensionless]

    !!! note "Thesis"
        Thesis section 2.1.

    ??? cite "References"
        `CIE2019`.
    """
    return (
        luminous_efficacy(spectral_values, wavelengths_nm, vision=vision, axis=axis)
        / EFFICACY[vision]
    )
