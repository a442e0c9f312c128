r"""Spectrum -> CIE XYZ (thesis eq. 2.12-2.19) and CIE 1931 RGB (eq. 2.6-2.10) tristimulus values.

Integration method (CIE 015:2018 section 7.1, ASTM E308 practice): the colour-matching
functions are interpolated *linearly* onto the spectrum's own wavelength grid (zero outside
their tabulated range; on an integer-nm grid this is exactly subsampling the 1 nm CIE table)
and the integral is a **rectangle (cell) sum**

$$\int f(\lambda)\,d\lambda \approx \sum_i f(\lambda_i)\,\Delta\lambda_i,\qquad
\Delta\lambda_i = \tfrac12(\lambda_{i+1}-\lambda_{i-1}),\ \Delta\lambda_0 = \lambda_1-\lambda_0,\
\Delta\lambda_{n-1} = \lambda_{n-1}-\lambda_{n-2}.$$

On a uniform grid every cell is $\Delta\lambda$, the CIE 15 summation $k\sum
\varphi(\lambda)\bar x(\lambda)\Delta\lambda$; on the 1 nm CMF grid it equals colour-science's
`sd_to_XYZ(..., method="Integration")` to rounding (tested at rtol 1e-12). It differs from the
trapezoid rule only by half the two end samples, where the CMFs are < 1.3e-4 of their peak.
"""

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_broadcastable, check_last_axis
from ..constants import K_M
from ._data import (
    CMFS_RGB,
    CMFS_XYZ,
    DEFAULT_OBSERVER,
    ILLUMINANTS_SD,
    TabulatedSpectra,
    interpolate_table,
    resolve_illuminant,
    resolve_observer,
)
from ._models import MATRIX_CIE_RGB_TO_XYZ

# The CIE 1931 RGB observer: Wright & Guild r, g, b CMFs (thesis eq. 2.7-2.9), and the row of
# thesis eq. 2.10 that gives the luminance of RGB tristimulus values, Y = R + 4.5907 G + 0.0601 B.
CIE_RGB_OBSERVER = "Wright & Guild 1931 2 Degree RGB CMFs"
_CIE_RGB_LUMINANCE_ROW = MATRIX_CIE_RGB_TO_XYZ[1]


def _grid(wavelengths_nm, name: str = "wavelengths_nm") -> Array:
    wl = as_float_array(wavelengths_nm, name)
    if wl.ndim != 1 or wl.shape[0] < 2:
        raise ValueError(
            f"`{name}` must be a 1-D grid of >= 2 wavelengths [nm], got shape {wl.shape}."
        )
    if not _is_tracer(wl) and not bool(np.all(np.diff(np.asarray(wl)) > 0)):
        raise ValueError(f"`{name}` must be strictly increasing [nm].")
    return wl


def _is_tracer(x) -> bool:
    return isinstance(x, jax.core.Tracer)


def cell_widths(wavelengths_nm: Array) -> Array:
    """Rectangle-rule cell widths of a 1-D grid (module docstring). [nm]"""
    d = jnp.diff(wavelengths_nm)
    return jnp.concatenate([d[:1], 0.5 * (d[:-1] + d[1:]), d[-1:]])


def _illuminant_on_grid(illuminant, wl: Array) -> Array:
    """An illuminant (name, TabulatedSpectra or array on `wl`) sampled on the grid `wl`."""
    if isinstance(illuminant, str):
        twl, tv = ILLUMINANTS_SD[resolve_illuminant(illuminant)]
        return interpolate_table(twl, tv, wl, extrapolation="constant")
    if isinstance(illuminant, TabulatedSpectra):
        if illuminant.values.ndim != 1:
            raise ValueError(
                f"`illuminant` must hold one spectrum, got values {illuminant.values.shape}."
            )
        return interpolate_table(
            illuminant.wavelengths_nm, illuminant.values, wl, extrapolation="constant"
        )
    s = as_float_array(illuminant, "illuminant")
    if s.ndim == 0 or s.shape[-1] != wl.shape[0]:
        raise ValueError(
            f"`illuminant` must be sampled on `wavelengths_nm` (last axis {wl.shape[0]}), "
            f"got shape {s.shape}."
        )
    return s


def tristimulus_weights(
    wavelengths_nm: Float[ArrayLike, " n"],
    illuminant=None,
    observer: str = DEFAULT_OBSERVER,
) -> Float[Array, "n 3"]:
    r"""The (n, 3) weight matrix W with `sd_to_XYZ(values, wavelengths_nm, ...) == values @ W`.

    The fast path of `sd_to_XYZ` for many spectra on one fixed grid: compute W once, then each
    batch is one matrix product (memory bound). Emissive (`illuminant=None`):
    $W_{ik} = K_m\,\bar c_k(\lambda_i)\,\Delta\lambda_i$; reflective:
    $W_{ik} = S(\lambda_i)\,\bar c_k(\lambda_i)\,\Delta\lambda_i
    / \sum_j S(\lambda_j)\bar y(\lambda_j)\Delta\lambda_j$.

    **Arguments:**

    - `wavelengths_nm`: strictly increasing grid (n,). [nm]
    - `illuminant`: `None` (emissive), an illuminant name ("D65", ...), a `TabulatedSpectra`
        (both interpolated linearly onto the grid, constant beyond their range, as colour does),
        or an array (n,) sampled on the grid. [relative spectral power]
    - `observer`: XYZ observer name (see `get_cmfs`).

    **Returns:**

    (n, 3) array [lm W^-1 for emissive, per unit spectral value for reflective], in the dtype
    of `wavelengths_nm`.

    !!! note "Thesis"
        Eq. 2.12-2.17, section 2.2.

    ??? cite "References"
        `CIE2018` section 7; `ASTM2017` (ASTM E308).
    """
    wl = _grid(wavelengths_nm)
    name = resolve_observer(observer, allow_rgb=False)
    return _weights(wl, illuminant, CMFS_XYZ[name], _luminance_xyz)


def _luminance_xyz(w: Array) -> Array:
    """The luminance channel of XYZ weights or values (..., 3): Y."""
    return w[..., 1]


def _luminance_cie_rgb(w: Array) -> Array:
    """The luminance of CIE RGB weights or values (..., 3): thesis eq. 2.10."""
    return w @ jnp.asarray(_CIE_RGB_LUMINANCE_ROW, dtype=w.dtype)


def _weights(wl: Array, illuminant, table, luminance) -> Array:
    """Weights (n, 3) of the CMF `table` on the grid `wl` (see `tristimulus_weights`);
    reflective weights are normalised so that `luminance` of a perfect reflector is 1."""
    cmf_wl, cmf_v = table
    cmfs = interpolate_table(cmf_wl, cmf_v, wl)  # (n, 3), zero outside the table
    w = cmfs * cell_widths(wl)[:, None]
    if illuminant is None:
        return K_M * w
    s = _illuminant_on_grid(illuminant, wl)
    if s.ndim != 1:
        raise ValueError(f"`illuminant` must be one spectrum (n,) here, got shape {s.shape}.")
    s = s.astype(wl.dtype)
    w = s[:, None] * w
    return w / jnp.sum(luminance(w))


def sd_to_XYZ(
    values: Float[ArrayLike, "*batch _n"],
    wavelengths_nm: Float[ArrayLike, " _n"],
    illuminant=None,
    observer: str = DEFAULT_OBSERVER,
) -> Float[Array, "*batch 3"]:
    r"""CIE XYZ tristimulus values of spectra, emissive or reflective.

    Emissive (`illuminant=None`, thesis eq. 2.12-2.14):
    $X = K_m \int L_{e,\lambda}(\lambda)\,\bar x(\lambda)\,d\lambda$ with
    $K_m = 683.002$ lm W^-1, so for a spectral radiance in W sr^-1 m^-2 nm^-1, Y is the
    luminance in cd m^-2.

    Reflective / transmissive (thesis eq. 2.15-2.19):
    $X = \int S(\lambda) R(\lambda) \bar x\,d\lambda \big/ \int S(\lambda)\bar y\,d\lambda$, so a
    perfect reflector (R = 1) has Y = 1.

    Integration: CMFs interpolated linearly onto the spectrum's grid, rectangle (cell) sum;
    see the module docstring (CIE 015 / ASTM E308 practice). NaN or inf in `values` propagate
    to the XYZ of that spectrum only.

    **Arguments:**

    - `values`: spectra (..., n) sampled on `wavelengths_nm`; leading axes are batch axes.
        [W sr^-1 m^-2 nm^-1 for emissive; dimensionless reflectance for reflective]
    - `wavelengths_nm`: strictly increasing grid (n,). [nm]
    - `illuminant`: `None` for emissive; else the illuminant: a name ("D65", ...), a
        `TabulatedSpectra`, or an array (..., n) on the grid that broadcasts with `values`.
    - `observer`: XYZ observer name (default CIE 1931 2°; see `get_cmfs`).

    **Returns:**

    XYZ (..., 3) [cd m^-2 for emissive radiance; dimensionless, Y in [0, 1] for reflectances],
    in the dtype of `values`.

    !!! note "Thesis"
        Eq. 2.12-2.19, section 2.2.

    ??? cite "References"
        `CIE2018` section 7.1; `ASTM2017`; `Wyszecki2000` section 3.3.
    """
    name = resolve_observer(observer, allow_rgb=False)
    return _sd_to_tristimulus(values, wavelengths_nm, illuminant, CMFS_XYZ[name], _luminance_xyz)


def _sd_to_tristimulus(values, wavelengths_nm, illuminant, table, luminance) -> Array:
    """Tristimulus values of spectra with the CMF `table` (`sd_to_XYZ`, `sd_to_CIE_RGB`)."""
    v = as_float_array(values, "values")
    wl = _grid(wavelengths_nm)
    check_last_axis(v, "values", wl.shape[0])
    wl = wl.astype(v.dtype)
    if (
        illuminant is None
        or isinstance(illuminant, str | TabulatedSpectra)
        or jnp.ndim(illuminant) == 1
    ):
        return v @ _weights(wl, illuminant, table, luminance)
    # A batch of illuminants (..., n): normalise each separately.
    s = _illuminant_on_grid(illuminant, wl).astype(v.dtype)
    check_broadcastable(("values", v), ("illuminant", s))
    v, s = jnp.broadcast_arrays(v, s)
    cmf_wl, cmf_v = table
    cw = interpolate_table(cmf_wl, cmf_v, wl) * cell_widths(wl)[:, None]
    return ((v * s) @ cw) / (s @ luminance(cw))[..., None]


def sd_to_CIE_RGB(
    values: Float[ArrayLike, "*batch _n"],
    wavelengths_nm: Float[ArrayLike, " _n"],
    illuminant=None,
) -> Float[Array, "*batch 3"]:
    r"""CIE 1931 RGB tristimulus values of spectra, with the r̄ḡb̄ colour-matching functions.

    A colour stimulus is matched by a mixture of the three CIE 1931 primaries, monochromatic at
    700 nm, 546.1 nm and 435.8 nm, $C = R\langle R\rangle + G\langle G\rangle +
    B\langle B\rangle$ (thesis eq. 2.6); its tristimulus values are (eq. 2.7-2.9)

    $$R = K_m\int \bar r(\lambda) L_{e,\lambda}(\lambda)\,d\lambda,\quad
      G = K_m\int \bar g(\lambda) L_{e,\lambda}(\lambda)\,d\lambda,\quad
      B = K_m\int \bar b(\lambda) L_{e,\lambda}(\lambda)\,d\lambda$$

    with the Wright & Guild 1931 2° CMFs (`get_cmfs("CIE 1931 RGB")`, 380-780 nm at 5 nm, zero
    outside). The thesis prints eq. 2.7-2.9 without a constant but reads the luminance off them
    in cd m^-2 (eq. 2.10, `CIE_RGB_luminance`), which needs the $K_m$ of eq. 2.12-2.14: with
    it, `CIE_RGB_to_XYZ(sd_to_CIE_RGB(L, wl))` is `sd_to_XYZ(L, wl)` up to the 4-5 digits to
    which the two CIE tabulations agree. Reflective (`illuminant` given): $R = \int S\,\rho\,
    \bar r\,d\lambda / \int S\,\bar y_{RGB}\,d\lambda$ with $\bar y_{RGB} = \bar r +
    4.5907\,\bar g + 0.0601\,\bar b$, so a perfect reflector has luminance factor 1.

    Integration as in `sd_to_XYZ`: CMFs interpolated linearly onto the spectrum's grid and a
    rectangle (cell) sum (module docstring).

    **Arguments:**

    - `values`: spectra (..., n) sampled on `wavelengths_nm`; leading axes are batch axes.
        [W sr^-1 m^-2 nm^-1 for emissive; dimensionless reflectance for reflective]
    - `wavelengths_nm`: strictly increasing grid (n,). [nm]
    - `illuminant`: `None` for emissive; else a name ("D65", ...), a `TabulatedSpectra`, or an
        array (..., n) on the grid that broadcasts with `values`. [relative spectral power]

    **Returns:**

    CIE RGB (..., 3) [cd m^-2 luminance units for an emissive radiance; dimensionless for
    reflectances], in the dtype of `values`. Spectral colours outside the triangle of the
    primaries have a negative component (the negative lobes of r̄ḡb̄).

    !!! note "Thesis"
        Eq. 2.6-2.9 and eq. 2.12-2.19 (normalisation), section 2.2.

    ??? cite "References"
        `CIE1932`; `Broadbent2009` (the tabulated r̄ḡb̄); `Wyszecki2000` section 3.3.3.
    """
    return _sd_to_tristimulus(
        values, wavelengths_nm, illuminant, CMFS_RGB[CIE_RGB_OBSERVER], _luminance_cie_rgb
    )


def CIE_RGB_luminance(RGB: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch"]:
    r"""Luminance of CIE 1931 RGB tristimulus values, $L_v = 1.0000 R + 4.5907 G + 0.0601 B$.

    The luminances of the three primaries in the ratio 1 : 4.5907 : 0.0601 (the Y row of thesis
    eq. 2.11, so this equals `CIE_RGB_to_XYZ(RGB)[..., 1]`).

    **Arguments:**

    - `RGB`: CIE RGB tristimulus values (..., 3), e.g. from `sd_to_CIE_RGB`. [cd m^-2
        luminance units, or dimensionless for reflectances]

    **Returns:**

    Luminance $L_v$ (...,). [cd m^-2] (the luminance factor, dimensionless, for reflective
    values)

    !!! note "Thesis"
        Eq. 2.10, section 2.2.

    ??? cite "References"
        `CIE1932`; `Wyszecki2000` section 3.3.3.
    """
    RGB = check_last_axis(as_float_array(RGB, "RGB"), "RGB", 3)
    return _luminance_cie_rgb(RGB)


def XYZ_to_xyY(XYZ: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 3"]:
    r"""CIE XYZ -> xyY: $x = X/(X+Y+Z)$, $y = Y/(X+Y+Z)$ (thesis eq. 2.20-2.21), Y kept.

    Black (X+Y+Z = 0) gives x = y = 0, as colour-science does; gradients there are 0, not NaN.

    **Arguments:** `XYZ` (..., 3) [Y in the caller's scale].
    **Returns:** xyY (..., 3) [x, y dimensionless; Y as given].

    !!! note "Thesis"
        Eq. 2.20-2.22, section 2.2.1.

    ??? cite "References"
        `CIE2018` section 7.3.
    """
    XYZ = check_last_axis(as_float_array(XYZ, "XYZ"), "XYZ", 3)
    s = jnp.sum(XYZ, axis=-1, keepdims=True)
    black = s == 0
    xy = jnp.where(black, 0.0, XYZ[..., :2] / jnp.where(black, 1.0, s))
    return jnp.concatenate([xy, XYZ[..., 1:2]], axis=-1)


def XYZ_to_xy(XYZ: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 2"]:
    """CIE XYZ -> chromaticity xy (thesis eq. 2.20-2.21); black gives (0, 0). [dimensionless]

    ??? cite "References"
        `CIE2018` section 7.3.
    """
    return XYZ_to_xyY(XYZ)[..., :2]


def xyY_to_XYZ(xyY: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 3"]:
    r"""xyY -> CIE XYZ: $X = xY/y$, $Z = (1-x-y)Y/y$ (inverse of thesis eq. 2.20-2.22).

    y = 0 gives X = Y = Z = 0 (colour-science's convention), with zero gradients.

    ??? cite "References"
        `CIE2018` section 7.3.

    Arguments: `xyY` (..., 3) [x, y dimensionless; Y in the caller's scale]. Returns XYZ (..., 3)
    [the scale of Y].
    """
    xyY = check_last_axis(as_float_array(xyY, "xyY"), "xyY", 3)
    x, y, Y = xyY[..., 0], xyY[..., 1], xyY[..., 2]
    zero = y == 0
    k = jnp.where(zero, 0.0, Y / jnp.where(zero, 1.0, y))
    return jnp.stack([x * k, jnp.where(zero, 0.0, Y), (1.0 - x - y) * k], axis=-1)


def xy_to_xyY(xy: Float[ArrayLike, "*batch 2"], Y: ArrayLike = 1.0) -> Float[Array, "*batch 3"]:
    """Chromaticity xy -> xyY with luminance factor `Y` (default 1). [dimensionless]

    Arguments: `xy` (..., 2) [dimensionless]; `Y` [the caller's scale].

    !!! note "Thesis"
        Eq. 2.20-2.22, section 2.2.1.
    """
    xy = check_last_axis(as_float_array(xy, "xy"), "xy", 2)
    Y = jnp.broadcast_to(jnp.asarray(Y, dtype=xy.dtype), xy.shape[:-1])
    return jnp.concatenate([xy, Y[..., None]], axis=-1)


def xy_to_XYZ(xy: Float[ArrayLike, "*batch 2"], Y: ArrayLike = 1.0) -> Float[Array, "*batch 3"]:
    """Chromaticity xy -> XYZ with Y = `Y` (default 1, as a white point). [dimensionless]

    ??? cite "References"
        `CIE2018` section 7.3.
    """
    return xyY_to_XYZ(xy_to_xyY(xy, Y))


def xyY_to_xy(xyY: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 2"]:
    """xyY -> xy (drops Y).

    Arguments: `xyY` (..., 3) [dimensionless]. Returns xy (..., 2) [dimensionless].

    !!! note "Thesis"
        Eq. 2.20-2.21, section 2.2.1.
    """
    return check_last_axis(as_float_array(xyY, "xyY"), "xyY", 3)[..., :2]
