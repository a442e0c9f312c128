r"""Infrared tails of upsampled reflectances (pbrt-v4 #82) and the fit stage that removes them.

**The failure.** Eq. 2.27 sees a reflectance only through the colour-matching functions, which
above 730 nm are below 0.2 % of their peaks. A dark saturated colour therefore has two kinds of
exact solution: a low bump under the CMFs, and a sigmoid whose rising edge sits past 730 nm,
nearly 0 in the visible and close to 1 in the infrared. The continuation of `fit_lut` along
brightness follows a bright red's rising edge down into the dark levels, so the table's darkest
reds are of the second kind: pbrt-v4 issue #82 reports the colour (1.07e-4, 0, 1.05e-5) turned
into a reflectance near 1 above 760 nm, and radiometria's tables reproduced it (tail ratio
1e3-4e3). Both kinds have the same colour, but a spectral renderer samples wavelengths up to
830 nm, where such a "dark" surface reflects as a white one would (and a medium whose
coefficients are upsampled from it is transparent there).

**Tail ratio.** $q(c) = \max_{730 \le \lambda \le 830} S(\lambda) /
\max_{360 \le \lambda \le 730} S(\lambda)$. $S = s(x)$ with $s$ increasing and $x$ a quadratic,
so each maximum is the sigmoid of the quadratic's maximum over the interval, at an end or at
the vertex (closed form, no wavelength grid), and $\ln q$ has the closed-form gradient
$(s'/s)(x_t)\,\partial x_t/\partial c - (s'/s)(x_v)\,\partial x_v/\partial c$ at the two
maximising wavelengths (envelope theorem; a subgradient where a maximum is shared).

**Why not every tail can go.** The sigmoid polynomial of `Jakob2019` has three parameters,
and in the dark its spectra are $s(x) \approx 1/(4x^2)$: bumps with algebraic flanks. A bump
centred in the visible red leaks into the green and blue through those flanks, so the family
makes a dark, saturated red only with a bump whose peak lies past 730 nm and whose blue-ward
flank carries the colour (sRGB's red primary at brightness 1e-4: peak at 744 nm, q = 2 at
0.0005 $\Delta E^*_{ab}$), or with the rising edge. For some colours even the best tail-free
member misses the colour (pbrt's (1.07e-4, 0, 1.05e-5): 0.010-0.014 $\Delta E^*_{ab}$ at
q <= 2, found by this module's fit from several starts), so removing a tail can cost colour
accuracy, and the stage trades at most `TAIL_TOLERANCE` = 0.05 $\Delta E^*_{ab}$ (a
twentieth of a just-noticeable difference) for it.

**The stage** (`suppress_infrared_tails`, stage 4 of `fit_lut`). Every entry with
$q > $ `TAIL_RATIO` is fitted again with eq. 2.27 plus one residual more,
$w \max(0, \ln q - \ln T)$ (a hinge on the log tail ratio: zero for every spectrum without a
tail, so a tail-free exact solution has cost 0), by the Levenberg-Marquardt iteration of
`_lm.py` (`TAIL_STEPS` iterations), from three starts: the entry itself, a bump of its
brightness where its spectrum peaks in the visible, and the deep red above scaled to its
brightness (`deep_red_start`; dark spectra are $s(x) \approx 1/(4x^2)$, so scaling x by
$\sqrt{z_0 / z}$ keeps the shape and scales the spectrum to brightness z). All entries of all
nodes go through one compiled program in fixed-size chunks, in the table's own precision; which
entries have a tail, and whether a refit keeps the colour, is decided in float64 on the
coefficients as they are stored. The refit replaces the entry where it keeps the colour
within `TAIL_TOLERANCE` with $q \le T$; elsewhere the entry is kept and counted (`report`):
those are colours that only a spectrum with a tail reproduces that closely (mostly the
brighter saturated reds, whose tails stay moderate: q < 10 above brightness 0.03 in sRGB).
Lookups interpolate between nodes, and refined lookups (`_lut._refine`) make the same trade.
Cost: 2.4 s for a res-64 table on 2 CPU cores, warm (the fit's stages 1-3: 1.2 s).

Thesis: section 2.2.3 (eq. 2.27 and its table). References: pbrt-v4 issue #82 (the tail of
near-black RGB albedos); `Jakob2019` (the sigmoid polynomial and its table); `Marquardt1963`.
"""

import contextlib
import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array

from ..constants import VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM
from ._forward import forward_model
from ._layout import column_directions
from ._lm import ModelArrays, _lm_direction, residual_and_jacobian, target_Lab
from ._sigmoid_polynomial import _nm_to_normalised_np, _normalised_to_nm_np, _sigmoid

TAIL_START_NM = 730.0  # above it the CIE 1931 CMFs are below 0.2 % of their peaks
TAIL_RATIO = 2.0  # the stage's bound on q at the table's nodes (lookups interpolate between)
TAIL_WEIGHT = 10.0  # w: Delta E*ab per unit of ln q above the bound
TAIL_STEPS = 16  # Levenberg-Marquardt iterations per start (200 replace 2 % more entries)
TAIL_TOLERANCE = 0.05  # Delta E*ab a tail-free refit may trade (1/20 of a JND)


_T730 = (TAIL_START_NM - VISIBLE_WAVELENGTH_MIN_NM) / (
    VISIBLE_WAVELENGTH_MAX_NM - VISIBLE_WAVELENGTH_MIN_NM
)  # 730 nm on the normalised wavelength axis


def _tail_mask(m: ModelArrays) -> Array:
    return m.lam > _T730


def _log_s_and_slope(x: Array) -> tuple[Array, Array]:
    """ln s(x) and d ln s / dx = s'(x) / s(x) of the Jakob sigmoid, stable for x << 0."""
    ax = jnp.abs(x)
    r = jnp.sqrt(1.0 + ax * ax)
    lower = -jnp.log(2.0 * r * (r + ax))  # ln s(-|x|), no cancellation
    s = _sigmoid(x)
    log_s = jnp.where(x < 0, lower, jnp.log(s))
    return log_s, 0.5 / (r * r * r) / s


def _interval_max(c: Array, lo: float, hi: float) -> tuple[Array, Array]:
    """max of x = c0 l^2 + c1 l + c2 over l in [lo, hi] (normalised), and where: at an end or
    at the vertex of a concave parabola (closed form, (n,) each)."""
    a, b, c0 = c[:, 0], c[:, 1], c[:, 2]
    x = lambda t: (a * t + b) * t + c0  # noqa: E731
    x_lo, x_hi = x(lo), x(hi)
    v = -b / (2.0 * jnp.where(a < 0, a, -1.0))
    inside = (a < 0) & (v > lo) & (v < hi)
    x_v = jnp.where(inside, x(jnp.where(inside, v, lo)), -jnp.inf)
    at = jnp.where(x_v >= jnp.maximum(x_lo, x_hi), v, jnp.where(x_lo >= x_hi, lo, hi))
    return jnp.maximum(jnp.maximum(x_lo, x_hi), x_v), at


def log_tail_ratio(c: Array, m: ModelArrays | None = None) -> tuple[Array, Array]:
    r"""$\ln q$ (n,) and its gradient in the normalised coefficients `c` (n, 3) (module
    docstring). `m` is not needed (the maxima are in closed form); accepted for symmetry with
    the residual functions."""
    xt, lt_at = _interval_max(c, _T730, 1.0)
    xv, lv_at = _interval_max(c, 0.0, _T730)
    lt, gt = _log_s_and_slope(xt)
    lv, gv = _log_s_and_slope(xv)
    basis = lambda t: jnp.stack([t * t, t, jnp.ones_like(t)], -1)  # noqa: E731
    # Envelope theorem: at an interior maximum dx/dl = 0, so only c moves the maximum.
    grad = gt[:, None] * basis(lt_at) - gv[:, None] * basis(lv_at)
    return lt - lv, grad


def penalised_residual_and_jacobian(c, lab_t, m: ModelArrays, log_bound, weight):
    """Eq. 2.27's residual (n, 3) plus the tail hinge, as (n, 4) with Jacobian (n, 4, 3)."""
    r, J = residual_and_jacobian(c, lab_t, m)
    q, g = log_tail_ratio(c, m)
    active = q > log_bound
    w = jnp.broadcast_to(jnp.asarray(weight, q.dtype), q.shape)  # a scalar or one per row
    rt = w * jnp.where(active, q - log_bound, 0.0)
    Jt = w[:, None] * jnp.where(active[:, None], g, 0.0)
    return jnp.concatenate([r, rt[:, None]], -1), jnp.concatenate([J, Jt[:, None, :]], -2)


@functools.partial(jax.jit, static_argnames=("n_steps",))
def _penalised_lm(c0, lab_t, m, log_bound, weight, n_steps: int):
    """`n_steps` Levenberg-Marquardt iterations (the acceptance rule of `_lm.lm_step`) on the
    penalised residual; returns the best coefficients, the colour residual norm (Delta E*ab)
    and ln q there."""
    rj = lambda c: penalised_residual_and_jacobian(c, lab_t, m, log_bound, weight)  # noqa: E731
    r, J = rj(c0)
    cost = jnp.sum(r * r, -1)
    cost = jnp.where(jnp.isfinite(cost), cost, jnp.inf)
    mu = jnp.full(cost.shape, 1e-4, c0.dtype)

    def body(_, s):
        c, r, J, cost, mu = s
        cn = c + _lm_direction(J, r, mu)
        rn, Jn = rj(cn)
        cost_n = jnp.sum(rn * rn, -1)
        ok = (cost_n < cost) & jnp.isfinite(cost_n)
        c = jnp.where(ok[:, None], cn, c)
        r = jnp.where(ok[:, None], rn, r)
        J = jnp.where(ok[:, None, None], Jn, J)
        cost = jnp.where(ok, cost_n, cost)
        mu = jnp.clip(jnp.where(ok, mu * 0.2, mu * 8.0), 1e-9, 1e9)
        return c, r, J, cost, mu

    c, r, J, cost, mu = lax.fori_loop(0, n_steps, body, (c0, r, J, cost, mu))
    return c, jnp.linalg.norm(r[:, :3], axis=-1), log_tail_ratio(c, m)[0], cost


def _bump_start(c: np.ndarray, m_lam: np.ndarray, vis: np.ndarray, z: np.ndarray) -> np.ndarray:
    """A concave parabola of peak value s^-1(z) (brightness z, (n,)) at the visible argmax of
    each spectrum `c` (n, 3)."""
    x = (c[:, 0:1] * m_lam + c[:, 1:2]) * m_lam + c[:, 2:3]
    peak = m_lam[np.argmax(np.where(vis, x, -np.inf), axis=1)]
    peak = np.clip(peak, 0.05, 0.75)
    x0 = (z - 0.5) / np.sqrt(z * (1.0 - z))  # the grey closed form's inverse sigmoid
    a = 40.0
    return np.stack([-a * np.ones_like(peak), 2 * a * peak, x0 - a * peak * peak], -1)


# A tail-free reflectance of the darkest saturated reds (normalised coefficients): the
# penalised fit's solution for sRGB's red primary at brightness 1e-4, a bump peaking at 744 nm
# whose blue-ward flank carries the colour (`Jakob2019`'s family makes such reds no other way
# without a tail). Dark spectra are s(x) ~ 1 / (4 x^2), so `deep_red_start(z)` scales it to
# brightness z with its shape kept.
_DEEP_RED = np.array([-1050.0, 1713.0, -700.0])
_DEEP_RED_Z = 1e-4


def deep_red_start(z) -> np.ndarray:
    """`_DEEP_RED` scaled to brightness `z` (..., ) -> (..., 3) (see above)."""
    z = np.clip(np.asarray(z, np.float64), 1e-12, 1e-2)
    return _DEEP_RED * np.sqrt(_DEEP_RED_Z / z)[..., None]


class TailStage(NamedTuple):
    """What `suppress_infrared_tails` returns."""

    coeffs: np.ndarray  # (3, res, res, res, 3) the new table, nm coefficients
    replaced: np.ndarray  # (3, res, res, res) bool: the entries refitted without a tail
    residual: np.ndarray  # (3, res, res, res) Delta E*ab of the replaced entries (0 elsewhere)
    report: dict  # counts and bounds, JSON-able


def colour_errors(coeffs_nm: np.ndarray, rgb: np.ndarray, colourspace: str) -> np.ndarray:
    """Delta E*ab (n,) of nm coefficients (n, 3) against linear RGB (n, 3) (float64)."""
    with jax.enable_x64(True):
        m64 = ModelArrays.build(forward_model(colourspace), jnp.float64)
        c = _nm_to_normalised_np(np.asarray(coeffs_nm, np.float64))
        return _chunked(_colour_error, np.concatenate([c, rgb], -1), m64)


def suppress_infrared_tails(
    coeffs_nm: np.ndarray,
    scale: np.ndarray,
    colourspace: str,
    *,
    tail_ratio: float = TAIL_RATIO,
    tolerance: float = TAIL_TOLERANCE,
    n_steps: int = TAIL_STEPS,
    weight: float = TAIL_WEIGHT,
    progress=None,
) -> TailStage:
    r"""Refit the table entries whose reflectance has an infrared tail (module docstring).

    **Arguments:**

    - `coeffs_nm`: the table, (3, res, res, res, 3) nm coefficients in `RGBToSpectrumLUT`'s
        layout (not modified).
    - `scale`: its brightness nodes (res,). [-]
    - `colourspace`: the table's colour space (its forward model).
    - `tail_ratio`: the bound T on q at a node. [-]
    - `tolerance`: the colour error $\Delta E^*_{ab}$ a tail-free refit may have and still
        replace the entry. [-]
    - `n_steps`, `weight`: Levenberg-Marquardt iterations per start and the hinge's weight w.
    - `progress`: optional `progress("tails", done, total)` per chunk of entries.

    **Returns:**

    A `TailStage`: the new table (same dtype; entries without a tail, the grey column and the
    entries no tail-free refit reproduces are unchanged bit for bit; row 0 = row 1 as in
    `fit_lut`), which entries were replaced and their colour error, and a report (entries
    with a tail, replaced, kept, largest q left, the bounds used).
    """
    coeffs_nm = np.asarray(coeffs_nm)
    res = coeffs_nm.shape[1]
    if coeffs_nm.shape != (3, res, res, res, 3) or np.shape(scale) != (res,):
        raise ValueError(
            f"`coeffs_nm` must have shape (3, res, res, res, 3) and `scale` (res,), got "
            f"{coeffs_nm.shape} and {np.shape(scale)}."
        )
    out = coeffs_nm.copy()
    replaced = np.zeros((3, res, res, res), bool)
    residual = np.zeros((3, res, res, res))
    scale = np.asarray(scale, np.float64)
    log_bound = float(np.log(tail_ratio))
    grey = np.zeros((3, res, res), bool)
    grey[:, res - 1, res - 1] = True
    grey = grey.reshape(-1)
    # The table's own precision (float32 for the packaged tables, as the fit).
    dtype = np.dtype(np.float64 if coeffs_nm.dtype == np.float64 else np.float32)
    # Which entries have a tail, and whether a refit keeps the colour, is decided in float64
    # on the coefficients as stored; the search runs in the table's own precision (float32
    # for the packaged tables, as the fit: about twice as fast).
    with jax.enable_x64(True):
        m64 = ModelArrays.build(forward_model(colourspace), jnp.float64)
        lam = np.asarray(m64.lam)
        vis = ~np.asarray(_tail_mask(m64))
        # Every node k >= 1 at once: (k, l, j, i) flattened, the grey column left out.
        nodes = np.moveaxis(out[:, 1:], 1, 0).reshape(res - 1, -1, 3)
        own = _nm_to_normalised_np(nodes.reshape(-1, 3).astype(np.float64))
        q = _chunked(_log_q, own, m64)
    grey_all = np.tile(grey, res - 1)
    cand = np.flatnonzero((q > log_bound) & ~grey_all)
    k_c = cand // (3 * res * res) + 1
    z = scale[k_c]
    rgb = column_directions(res, np.float64)[cand % (3 * res * res)] * z[:, None]
    starts = [own[cand], _bump_start(own[cand], lam, vis, z), deep_red_start(z)]
    with jax.enable_x64(True) if dtype == np.float64 else contextlib.nullcontext():
        m = ModelArrays.build(forward_model(colourspace), dtype)
        c = _best_of_starts(starts, rgb, m, log_bound, weight, n_steps, progress)
    with np.errstate(over="ignore", invalid="ignore"):
        new_nm = _normalised_to_nm_np(c).astype(out.dtype)
    finite = np.all(np.isfinite(new_nm), -1)
    new_nm[~finite] = 0.0
    de = colour_errors(new_nm, rgb, colourspace)
    with jax.enable_x64(True):
        qn = _chunked(_log_q, _nm_to_normalised_np(new_nm.astype(np.float64)), m64)
    ok = (de <= tolerance) & (qn <= log_bound + 1e-3) & finite
    kk, rest = np.divmod(cand[ok], 3 * res * res)
    l_, j_, i_ = np.unravel_index(rest, (3, res, res))
    out[l_, kk + 1, j_, i_] = new_nm[ok]
    replaced[l_, kk + 1, j_, i_] = True
    residual[l_, kk + 1, j_, i_] = de[ok]
    out[:, 0] = out[:, 1]
    replaced[:, 0], residual[:, 0] = replaced[:, 1], residual[:, 1]
    n_tail = int(cand.size)
    left = np.ones(q.shape, bool)
    left[cand[ok]] = False
    left &= ~grey_all  # greys are exactly flat
    q_left = float(np.exp(q[left].max())) if left.any() else 1.0
    report = {
        "tail_start_nm": TAIL_START_NM,
        "tail_ratio_bound": float(tail_ratio),
        "tolerance_delta_E_ab": float(tolerance),
        "entries_with_tail": int(n_tail),
        "replaced": int(replaced[:, 1:].sum()),
        "kept": int(n_tail - replaced[:, 1:].sum()),
        "residual_max_replaced": float(residual.max()),
        "max_tail_ratio_left": q_left,
    }
    return TailStage(out, replaced, residual, report)


_CHUNK = 2048  # entries per compiled call (x the number of starts): one program for any table


def _pad_rows(x: np.ndarray, size: int, value: float = 0.0) -> np.ndarray:
    return np.pad(x, ((0, size - x.shape[0]), (0, 0)), constant_values=value)


@jax.jit
def _log_q(c, m):
    return log_tail_ratio(c, m)[0]


@jax.jit
def _colour_error(c_rgb, m):
    """Delta E*ab of normalised coefficients `c_rgb[:, :3]` against linear RGB `c_rgb[:, 3:]`."""
    r, _ = residual_and_jacobian(c_rgb[:, :3], target_Lab(c_rgb[:, 3:], m), m)
    return jnp.linalg.norm(r, axis=-1)


def _chunked(fn, c: np.ndarray, m: ModelArrays, size: int = 8 * _CHUNK) -> np.ndarray:
    """`fn(rows, m)` over the rows of `c` in padded chunks of `size` (one compiled shape)."""
    out = []
    for a in range(0, c.shape[0], size):
        part = c[a : a + size]
        rows = jnp.asarray(_pad_rows(part, size), m.lam.dtype)
        out.append(np.asarray(fn(rows, m), np.float64)[: part.shape[0]])
    return np.concatenate(out) if out else np.zeros((0,))


def _best_of_starts(starts, rgb, m, log_bound, weight, n_steps, progress=None):
    """The penalised fit from every start, in chunks of `_CHUNK` entries (all starts of an
    entry in one batch); per entry the coefficients of the run of lowest penalised cost."""
    n, ns = rgb.shape[0], len(starts)
    c_out = np.zeros((n, 3))
    for a in range(0, n, _CHUNK):
        b = min(n, a + _CHUNK)
        dt = m.lam.dtype
        c0 = jnp.asarray(np.concatenate([_pad_rows(s[a:b], _CHUNK) for s in starts]), dt)
        lab_t = target_Lab(jnp.asarray(np.tile(_pad_rows(rgb[a:b], _CHUNK, 0.5), (ns, 1)), dt), m)
        c, _, _, cost = _penalised_lm(c0, lab_t, m, log_bound, weight, n_steps)
        c, cost = (
            np.asarray(x, np.float64).reshape((ns, _CHUNK) + x.shape[1:])[:, : b - a]
            for x in (c, cost)
        )
        best = np.argmin(np.where(np.isfinite(cost), cost, np.inf), axis=0)
        rows = np.arange(b - a)
        c_out[a:b] = c[best, rows]
        if progress is not None:
            progress("tails", b, n)
    return c_out
