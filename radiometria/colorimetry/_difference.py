r"""Colour differences in CIELAB: Delta E*ab (CIE 1976), Delta E*94 (CIE 1994) and
Delta E00 (CIEDE2000).

All three take Lab (..., 3) pairs that broadcast and return (...,) [dimensionless, CIELAB
units]. Square roots are guarded so that identical colours (Delta E = 0) and neutral colours
(C* = 0) give finite gradients.
"""

import math

import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_broadcastable, check_last_axis
from .._math import safe_sqrt
from ._fastmath import atan2_degrees, sin_small
from ._models import _safe_norm2

_COS30, _SIN30 = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
_COS6, _SIN6 = math.cos(math.radians(6.0)), math.sin(math.radians(6.0))
_COS63, _SIN63 = math.cos(math.radians(63.0)), math.sin(math.radians(63.0))


def _pair(Lab_1, Lab_2):
    a = check_last_axis(as_float_array(Lab_1, "Lab_1"), "Lab_1", 3)
    b = check_last_axis(as_float_array(Lab_2, "Lab_2"), "Lab_2", 3)
    check_broadcastable(("Lab_1", a), ("Lab_2", b))
    shape = jnp.broadcast_shapes(a.shape, b.shape)
    return jnp.broadcast_to(a, shape), jnp.broadcast_to(b, shape)


def delta_E_CIE1976(
    Lab_1: Float[ArrayLike, "*#batch 3"], Lab_2: Float[ArrayLike, "*#batch 3"]
) -> Float[Array, "..."]:
    r"""CIE 1976 colour difference $\Delta E^*_{ab}$: the Euclidean distance in CIELAB.

    ??? cite "References"
        `CIE2018` section 8.2.3.

    Arguments: `Lab_1`, `Lab_2` (..., 3) [dimensionless]. Returns (...) [CIELAB units].
    """
    a, b = _pair(Lab_1, Lab_2)
    d = a - b
    return safe_sqrt(jnp.sum(d * d, axis=-1), propagate_nan=True)


def delta_E_CIE1994(
    Lab_1: Float[ArrayLike, "*#batch 3"],
    Lab_2: Float[ArrayLike, "*#batch 3"],
    textiles: bool = False,
) -> Float[Array, "..."]:
    r"""CIE 1994 colour difference $\Delta E^*_{94}$ (asymmetric: `Lab_1` is the reference).

    $S_L = 1$, $S_C = 1 + k_1 C^*_1$, $S_H = 1 + k_2 C^*_1$; graphic arts $k_L = 1$,
    $k_1 = 0.045$, $k_2 = 0.015$; `textiles=True`: $k_L = 2$, $k_1 = 0.048$, $k_2 = 0.014$
    (colour-science's convention).

    ??? cite "References"
        `CIE1995` (CIE 116-1995).

    Arguments: `Lab_1`, `Lab_2` (..., 3) [dimensionless]. Returns (...) [CIELAB units].
    """
    a, b = _pair(Lab_1, Lab_2)
    k_1, k_2, k_L = (0.048, 0.014, 2.0) if textiles else (0.045, 0.015, 1.0)
    C_1 = _safe_norm2(a[..., 1], a[..., 2])
    C_2 = _safe_norm2(b[..., 1], b[..., 2])
    s_C = 1.0 + k_1 * C_1
    s_H = 1.0 + k_2 * C_1
    d_L = a[..., 0] - b[..., 0]
    d_C = C_1 - C_2
    d_a = a[..., 1] - b[..., 1]
    d_b = a[..., 2] - b[..., 2]
    d_H2 = jnp.maximum(d_a**2 + d_b**2 - d_C**2, 0.0)
    return safe_sqrt((d_L / k_L) ** 2 + (d_C / s_C) ** 2 + d_H2 / s_H**2, propagate_nan=True)


def delta_E_CIE2000(
    Lab_1: Float[ArrayLike, "*#batch 3"],
    Lab_2: Float[ArrayLike, "*#batch 3"],
    textiles: bool = False,
) -> Float[Array, "..."]:
    r"""CIEDE2000 colour difference $\Delta E_{00}$ (Sharma, Wu & Dalal 2005 implementation).

    $\Delta E_{00} = \sqrt{(\tfrac{\Delta L'}{k_L S_L})^2 + (\tfrac{\Delta C'}{k_C S_C})^2
    + (\tfrac{\Delta H'}{k_H S_H})^2 + R_T \tfrac{\Delta C'}{k_C S_C}\tfrac{\Delta H'}{k_H S_H}}$,
    $k_L = k_C = k_H = 1$ (`textiles=True`: $k_L = 2$). Hue angles of neutral colours
    (a' = b = 0) are 0, and the mean hue follows Sharma's rule including the C'1 C'2 = 0 case.

    ??? cite "References"
        `CIE2001` (CIE 142-2001); `Sharma2005`.

    Arguments: `Lab_1`, `Lab_2` (..., 3) [dimensionless]. Returns (...) [CIELAB units].
    """
    a, b = _pair(Lab_1, Lab_2)
    L_1, a_1, b_1 = a[..., 0], a[..., 1], a[..., 2]
    L_2, a_2, b_2 = b[..., 0], b[..., 1], b[..., 2]
    k_L = 2.0 if textiles else 1.0

    C_bar = 0.5 * (_safe_norm2(a_1, b_1) + _safe_norm2(a_2, b_2))
    C_bar_7 = C_bar**7
    G = 0.5 * (1.0 - safe_sqrt(C_bar_7 / (C_bar_7 + 25.0**7), propagate_nan=True))
    a_p_1 = (1.0 + G) * a_1
    a_p_2 = (1.0 + G) * a_2
    C_p_1 = _safe_norm2(a_p_1, b_1)
    C_p_2 = _safe_norm2(a_p_2, b_2)

    # Hue angles as unit vectors e = (a', b) / C' (zero for a neutral colour, whose hue is 0 by
    # convention). This is Sharma's algorithm without its angle arithmetic, so that only one
    # arctan is evaluated (float64 sin/cos/atan2 are slow scalar calls on XLA:CPU):
    #   Delta H' = 2 sqrt(C'1 C'2) sin(Delta h'/2) = sign(Delta h') sqrt(C'1 C'2) |e2 - e1|,
    #   the mean hue h_bar' points along e1 + e2 (the bisector of the shorter arc).
    n_1 = C_p_1 == 0
    n_2 = C_p_2 == 0
    e1x = jnp.where(n_1, 0.0, a_p_1 / jnp.where(n_1, 1.0, C_p_1))
    e1y = jnp.where(n_1, 0.0, b_1 / jnp.where(n_1, 1.0, C_p_1))
    e2x = jnp.where(n_2, 0.0, a_p_2 / jnp.where(n_2, 1.0, C_p_2))
    e2y = jnp.where(n_2, 0.0, b_2 / jnp.where(n_2, 1.0, C_p_2))
    cross = e1x * e2y - e1y * e2x  # sin(h'2 - h'1)
    # Exactly opposite hues (|h'2 - h'1| = 180): Sharma takes Delta h' = h'2 - h'1, positive
    # when h'1 < 180, i.e. when e1 lies in the upper half plane.
    e1_upper = (e1y > 0) | ((e1y == 0) & (e1x > 0))
    sign = jnp.where(cross > 0, 1.0, jnp.where(cross < 0, -1.0, jnp.where(e1_upper, 1.0, -1.0)))
    d_H = sign * safe_sqrt(C_p_1 * C_p_2, propagate_nan=True) * _safe_norm2(e2x - e1x, e2y - e1y)

    d_L = L_2 - L_1
    d_C = C_p_2 - C_p_1
    L_bar = 0.5 * (L_1 + L_2)
    C_bar_p = 0.5 * (C_p_1 + C_p_2)

    # Mean hue direction (c, s) = (cos h_bar', sin h_bar').
    mx, my = e1x + e2x, e1y + e2y
    m = _safe_norm2(mx, my)
    opposite = m == 0
    # e1 + e2 = 0: both neutral (h_bar' = 0), or opposite hues (h_bar' = min(h'1, h'2) + 90).
    lx = jnp.where(e1_upper, e1x, e2x)
    ly = jnp.where(e1_upper, e1y, e2y)
    both_neutral = n_1 & n_2
    c = jnp.where(opposite, jnp.where(both_neutral, 1.0, -ly), mx / jnp.where(opposite, 1.0, m))
    s = jnp.where(opposite, jnp.where(both_neutral, 0.0, lx), my / jnp.where(opposite, 1.0, m))
    # cos(k h + phi) from (c, s) by the angle-addition formulas.
    c2, s2 = c * c - s * s, 2.0 * c * s
    c3, s3 = c * c2 - s * s2, s * c2 + c * s2
    c4, s4 = c2 * c2 - s2 * s2, 2.0 * c2 * s2
    T = (
        1.0
        - 0.17 * (c * _COS30 + s * _SIN30)  # cos(h - 30)
        + 0.24 * c2  # cos(2h)
        + 0.32 * (c3 * _COS6 - s3 * _SIN6)  # cos(3h + 6)
        - 0.20 * (c4 * _COS63 + s4 * _SIN63)  # cos(4h - 63)
    )
    h_bar = atan2_degrees(s, c)  # [0, 360)
    d_theta = 30.0 * jnp.exp(-(((h_bar - 275.0) / 25.0) ** 2))
    C_bar_p_7 = C_bar_p**7
    R_C = 2.0 * safe_sqrt(C_bar_p_7 / (C_bar_p_7 + 25.0**7), propagate_nan=True)
    L_50 = (L_bar - 50.0) ** 2
    S_L = 1.0 + 0.015 * L_50 / jnp.sqrt(20.0 + L_50)
    S_C = 1.0 + 0.045 * C_bar_p
    S_H = 1.0 + 0.015 * C_bar_p * T
    R_T = -sin_small(jnp.radians(2.0 * d_theta)) * R_C  # 2 d_theta <= 60 degrees

    tL = d_L / (k_L * S_L)
    tC = d_C / S_C
    tH = d_H / S_H
    # Materialise the three terms: XLA:CPU otherwise re-evaluates the graph above once per
    # use in the final fusion (3x the work, measured).
    tL, tC, tH, R_T = lax.optimization_barrier((tL, tC, tH, R_T))
    return safe_sqrt(tL**2 + tC**2 + tH**2 + R_T * tC * tH, propagate_nan=True)
