r"""CIE daylight (D series): chromaticity from CCT and relative SPD from the S0, S1, S2 basis."""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_positive
from ._data import DAYLIGHT_BASIS, DAYLIGHT_BASIS_WAVELENGTHS, interpolate_table


def daylight_locus_xy(cct: ArrayLike) -> Float[Array, "*batch 2"]:
    r"""Chromaticity (x_D, y_D) of CIE daylight at correlated colour temperature `cct`.

    $x_D = -4.6070\,10^9/T^3 + 2.9678\,10^6/T^2 + 0.09911\,10^3/T + 0.244063$ for
    4000 K <= T <= 7000 K, $x_D = -2.0064\,10^9/T^3 + 1.9018\,10^6/T^2 + 0.24748\,10^3/T +
    0.237040$ above, and $y_D = -3.000 x_D^2 + 2.870 x_D - 0.275$. The CIE defines it on
    [4000, 25000] K; outside, the polynomials are extrapolated (as colour-science does).

    **Arguments:** `cct`: correlated colour temperature, > 0. [K]

    **Returns:** xy (..., 2). [dimensionless]

    ??? cite "References"
        `CIE2018` section 4.1.2 (eq. 4.7-4.9); `CIE2004`.
    """
    T = check_positive(as_float_array(cct, "cct"), "cct", "K")
    x_lo = -4.6070e9 / T**3 + 2.9678e6 / T**2 + 0.09911e3 / T + 0.244063
    x_hi = -2.0064e9 / T**3 + 1.9018e6 / T**2 + 0.24748e3 / T + 0.237040
    x = jnp.where(T <= 7000.0, x_lo, x_hi)
    y = -3.000 * x**2 + 2.870 * x - 0.275
    return jnp.stack([x, y], axis=-1)


def daylight_M1_M2(
    xy: Float[ArrayLike, "*batch 2"], *, rounding: bool = True
) -> Float[Array, "*batch 2"]:
    r"""The D-series weights $M_1, M_2$ of $S = S_0 + M_1 S_1 + M_2 S_2$ for daylight xy.

    $M = 0.0241 + 0.2562 x - 0.7341 y$, $M_1 = (-1.3515 - 1.7703 x + 5.9114 y)/M$,
    $M_2 = (0.0300 - 31.4424 x + 30.0717 y)/M$; `rounding=True` rounds them to 3 decimals
    as CIE 15:2004 recommends (and colour-science does by default); their gradient is then 0.

    ??? cite "References"
        `CIE2018` section 4.1.2 (eq. 4.10-4.11).

    Arguments: `xy` (..., 2) [dimensionless]. Returns (..., 2) [dimensionless].
    """
    xy = as_float_array(xy, "xy")
    x, y = xy[..., 0], xy[..., 1]
    M = 0.0241 + 0.2562 * x - 0.7341 * y
    M1 = (-1.3515 - 1.7703 * x + 5.9114 * y) / M
    M2 = (0.0300 - 31.4424 * x + 30.0717 * y) / M
    if rounding:
        M1, M2 = jnp.round(M1, 3), jnp.round(M2, 3)
    return jnp.stack([M1, M2], axis=-1)


def daylight_spd(
    cct: ArrayLike, wavelengths_nm: Float[ArrayLike, " n"], *, rounding: bool = True
) -> Float[Array, "*batch n"]:
    r"""Relative SPD of CIE daylight (D series) at correlated colour temperature `cct`.

    CIE 15 method: $x_D$ from the CCT polynomial, $y_D$ from the daylight locus,
    $M_1, M_2$ from $(x_D, y_D)$ (rounded to 3 decimals unless `rounding=False`),
    $S(\lambda) = S_0 + M_1 S_1 + M_2 S_2$ with the basis interpolated *linearly* from its
    5 nm table onto `wavelengths_nm` (CIE 15 practice; zero outside 300-830 nm). On the 5 nm
    table grid it equals `colour.sd_CIE_illuminant_D_series(CCT_to_xy_CIE_D(cct))`.

    The nominal CCTs of D50/D55/D65/D75 are 5000, 5500, 6500, 7500 K x 1.4388/1.4380 (the
    1968 change of c2), e.g. D65 = 6504 K.

    **Arguments:**

    - `cct`: correlated colour temperature (...,), > 0; the CIE range is 4000-25000 K. [K]
    - `wavelengths_nm`: (n,) grid. [nm]
    - `rounding`: round M1, M2 to 3 decimals (CIE 15). Use `False` to differentiate in `cct`.

    **Returns:** (..., n) relative spectral power, 100 near 560 nm. [relative]

    ??? cite "References"
        `CIE2018` section 4.1.2; `Judd1964`.
    """
    T = as_float_array(cct, "cct")
    wl = as_float_array(wavelengths_nm, "wavelengths_nm")
    if wl.ndim != 1:
        raise ValueError(f"`wavelengths_nm` must be 1-D (n,), got shape {wl.shape}. [nm]")
    M = daylight_M1_M2(daylight_locus_xy(T), rounding=rounding).astype(wl.dtype)
    S = interpolate_table(DAYLIGHT_BASIS_WAVELENGTHS, DAYLIGHT_BASIS, wl)  # (n, 3)
    S = S.reshape((1,) * (M.ndim - 1) + S.shape)  # explicit broadcasting over the batch axes
    return S[..., 0] + M[..., 0:1] * S[..., 1] + M[..., 1:2] * S[..., 2]
