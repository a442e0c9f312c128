r"""Colour models derived from CIE XYZ: CIELAB, CIELCh, CIELUV, CIELCh(uv), CIE 1960 UCS uv,
CIE 1976 u'v', and the CIE 1931 RGB system (thesis eq. 2.11)."""

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_last_axis
from .._math import safe_sqrt
from ._fastmath import cbrt_positive

# CIE 1976 constants, exact rationals (CIE 015:2018 eq. 8.3-8.5): epsilon = (6/29)^3.
_DELTA = 6.0 / 29.0
_EPSILON = _DELTA**3  # 216/24389

# Thesis eq. 2.11 (Wright & Guild / CIE 1931): XYZ = M_RGB RGB, for CIE RGB tristimulus values
# in the luminance-unit normalisation Y = R + 4.5907 G + 0.0601 B (thesis eq. 2.10). The thesis
# prints the product with the sides swapped ([R G B] = M [X Y Z]); the rows are those of X, Y, Z.
MATRIX_CIE_RGB_TO_XYZ = np.array(
    [
        [2.768892, 1.751748, 1.130160],
        [1.000000, 4.590700, 0.060100],
        [0.000000, 0.056508, 5.594292],
    ]
)
MATRIX_XYZ_TO_CIE_RGB = np.linalg.inv(MATRIX_CIE_RGB_TO_XYZ)

# CIE D65 white, Y = 1, from its CIE 1931 2 deg chromaticity (0.3127, 0.3290) (thesis table 2.1).
_D65_XYZ = (0.3127 / 0.3290, 1.0, (1.0 - 0.3127 - 0.3290) / 0.3290)


def _vec3(x, name):
    return check_last_axis(as_float_array(x, name), name, 3)


def _matmul(M: np.ndarray, v: Array) -> Array:
    """`M @ v` over the last axis, with the constant matrix in the dtype of `v`."""
    return v @ jnp.asarray(M.T, dtype=v.dtype)


def _white(white_XYZ, dtype):
    if white_XYZ is None:
        return jnp.asarray(_D65_XYZ, dtype=dtype)
    return _vec3(white_XYZ, "white_XYZ").astype(dtype)


def _f_lab(t: Array) -> Array:
    """CIE 1976 lightness function f(t), with the linear segment below (6/29)^3."""
    # cbrt_positive: a vectorised cube root (jnp.cbrt is a slow scalar call on XLA:CPU).
    big = t > _EPSILON
    root = cbrt_positive(jnp.where(big, t, 1.0))
    return jnp.where(big, root, t / (3.0 * _DELTA**2) + 4.0 / 29.0)


def _f_lab_inverse(f: Array) -> Array:
    return jnp.where(f > _DELTA, f**3, 3.0 * _DELTA**2 * (f - 4.0 / 29.0))


def XYZ_to_Lab(XYZ: Float[ArrayLike, "*batch 3"], white_XYZ=None) -> Float[Array, "*batch 3"]:
    r"""CIE XYZ -> CIELAB (CIE 1976 L*a*b*).

    $L^* = 116 f(Y/Y_n) - 16$, $a^* = 500(f(X/X_n) - f(Y/Y_n))$, $b^* = 200(f(Y/Y_n) - f(Z/Z_n))$
    with $f(t) = t^{1/3}$ for $t > (6/29)^3$, else $t/(3 (6/29)^2) + 4/29$.

    **Arguments:**

    - `XYZ`: (..., 3), same scale as the white. [dimensionless, Y = 1 for the white]
    - `white_XYZ`: reference white (..., 3); default CIE D65 with Y = 1.

    **Returns:**

    Lab (..., 3): L* in [0, 100] for Y in [0, Y_n], a*, b*. [dimensionless]

    ??? cite "References"
        `CIE2018` section 8.2.1.
    """
    XYZ = _vec3(XYZ, "XYZ")
    XYZ, w = jnp.broadcast_arrays(XYZ, _white(white_XYZ, XYZ.dtype))
    f = _f_lab(XYZ / w)
    fx, fy, fz = f[..., 0], f[..., 1], f[..., 2]
    return jnp.stack([116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)], axis=-1)


def Lab_to_XYZ(Lab: Float[ArrayLike, "*batch 3"], white_XYZ=None) -> Float[Array, "*batch 3"]:
    """CIELAB -> CIE XYZ, the exact inverse of `XYZ_to_Lab` (default white D65, Y = 1).

    ??? cite "References"
        `CIE2018` section 8.2.1.

    Arguments: `Lab` (..., 3) [dimensionless]; `white_XYZ` (..., 3) [dimensionless, Y = 1].
    Returns XYZ (..., 3) in the scale of the white [dimensionless].
    """
    Lab = _vec3(Lab, "Lab")
    Lab, w = jnp.broadcast_arrays(Lab, _white(white_XYZ, Lab.dtype))
    fy = (Lab[..., 0] + 16.0) / 116.0
    fx = fy + Lab[..., 1] / 500.0
    fz = fy - Lab[..., 2] / 200.0
    return _f_lab_inverse(jnp.stack([fx, fy, fz], axis=-1)) * w


def _safe_norm2(a: Array, b: Array) -> Array:
    """sqrt(a^2 + b^2) with a zero (not NaN) gradient at the origin; NaN propagates."""
    return safe_sqrt(a * a + b * b, propagate_nan=True)


def _hue_degrees(b: Array, a: Array) -> Array:
    """atan2(b, a) in degrees in [0, 360); 0 (and zero gradient) at a = b = 0."""
    zero = (a == 0) & (b == 0)
    h = jnp.degrees(jnp.arctan2(jnp.where(zero, 0.0, b), jnp.where(zero, 1.0, a)))
    return jnp.where(zero, 0.0, jnp.mod(h, 360.0))


def Lab_to_LCh(Lab: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 3"]:
    """CIELAB -> CIELCh: L*, chroma C*_ab = sqrt(a*^2 + b*^2), hue h_ab in degrees [0, 360).

    ??? cite "References"
        `CIE2018` section 8.2.2.
    """
    Lab = _vec3(Lab, "Lab")
    L, a, b = Lab[..., 0], Lab[..., 1], Lab[..., 2]
    return jnp.stack([L, _safe_norm2(a, b), _hue_degrees(b, a)], axis=-1)


def LCh_to_Lab(LCh: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 3"]:
    """CIELCh -> CIELAB: a* = C cos h, b* = C sin h (h in degrees).

    Arguments and result: L* [dimensionless], C* [dimensionless], h [degrees].

    ??? cite "References"
        `CIE2018` section 8.2.2.
    """
    LCh = _vec3(LCh, "LCh")
    L, C, h = LCh[..., 0], LCh[..., 1], jnp.radians(LCh[..., 2])
    return jnp.stack([L, C * jnp.cos(h), C * jnp.sin(h)], axis=-1)


def _ratio(num: Array, den: Array) -> Array:
    zero = den == 0
    return jnp.where(zero, 0.0, num / jnp.where(zero, 1.0, den))


def XYZ_to_UCS_uv(XYZ: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 2"]:
    """CIE XYZ -> CIE 1960 UCS chromaticity: u = 4X/(X+15Y+3Z), v = 6Y/(X+15Y+3Z).

    Black gives (0, 0). [dimensionless]

    ??? cite "References"
        `Wyszecki2000` section 3.3.9; `CIE2018` section 9.1 (CCT is defined in this space).
    """
    XYZ = _vec3(XYZ, "XYZ")
    X, Y, Z = XYZ[..., 0], XYZ[..., 1], XYZ[..., 2]
    d = X + 15.0 * Y + 3.0 * Z
    return jnp.stack([_ratio(4.0 * X, d), _ratio(6.0 * Y, d)], axis=-1)


def xy_to_UCS_uv(xy: Float[ArrayLike, "*batch 2"]) -> Float[Array, "*batch 2"]:
    """xy -> CIE 1960 uv: u = 4x/(-2x+12y+3), v = 6y/(-2x+12y+3). [dimensionless]

    ??? cite "References"
        `Wyszecki2000` section 3.3.9.
    """
    xy = check_last_axis(as_float_array(xy, "xy"), "xy", 2)
    x, y = xy[..., 0], xy[..., 1]
    d = -2.0 * x + 12.0 * y + 3.0
    return jnp.stack([4.0 * x / d, 6.0 * y / d], axis=-1)


def UCS_uv_to_xy(uv: Float[ArrayLike, "*batch 2"]) -> Float[Array, "*batch 2"]:
    """CIE 1960 uv -> xy: x = 3u/(2u-8v+4), y = 2v/(2u-8v+4). [dimensionless]

    ??? cite "References"
        `Wyszecki2000` section 3.3.9.
    """
    uv = check_last_axis(as_float_array(uv, "uv"), "uv", 2)
    u, v = uv[..., 0], uv[..., 1]
    d = 2.0 * u - 8.0 * v + 4.0
    return jnp.stack([3.0 * u / d, 2.0 * v / d], axis=-1)


def XYZ_to_Luv_uv(XYZ: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 2"]:
    """CIE XYZ -> CIE 1976 UCS u'v': u' = 4X/(X+15Y+3Z), v' = 9Y/(X+15Y+3Z); black -> (0, 0).

    ??? cite "References"
        `CIE2018` section 8.1.

    Arguments: `XYZ` (..., 3) [dimensionless]. Returns u'v' (..., 2) [dimensionless].
    """
    XYZ = _vec3(XYZ, "XYZ")
    X, Y, Z = XYZ[..., 0], XYZ[..., 1], XYZ[..., 2]
    d = X + 15.0 * Y + 3.0 * Z
    return jnp.stack([_ratio(4.0 * X, d), _ratio(9.0 * Y, d)], axis=-1)


def xy_to_Luv_uv(xy: Float[ArrayLike, "*batch 2"]) -> Float[Array, "*batch 2"]:
    """xy -> CIE 1976 u'v': u' = 4x/(-2x+12y+3), v' = 9y/(-2x+12y+3). [dimensionless]

    ??? cite "References"
        `CIE2018` section 8.1.
    """
    xy = check_last_axis(as_float_array(xy, "xy"), "xy", 2)
    x, y = xy[..., 0], xy[..., 1]
    d = -2.0 * x + 12.0 * y + 3.0
    return jnp.stack([4.0 * x / d, 9.0 * y / d], axis=-1)


def Luv_uv_to_xy(uv: Float[ArrayLike, "*batch 2"]) -> Float[Array, "*batch 2"]:
    """CIE 1976 u'v' -> xy: x = 9u'/(6u'-16v'+12), y = 4v'/(6u'-16v'+12). [dimensionless]

    ??? cite "References"
        `CIE2018` section 8.1.
    """
    uv = check_last_axis(as_float_array(uv, "uv"), "uv", 2)
    u, v = uv[..., 0], uv[..., 1]
    d = 6.0 * u - 16.0 * v + 12.0
    return jnp.stack([9.0 * u / d, 4.0 * v / d], axis=-1)


def _luv_uv_prime(XYZ: Array) -> tuple[Array, Array]:
    """u' = 4X/(X+15Y+3Z), v' = 9Y/(X+15Y+3Z); black gives (0, 0) with zero gradients."""
    X, Y, Z = XYZ[..., 0], XYZ[..., 1], XYZ[..., 2]
    d = X + 15.0 * Y + 3.0 * Z
    return _ratio(4.0 * X, d), _ratio(9.0 * Y, d)


def XYZ_to_Luv(XYZ: Float[ArrayLike, "*batch 3"], white_XYZ=None) -> Float[Array, "*batch 3"]:
    r"""CIE XYZ -> CIELUV (CIE 1976 L*u*v*).

    $L^* = 116 f(Y/Y_n) - 16$ (as in CIELAB), $u^* = 13 L^*(u' - u'_n)$,
    $v^* = 13 L^*(v' - v'_n)$, with the CIE 1976 UCS chromaticities
    $u' = 4X/(X + 15Y + 3Z)$, $v' = 9Y/(X + 15Y + 3Z)$ of the colour and of the white.
    Black gives (0, 0, 0).

    **Arguments:**

    - `XYZ`: (..., 3), same scale as the white. [dimensionless, Y = 1 for the white]
    - `white_XYZ`: reference white (..., 3); default CIE D65 with Y = 1. [dimensionless]

    **Returns:**

    Luv (..., 3): L* in [0, 100] for Y in [0, Y_n], u*, v*. [dimensionless]

    !!! note "Thesis"
        Section 2.2.1 (uniform colour spaces derived from XYZ and xy).

    ??? cite "References"
        `CIE2018` section 8.2.2; `Wyszecki2000` section 3.3.9.
    """
    XYZ = _vec3(XYZ, "XYZ")
    XYZ, w = jnp.broadcast_arrays(XYZ, _white(white_XYZ, XYZ.dtype))
    L = 116.0 * _f_lab(XYZ[..., 1] / w[..., 1]) - 16.0
    u_p, v_p = _luv_uv_prime(XYZ)
    u_n, v_n = _luv_uv_prime(w)
    return jnp.stack([L, 13.0 * L * (u_p - u_n), 13.0 * L * (v_p - v_n)], axis=-1)


def Luv_to_XYZ(Luv: Float[ArrayLike, "*batch 3"], white_XYZ=None) -> Float[Array, "*batch 3"]:
    r"""CIELUV -> CIE XYZ, the inverse of `XYZ_to_Luv` (default white D65, Y = 1).

    $Y = Y_n f^{-1}((L^* + 16)/116)$, $u' = u^*/(13 L^*) + u'_n$, $v' = v^*/(13 L^*) + v'_n$,
    $X = Y\,9u'/(4v')$, $Z = Y\,(12 - 3u' - 20v')/(4v')$. L* = 0 gives black; so does
    $v' = 0$ (no real colour has it), with zero gradients in both cases.

    **Arguments:**

    - `Luv`: (..., 3). [dimensionless]
    - `white_XYZ`: reference white (..., 3); default CIE D65 with Y = 1. [dimensionless]

    **Returns:**

    XYZ (..., 3) in the scale of the white. [dimensionless]

    !!! note "Thesis"
        Section 2.2.1.

    ??? cite "References"
        `CIE2018` section 8.2.2; `Wyszecki2000` section 3.3.9.
    """
    Luv = _vec3(Luv, "Luv")
    Luv, w = jnp.broadcast_arrays(Luv, _white(white_XYZ, Luv.dtype))
    L, u, v = Luv[..., 0], Luv[..., 1], Luv[..., 2]
    Y = _f_lab_inverse((L + 16.0) / 116.0) * w[..., 1]
    u_n, v_n = _luv_uv_prime(w)
    black = L == 0
    thirteen_L = 13.0 * jnp.where(black, 1.0, L)
    u_p = u / thirteen_L + u_n
    v_p = v / thirteen_L + v_n
    four_v = 4.0 * v_p
    k = jnp.where(black, 0.0, _ratio(Y, four_v))  # Y / (4 v'), 0 for black or v' = 0
    return jnp.stack(
        [9.0 * u_p * k, jnp.where(black, 0.0, Y), (12.0 - 3.0 * u_p - 20.0 * v_p) * k], axis=-1
    )


def Luv_to_LCHuv(Luv: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 3"]:
    r"""CIELUV -> CIELCh(uv): L*, chroma $C^*_{uv} = \sqrt{u^{*2} + v^{*2}}$, hue $h_{uv}$.

    **Arguments:**

    - `Luv`: (..., 3). [dimensionless]

    **Returns:**

    LCHuv (..., 3): L* and C*_uv [dimensionless], h_uv in [0, 360) [degrees]; the hue of a
    neutral (u* = v* = 0) is 0, with zero gradients.

    !!! note "Thesis"
        Section 2.2.1.

    ??? cite "References"
        `CIE2018` section 8.2.2.
    """
    Luv = _vec3(Luv, "Luv")
    L, u, v = Luv[..., 0], Luv[..., 1], Luv[..., 2]
    return jnp.stack([L, _safe_norm2(u, v), _hue_degrees(v, u)], axis=-1)


def LCHuv_to_Luv(LCHuv: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 3"]:
    r"""CIELCh(uv) -> CIELUV: $u^* = C^*_{uv}\cos h_{uv}$, $v^* = C^*_{uv}\sin h_{uv}$.

    **Arguments:**

    - `LCHuv`: (..., 3): L*, C*_uv [dimensionless] and h_uv [degrees].

    **Returns:**

    Luv (..., 3). [dimensionless] The inverse of `Luv_to_LCHuv`.

    !!! note "Thesis"
        Section 2.2.1.

    ??? cite "References"
        `CIE2018` section 8.2.2.
    """
    LCHuv = _vec3(LCHuv, "LCHuv")
    L, C, h = LCHuv[..., 0], LCHuv[..., 1], jnp.radians(LCHuv[..., 2])
    return jnp.stack([L, C * jnp.cos(h), C * jnp.sin(h)], axis=-1)


def Luv_to_uv(Luv: Float[ArrayLike, "*batch 3"], white_XYZ=None) -> Float[Array, "*batch 2"]:
    r"""CIELUV -> CIE 1976 UCS chromaticity u'v' of the colour (black gives (0, 0)).

    **Arguments:**

    - `Luv`: (..., 3). [dimensionless]
    - `white_XYZ`: reference white (..., 3); default CIE D65 with Y = 1. [dimensionless]

    **Returns:**

    u'v' (..., 2). [dimensionless] `uv_to_Luv` goes back, given L*.

    !!! note "Thesis"
        Section 2.2.1.

    ??? cite "References"
        `CIE2018` sections 8.1 and 8.2.2.
    """
    return XYZ_to_Luv_uv(Luv_to_XYZ(Luv, white_XYZ))


def uv_to_Luv(
    uv: Float[ArrayLike, "*batch 2"], white_XYZ=None, L: ArrayLike = 100.0
) -> Float[Array, "*batch 3"]:
    r"""CIE 1976 UCS chromaticity u'v' and lightness L* -> CIELUV.

    $u^* = 13 L^*(u' - u'_n)$, $v^* = 13 L^*(v' - v'_n)$.

    **Arguments:**

    - `uv`: u'v' chromaticity (..., 2). [dimensionless]
    - `white_XYZ`: reference white (..., 3); default CIE D65 with Y = 1. [dimensionless]
    - `L`: lightness L*, broadcasting with the batch shape; default 100. [dimensionless]

    **Returns:**

    Luv (..., 3). [dimensionless] The inverse of `Luv_to_uv` for L* > 0.

    !!! note "Thesis"
        Section 2.2.1.

    ??? cite "References"
        `CIE2018` sections 8.1 and 8.2.2.
    """
    uv = check_last_axis(as_float_array(uv, "uv"), "uv", 2)
    w = _white(white_XYZ, uv.dtype)
    u_n, v_n = _luv_uv_prime(w)
    L = jnp.asarray(as_float_array(L, "L"), dtype=uv.dtype)
    L, u_p, v_p, u_n, v_n = jnp.broadcast_arrays(L, uv[..., 0], uv[..., 1], u_n, v_n)
    return jnp.stack([L, 13.0 * L * (u_p - u_n), 13.0 * L * (v_p - v_n)], axis=-1)


def CIE_RGB_to_XYZ(RGB: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 3"]:
    r"""CIE 1931 RGB tristimulus values -> CIE 1931 XYZ (thesis eq. 2.11).

    The RGB values are in the luminance-unit normalisation of the thesis,
    $Y = L_v = 1.0000 R + 4.5907 G + 0.0601 B$ (eq. 2.10); the same matrix maps the
    r̄ḡb̄ CMFs to x̄ȳz̄ up to that normalisation.

    ??? cite "References"
        `CIE1932`; `Wyszecki2000` section 3.3.3; `Broadbent2009`.

    Arguments: `RGB` (..., 3) [luminance units, cd m^-2 for a radiance]. Returns XYZ (..., 3)
    [cd m^-2 for a radiance].
    """
    return _matmul(MATRIX_CIE_RGB_TO_XYZ, _vec3(RGB, "RGB"))


def XYZ_to_CIE_RGB(XYZ: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 3"]:
    """CIE 1931 XYZ -> CIE 1931 RGB, the inverse of `CIE_RGB_to_XYZ` (thesis eq. 2.11).

    Arguments: `XYZ` (..., 3) [cd m^-2 for a radiance]. Returns CIE RGB (..., 3) [same unit].

    !!! note "Thesis"
        Eq. 2.11, section 2.2.
    """
    return _matmul(MATRIX_XYZ_TO_CIE_RGB, _vec3(XYZ, "XYZ"))
