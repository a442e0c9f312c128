r"""Colour differences in CIELAB: Delta E*ab (CIE 1976), Delta E*94 (CIE 1994) and
Delta E00 (CIEDE2000).

All three take Lab (..., 3) pairs that broadcast and return (...,) [dimensionless, CIELAB
units]. Square roots are guarded so that identical colours (Delta E = 0) and neutral colours
(C* = 0) give finite gradients.
"""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_broadcastable, check_last_axis
from ._models import _hue_degrees, _safe_norm2


def _pair(Lab_1, Lab_2):
    a = check_last_axis(as_float_array(Lab_1, "Lab_1"), "Lab_1", 3)
    b = check_last_axis(as_float_array(Lab_2, "Lab_2"), "Lab_2", 3)
    check_broadcastable(("Lab_1", a), ("Lab_2", b))
    shape = jnp.broadcast_shapes(a.shape, b.shape)
    return jnp.broadcast_to(a, shape), jnp.broadcast_to(b, shape)


def _safe_sqrt(x: Array) -> Array:
    """sqrt(max(x, 0)) with a zero gradient where x <= 0; NaN propagates."""
    nonpos = x <= 0
    return jnp.where(nonpos, 0.0, jnp.sqrt(jnp.where(nonpos, 1.0, x)))


def delta_E_CIE1976(
    Lab_1: Float[ArrayLike, "*#batch 3"], Lab_2: Float[ArrayLike, "*#batch 3"]
) -> Float[Array, "..."]:
    r"""CIE 1976 colour difference $\Delta E^*_{ab}$: the Euclidean distance in CIELAB.

    ??? cite "References"
        `CIE2018` section 8.2.3.
    """
    a, b = _pair(Lab_1, Lab_2)
    d = a - b
    return _safe_sqrt(jnp.sum(d * d, axis=-1))


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
    return _safe_sqrt((d_L / k_L) ** 2 + (d_C / s_C) ** 2 + d_H2 / s_H**2)


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
    """
    a, b = _pair(Lab_1, Lab_2)
    L_1, a_1, b_1 = a[..., 0], a[..., 1], a[..., 2]
    L_2, a_2, b_2 = b[..., 0], b[..., 1], b[..., 2]
    k_L = 2.0 if textiles else 1.0

    C_bar = 0.5 * (_safe_norm2(a_1, b_1) + _safe_norm2(a_2, b_2))
    C_bar_7 = C_bar**7
    G = 0.5 * (1.0 - _safe_sqrt(C_bar_7 / (C_bar_7 + 25.0**7)))
    a_p_1 = (1.0 + G) * a_1
    a_p_2 = (1.0 + G) * a_2
    C_p_1 = _safe_norm2(a_p_1, b_1)
    C_p_2 = _safe_norm2(a_p_2, b_2)
    h_p_1 = _hue_degrees(b_1, a_p_1)
    h_p_2 = _hue_degrees(b_2, a_p_2)

    d_L = L_2 - L_1
    d_C = C_p_2 - C_p_1
    C_pp = C_p_1 * C_p_2
    neutral = C_pp == 0
    dh = h_p_2 - h_p_1
    dh = jnp.where(dh > 180.0, dh - 360.0, jnp.where(dh < -180.0, dh + 360.0, dh))
    dh = jnp.where(neutral, 0.0, dh)
    d_H = 2.0 * _safe_sqrt(C_pp) * jnp.sin(jnp.radians(dh / 2.0))

    L_bar = 0.5 * (L_1 + L_2)
    C_bar_p = 0.5 * (C_p_1 + C_p_2)
    h_sum = h_p_1 + h_p_2
    far = jnp.abs(h_p_1 - h_p_2) > 180.0
    h_bar = jnp.where(
        far, jnp.where(h_sum < 360.0, (h_sum + 360.0) / 2.0, (h_sum - 360.0) / 2.0), h_sum / 2.0
    )
    h_bar = jnp.where(neutral, h_sum, h_bar)

    T = (
        1.0
        - 0.17 * jnp.cos(jnp.radians(h_bar - 30.0))
        + 0.24 * jnp.cos(jnp.radians(2.0 * h_bar))
        + 0.32 * jnp.cos(jnp.radians(3.0 * h_bar + 6.0))
        - 0.20 * jnp.cos(jnp.radians(4.0 * h_bar - 63.0))
    )
    d_theta = 30.0 * jnp.exp(-(((h_bar - 275.0) / 25.0) ** 2))
    C_bar_p_7 = C_bar_p**7
    R_C = 2.0 * _safe_sqrt(C_bar_p_7 / (C_bar_p_7 + 25.0**7))
    L_50 = (L_bar - 50.0) ** 2
    S_L = 1.0 + 0.015 * L_50 / jnp.sqrt(20.0 + L_50)
    S_C = 1.0 + 0.045 * C_bar_p
    S_H = 1.0 + 0.015 * C_bar_p * T
    R_T = -jnp.sin(jnp.radians(2.0 * d_theta)) * R_C

    tL = d_L / (k_L * S_L)
    tC = d_C / S_C
    tH = d_H / S_H
    return _safe_sqrt(tL**2 + tC**2 + tH**2 + R_T * tC * tH)
