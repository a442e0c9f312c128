r"""Planckian locus and correlated colour temperature (thesis section 2.2.1, def. 2.2.2).

The CCT of a stimulus is the temperature of the Planckian radiator whose chromaticity is
nearest in the CIE 1960 UCS (u, v) diagram; $D_{uv}$ is that distance, positive above the
locus. The Planckian chromaticities come from `radiometria.radiometry.planck` (thesis
eq. 1.24) integrated against the CMFs on their 1 nm grid with `sd_to_XYZ` (rectangle rule).

Second radiation constant. `planck` uses the exact SI value $c_2 = hc/k_B$
(1.438776877e-2 m K). CIE 15 and colour-science use $c_2 = 1.4388\times10^{-2}$ m K for
colorimetry (the CCTs of thesis table 2.1, e.g. D65 = 6504 K, follow it). Every function here
takes `c2=` (None: exact SI). Because the chromaticity of Planck's law depends on T only through
$c_2/(\lambda T)$, a different $c_2$ is the same locus at the rescaled temperature
$T\,c_{2,\mathrm{SI}}/c_2$; the two conventions differ by 1.55e-5 relative (0.1 K at 6504 K).
"""

import concurrent.futures
import functools

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_choice, check_last_axis, check_positive
from ..constants import C2
from ..radiometry import planck
from ._data import CMFS_XYZ, DEFAULT_OBSERVER, resolve_observer
from ._daylight import daylight_locus_xy
from ._models import UCS_uv_to_xy, XYZ_to_UCS_uv, xy_to_UCS_uv
from ._tristimulus import tristimulus_weights

# Ohno (2013) table range and spacing, as in colour-science 0.4.7 (`planckian_table`).
CCT_MINIMAL_OHNO2013 = 1000.0  # K
CCT_MAXIMAL_OHNO2013 = 100000.0  # K
CCT_SPACING_OHNO2013 = 1.001  # ratio between consecutive table temperatures
_COARSE_STRIDE = 32  # rows of the fine table per row of the coarse search table

# Robertson (1968) isotemperature lines: (reciprocal megakelvin, u, v, slope t), as tabulated
# in Wyszecki & Stiles (2000) table 1(3.11) and colour-science.
ROBERTSON1968 = np.array(
    [
        (0, 0.18006, 0.26352, -0.24341),
        (10, 0.18066, 0.26589, -0.25479),
        (20, 0.18133, 0.26846, -0.26876),
        (30, 0.18208, 0.27119, -0.28539),
        (40, 0.18293, 0.27407, -0.30470),
        (50, 0.18388, 0.27709, -0.32675),
        (60, 0.18494, 0.28021, -0.35156),
        (70, 0.18611, 0.28342, -0.37915),
        (80, 0.18740, 0.28668, -0.40955),
        (90, 0.18880, 0.28997, -0.44278),
        (100, 0.19032, 0.29326, -0.47888),
        (125, 0.19462, 0.30141, -0.58204),
        (150, 0.19962, 0.30921, -0.70471),
        (175, 0.20525, 0.31647, -0.84901),
        (200, 0.21142, 0.32312, -1.0182),
        (225, 0.21807, 0.32909, -1.2168),
        (250, 0.22511, 0.33439, -1.4512),
        (275, 0.23247, 0.33904, -1.7298),
        (300, 0.24010, 0.34308, -2.0637),
        (325, 0.24792, 0.34655, -2.4681),
        (350, 0.25591, 0.34951, -2.9641),
        (375, 0.26400, 0.35200, -3.5814),
        (400, 0.27218, 0.35407, -4.3633),
        (425, 0.28039, 0.35577, -5.3762),
        (450, 0.28863, 0.35714, -6.7262),
        (475, 0.29685, 0.35823, -8.5955),
        (500, 0.30505, 0.35907, -11.324),
        (525, 0.31320, 0.35968, -15.628),
        (550, 0.32129, 0.36011, -23.325),
        (575, 0.32931, 0.36038, -40.770),
        (600, 0.33724, 0.36051, -116.45),
    ]
)

_METHODS = ["Ohno 2013", "Robertson 1968", "McCamy 1992"]


def _c2_scale(c2) -> float:
    """Factor s with locus_c2(T) = locus_SI(s T): s = c2_SI / c2."""
    if c2 is None:
        return 1.0
    c2 = float(c2)
    if not c2 > 0:
        raise ValueError(f"`c2` must be > 0 [m K], got {c2}.")
    return C2 / c2


def planckian_locus_uv(
    temperature: ArrayLike, observer: str = DEFAULT_OBSERVER, *, c2: float | None = None
) -> Float[Array, "*batch 2"]:
    r"""CIE 1960 (u, v) of a Planckian radiator at `temperature` (exact, differentiable).

    Integrates `radiometria.radiometry.planck` against the observer's CMFs on their 1 nm grid
    (emissive `sd_to_XYZ`), then $u = 4X/(X+15Y+3Z)$, $v = 6Y/(X+15Y+3Z)$.

    **Arguments:**

    - `temperature`: (...,), > 0. [K]
    - `observer`: XYZ observer name (default CIE 1931 2°).
    - `c2`: second radiation constant [m K]; `None` = exact SI (see module docstring).

    **Returns:** uv (..., 2). [dimensionless]

    !!! note "Thesis"
        Section 2.2.1 (Planckian locus), eq. 1.24, 2.12-2.14.

    ??? cite "References"
        `CIE2018` section 9.1; `Wyszecki2000` section 3.11.
    """
    T = as_float_array(temperature, "temperature")
    T = check_positive(T, "temperature", "K") * _c2_scale(c2)
    name = resolve_observer(observer, allow_rgb=False)
    wl = jnp.asarray(CMFS_XYZ[name][0], dtype=T.dtype)
    W = tristimulus_weights(wl, None, name)  # (n, 3)
    L = planck(wl.reshape((1,) * T.ndim + wl.shape), T[..., None])  # (..., n)
    return XYZ_to_UCS_uv(L @ W)


def _ohno_temperatures(start: float, end: float, spacing: float) -> np.ndarray:
    """Table temperatures of colour-science's `planckian_table` (Ohno 2013): geometric steps
    of `spacing`, slightly smaller towards `end`, plus the end points and their +/- 1 K."""
    Ti = [start, start + 1.0]
    t = start + 1.0
    s = spacing
    while (t := t * s) < end:
        Ti.append(t)
        D = min(
            max((t - CCT_MINIMAL_OHNO2013) / (CCT_MAXIMAL_OHNO2013 - CCT_MINIMAL_OHNO2013), 0.0),
            1.0,
        )
        s = spacing * (1.0 - D) + (1.0 + (spacing - 1.0) / 10.0) * D
    return np.asarray(Ti + [end - 1.0, end])


@functools.lru_cache(maxsize=8)
def planckian_table(observer: str = DEFAULT_OBSERVER, c2: float | None = None) -> np.ndarray:
    """The Ohno (2013) Planckian table (m, 3) of rows (T [K], u, v), float64 NumPy.

    Built once per (observer, c2) on first use (not at import, so importing starts no device),
    with `planckian_locus_uv` evaluated eagerly in float64 whatever the JAX precision setting.
    The evaluation runs in a worker thread: JAX's tracing state and the x64 switch are
    thread-local, so the table is concrete even when first needed inside `jax.jit`.
    """
    T = _ohno_temperatures(CCT_MINIMAL_OHNO2013, CCT_MAXIMAL_OHNO2013, CCT_SPACING_OHNO2013)

    def build() -> np.ndarray:
        with jax.enable_x64(True):
            uv = planckian_locus_uv(jnp.asarray(T, dtype=jnp.float64), observer, c2=c2)
            return np.asarray(uv, dtype=np.float64)

    with concurrent.futures.ThreadPoolExecutor(max_workers=1) as pool:
        uv = pool.submit(build).result()
    table = np.concatenate([T[:, None], uv], axis=1)
    table.setflags(write=False)
    return table


def _uv_to_CCT_ohno2013(uv: Array, observer: str, c2) -> Array:
    table_np = planckian_table(resolve_observer(observer, allow_rgb=False), c2)
    return _ohno2013_core(uv, jnp.asarray(table_np, dtype=uv.dtype))


@jax.jit
def _ohno2013_core(uv: Array, table: Array) -> Array:
    # One compiled kernel: eager dispatch of its ~60 small ops would compile each separately.
    m = table.shape[0]
    K = _COARSE_STRIDE
    coarse = table[::K]  # (mc, 3)
    batch = uv.shape[:-1]
    q = uv.reshape(-1, 1, 2)  # (N, 1, 2)

    # Level 1: nearest row of the coarse table (every K-th row).
    dc = jnp.sum((coarse[None, :, 1:] - q) ** 2, axis=-1)  # (N, mc)
    ic = jnp.argmin(dc, axis=-1) * K  # fine index of the nearest coarse row
    # Level 2: nearest fine row within +/- (K + 1) rows; the distance along the locus is
    # unimodal there, so this is the global nearest row of the fine table.
    offsets = jnp.arange(-K - 1, K + 2)
    idx = jnp.clip(ic[:, None] + offsets[None, :], 0, m - 1)  # (N, 2K+3)
    rows = table[idx]  # (N, 2K+3, 3)
    df = jnp.sum((rows[..., 1:] - q) ** 2, axis=-1)
    i = jnp.take_along_axis(idx, jnp.argmin(df, axis=-1)[:, None], axis=-1)[:, 0]
    i = jnp.clip(i, 1, m - 2)  # keep both neighbours inside the table (colour does the same)

    u, v = q[:, 0, 0], q[:, 0, 1]

    def row(j):
        r = table[j]
        d = jnp.sqrt((r[:, 1] - u) ** 2 + (r[:, 2] - v) ** 2)
        return r[:, 0], r[:, 1], r[:, 2], d

    Tp, up, vp, dp = row(i - 1)
    Ti, _, _, di = row(i)
    Tn, un, vn, dn = row(i + 1)

    # Triangular solution (Ohno 2013, eq. 6-10).
    ll = jnp.sqrt((un - up) ** 2 + (vn - vp) ** 2)
    x = (dp**2 - dn**2 + ll**2) / (2.0 * ll)
    T_t = Tp + (Tn - Tp) * (x / ll)
    v_tx = vp + (vn - vp) * (x / ll)
    sign = jnp.sign(v - v_tx)
    Duv_t = jnp.sqrt(jnp.maximum(dp**2 - x**2, 0.0)) * sign

    # Parabolic solution (Ohno 2013, eq. 11-16), in t = T - T_i for conditioning (the same
    # parabola as colour-science's form in T).
    tp, tn = Tp - Ti, Tn - Ti
    X = tn * (tp - tn) * (-tp)
    a = (tp * (dn - di) + tn * (di - dp)) / X
    b = -(tp**2 * (dn - di) + tn**2 * (di - dp)) / X
    c = di
    t_p = -b / (2.0 * a)
    T_p = Ti + t_p
    Duv_p = (a * t_p**2 + b * t_p + c) * sign

    parabolic = jnp.abs(Duv_t) >= 0.002
    out = jnp.stack([jnp.where(parabolic, T_p, T_t), jnp.where(parabolic, Duv_p, Duv_t)], axis=-1)
    return out.reshape(batch + (2,))


@jax.jit
def _uv_to_CCT_robertson1968(uv: Array) -> Array:
    dtype = uv.dtype
    r_itl, u_itl, v_itl, t_itl = (jnp.asarray(c, dtype=dtype) for c in ROBERTSON1968.T)
    length = jnp.sqrt(1.0 + t_itl**2)
    du_itl, dv_itl = 1.0 / length, t_itl / length
    batch = uv.shape[:-1]
    u = uv.reshape(-1, 2)[:, 0:1]
    v = uv.reshape(-1, 2)[:, 1:2]
    dt = -(u - u_itl[None, 1:]) * dv_itl[None, 1:] + (v - v_itl[None, 1:]) * du_itl[None, 1:]
    mask = dt <= 0  # (N, 30)
    i = jnp.where(jnp.any(mask, axis=1), jnp.argmax(mask, axis=1) + 1, 30)
    dt_cur = -jnp.minimum(jnp.take_along_axis(dt, (i - 1)[:, None], axis=1)[:, 0], 0.0)
    dt_prev = jnp.take_along_axis(dt, jnp.maximum(i - 2, 0)[:, None], axis=1)[:, 0]
    f = jnp.where(i == 1, 0.0, dt_cur / jnp.where(i == 1, 1.0, dt_prev + dt_cur))
    mired = r_itl[i - 1] * f + r_itl[i] * (1.0 - f)
    T = 1e6 / mired
    u_i = u_itl[i - 1] * f + u_itl[i] * (1.0 - f)
    v_i = v_itl[i - 1] * f + v_itl[i] * (1.0 - f)
    du_i = du_itl[i] * (1.0 - f) + du_itl[i - 1] * f
    dv_i = dv_itl[i] * (1.0 - f) + dv_itl[i - 1] * f
    n = jnp.sqrt(du_i**2 + dv_i**2)
    Duv = (u[:, 0] - u_i) * du_i / n + (v[:, 0] - v_i) * dv_i / n
    return jnp.stack([T, -Duv], axis=-1).reshape(batch + (2,))


def uv_to_CCT(
    uv: Float[ArrayLike, "*batch 2"],
    method: str = "Ohno 2013",
    observer: str = DEFAULT_OBSERVER,
    *,
    c2: float | None = None,
) -> Float[Array, "*batch 2"]:
    r"""Correlated colour temperature and $D_{uv}$ from CIE 1960 (u, v).

    **Methods:**

    - "Ohno 2013" (default): nearest row of a Planckian table (T from 1000 K to 100000 K,
        0.1 % steps, the rows of colour-science's `planckian_table`) found by a two-level
        (coarse every 32nd row, then +/- 33 rows) search, then Ohno's triangular solution,
        or the parabolic one where $|D_{uv}| \ge 0.002$. Same table and formulas as
        `colour.temperature.uv_to_CCT_Ohno2013`; vectorised. Exact to ~0.01 K inside
        1000-100000 K, |Duv| <= 0.05. The table is built once per (observer, c2).
    - "Robertson 1968": interpolation between Robertson's 31 isotemperature lines (fixed
        table, CIE 1931 observer; `observer` and `c2` are ignored). Accurate to ~1 K near
        the locus between ~2000 K and 20000 K.

    **Arguments:**

    - `uv`: (..., 2) CIE 1960 UCS chromaticity. [dimensionless]
    - `method`, `observer`, `c2` (see module docstring; None: exact SI).

    **Returns:** (..., 2) `[CCT [K], Duv [dimensionless]]`, Duv > 0 above the locus.

    Gradients flow through the interpolation formulas (the table indices are piecewise
    constant). NaN input gives NaN output.

    !!! note "Thesis"
        Def. 2.2.2, section 2.2.1, table 2.1.

    ??? cite "References"
        `Ohno2014` (Ohno 2013/2014, LEUKOS 10(1)); `Robertson1968`; `CIE2018` section 9.1.
    """
    check_choice(method, "CCT method", ["Ohno 2013", "Robertson 1968"])
    uv = check_last_axis(as_float_array(uv, "uv"), "uv", 2)
    if method == "Ohno 2013":
        return _uv_to_CCT_ohno2013(uv, observer, c2)
    return _uv_to_CCT_robertson1968(uv)


def xy_to_CCT(
    xy: Float[ArrayLike, "*batch 2"],
    method: str = "Ohno 2013",
    observer: str = DEFAULT_OBSERVER,
    *,
    c2: float | None = None,
) -> Array:
    r"""Correlated colour temperature (and $D_{uv}$) of CIE xy chromaticities.

    **Arguments:**

    - `xy`: (..., 2) CIE 1931 chromaticity. [dimensionless]
    - `method`: "Ohno 2013" (default) or "Robertson 1968" (see `uv_to_CCT`), or
        "McCamy 1992": $T = -449 n^3 + 3525 n^2 - 6823.3 n + 5520.33$ with
        $n = (x - 0.3320)/(y - 0.1858)$, a cubic fit valid for ~2000-12500 K near the locus
        (errors up to a few K; no Duv).
    - `observer`, `c2`: as in `uv_to_CCT` (Ohno only).

    **Returns:** (..., 2) `[CCT [K], Duv]` for Ohno and Robertson; (...,) CCT [K] for McCamy.

    !!! note "Thesis"
        Def. 2.2.2, table 2.1 (A: 2856 K, D65: 6504 K).

    ??? cite "References"
        `Ohno2014`; `Robertson1968`; `McCamy1992`.
    """
    check_choice(method, "CCT method", _METHODS)
    xy = check_last_axis(as_float_array(xy, "xy"), "xy", 2)
    if method == "McCamy 1992":
        n = (xy[..., 0] - 0.3320) / (xy[..., 1] - 0.1858)
        return -449.0 * n**3 + 3525.0 * n**2 - 6823.3 * n + 5520.33
    return uv_to_CCT(xy_to_UCS_uv(xy), method, observer, c2=c2)


def CCT_to_uv(
    CCT: ArrayLike,
    Duv: ArrayLike = 0.0,
    observer: str = DEFAULT_OBSERVER,
    *,
    c2: float | None = None,
) -> Float[Array, "*batch 2"]:
    r"""CIE 1960 (u, v) at temperature `CCT` and distance `Duv` from the Planckian locus.

    $uv = uv_P(T) + D_{uv}\,\hat n(T)$ with $\hat n$ the unit normal of the locus (pointing
    up, the tangent rotated by +90°), taken from the exact derivative of `planckian_locus_uv`
    (colour-science's `CCT_to_uv_Ohno2013` uses a 0.01 K finite difference; they agree to
    ~1e-9 in uv).

    **Arguments:** `CCT` (...,) > 0 [K]; `Duv` (...,) [dimensionless]; `observer`; `c2`.

    **Returns:** uv (..., 2).

    ??? cite "References"
        `Ohno2014`.
    """
    T = as_float_array(CCT, "CCT")
    D = jnp.asarray(as_float_array(Duv, "Duv"), dtype=T.dtype)
    T, D = jnp.broadcast_arrays(T, D)
    f = functools.partial(planckian_locus_uv, observer=observer, c2=c2)
    uv0, duv = jax.jvp(f, (T,), (jnp.ones_like(T),))
    h = jnp.sqrt(jnp.sum(duv**2, axis=-1))
    # Normal: colour's convention (u0 - D dv/h, v0 + D du/h) with (du, dv) = uv(T) - uv(T+dT).
    nu = duv[..., 1] / h
    nv = -duv[..., 0] / h
    return jnp.stack([uv0[..., 0] + D * nu, uv0[..., 1] + D * nv], axis=-1)


def CCT_to_xy(
    CCT: ArrayLike,
    locus: str = "planckian",
    observer: str = DEFAULT_OBSERVER,
    *,
    Duv: ArrayLike = 0.0,
    c2: float | None = None,
) -> Float[Array, "*batch 2"]:
    r"""CIE xy chromaticity at correlated colour temperature `CCT`.

    **Arguments:**

    - `CCT`: (...,), > 0. [K]
    - `locus`: "planckian" (default; exact Planckian locus, optionally offset by `Duv`
        along its normal, see `CCT_to_uv`) or "daylight" (CIE D-series locus, 4000-25000 K,
        `daylight_locus_xy`; `Duv`, `observer` and `c2` are ignored).
    - `observer`, `Duv`, `c2`: Planckian locus only.

    **Returns:** xy (..., 2). [dimensionless]

    !!! note "Thesis"
        Section 2.2.1, fig. 2.2 (Planckian locus), table 2.1.

    ??? cite "References"
        `CIE2018` sections 4.1.2 and 9.1.
    """
    check_choice(locus, "locus", ["planckian", "daylight"])
    if locus == "daylight":
        return daylight_locus_xy(CCT)
    return UCS_uv_to_xy(CCT_to_uv(CCT, Duv, observer, c2=c2))
