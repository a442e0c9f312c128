r"""The RGB -> coefficient table (thesis section 2.2.3, after eq. 2.27): layout and lookup.

**Layout (pbrt-v4 `RGBToSpectrumTable`, rgb2spec).** `coeffs[l, k, j, i, :]` holds the nm
coefficients of the colour whose largest component is channel `l` with value `scale[k]`, and
whose next two components (cyclically, channels `(l+1) % 3` and `(l+2) % 3`) are
`i / (res - 1)` and `j / (res - 1)` times `scale[k]`. The brightness axis is nonlinear,
`scale[k] = smoothstep(smoothstep(k / (res - 1)))` with `smoothstep(t) = t^2 (3 - 2t)`, which
puts nodes densely near black and white.

**Lookup (pbrt semantics).** Greys (r = g = b) take the closed form
$c = (0, 0, (v - \tfrac12)/\sqrt{v(1-v)})$, exact (black -> 0, white -> 1). Otherwise: the
largest component `l` (ties broken as pbrt), `z = rgb[l]`, `x, y` the next two components
divided by `z` on the `(res - 1)` grid, the brightness interval found by search in `scale`, and
trilinear interpolation of the coefficients.

**Refined lookups (wide-gamut tables).** A table whose fit found colours that no reflectance
has (`fit_lut`'s `out_of_reach` entries: the bright, saturated corners of Display P3, Rec.2020
and ACEScg) has cells that mix exact nodes with best-fit nodes of unreachable colours, and
trilinear interpolation in those cells misses colours a reflectance does have by up to 8
CIEDE2000 units. Such a table (`refine_steps > 0`, set by `load_lut` and `fit_lut` from the
fit's record) finishes every lookup with the fit itself: `refine_steps` Levenberg-Marquardt
iterations of eq. 2.27 (`_lm.py`) from the interpolated coefficients and, side by side, from
(0, 0, 0), keeping the better. Measured on 21 000-24 000 random colours a reflectance has per
space: 32 iterations give max CIEDE2000 0.02-0.06, mean < 1e-4 (the interpolation alone:
max 3.2-7.8, mean 0.04-0.08; the interpolated start alone stalls in a poor basin for a few
colours, the start at 0 for others). Where the winner has an infrared tail, a tail-free fit of
the same colour replaces it on the tail stage's rule (`_tails.py`, `_refine`). Derivatives of
refined coefficients come from the implicit
function theorem at the solution ($dc = J^{+}\, d\,\mathrm{Lab}_t$, exact where the colour is
reproduced), not from unrolling the iterations. The sRGB table has no such cells and is looked
up exactly as pbrt does.

The table is built by `fit_lut` (`_fit_lut.py`), which also sets its explicit entries (black
row, grey column, white), and read and written by `load_lut` / `save_lut` (`_io.py`).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_last_axis, check_positive_int
from ._forward import forward_model
from ._lm import ModelArrays, _lm_direction, residual_and_jacobian, target_Lab
from ._sigmoid_polynomial import (
    common_float_dtype,
    grey_coefficients,
    nm_to_normalised_coefficients,
    normalised_to_nm_coefficients,
)
from ._tails import _DEEP_RED, _DEEP_RED_Z, TAIL_RATIO, TAIL_TOLERANCE, TAIL_WEIGHT, _penalised_lm

# Levenberg-Marquardt iterations of each of a refined lookup's two starts (module docstring):
# 16 left max CIEDE2000 0.36-0.47 on Rec.2020 and ACEScg, 32 gives 0.02-0.06.
REFINE_STEPS = 32


def brightness_scale(resolution: int, dtype=np.float64) -> np.ndarray:
    """pbrt's brightness nodes `smoothstep(smoothstep(k / (res - 1)))`, k = 0 .. res - 1. [-]

    The brightness axis of the table of thesis section 2.2.3 (`Pharr2023` section 4.6.6).
    """
    t = np.arange(resolution, dtype=np.float64) / (resolution - 1)
    ss = lambda u: u * u * (3.0 - 2.0 * u)  # noqa: E731
    return ss(ss(t)).astype(dtype)


class RGBToSpectrumLUT(eqx.Module):
    r"""Table of sigmoid-polynomial coefficients for the RGB colours of one colour space.

    A pytree (equinox Module), so it can be passed through `jit` and `vmap` and its arrays
    differentiated. Build one with `fit_lut`, read one with `load_lut`, or take the packaged
    sRGB table from `get_lut()`.

    **Fields:**

    - `resolution`: table size per axis (static).
    - `colourspace`: name of the RGB colour space (static).
    - `scale` (res,): brightness nodes, increasing from 0 to 1. [-]
    - `coeffs` (3, res, res, res, 3): nm coefficients in pbrt's layout (module docstring).
        [nm^-2, nm^-1, -]
    - `refine_steps`: Levenberg-Marquardt iterations that finish each lookup (static; 0 =
        pbrt's plain trilinear lookup). `load_lut` and `fit_lut` set `REFINE_STEPS` for tables
        whose fit found colours no reflectance has (module docstring, "Refined lookups").

    `lut.coefficients(rgb)` maps linear RGB (..., 3) in [0, 1] to nm coefficients (..., 3).

    !!! note "Thesis"
        Section 2.2.3, the lookup table after eq. 2.27.

    ??? cite "References"
        `Jakob2019` section 5; `Pharr2023` section 4.6.6 (`RGBToSpectrumTable`).
    """

    resolution: int = eqx.field(static=True)
    colourspace: str = eqx.field(static=True)
    scale: Float[Array, " res"]
    coeffs: Float[Array, "3 res res res 3"]
    refine_steps: int = eqx.field(static=True)

    def __init__(
        self,
        scale: ArrayLike,
        coeffs: ArrayLike,
        colourspace: str = "sRGB",
        refine_steps: int = 0,
    ):
        scale = as_float_array(scale, "scale")
        coeffs = as_float_array(coeffs, "coeffs")
        if scale.ndim != 1 or scale.shape[0] < 2:
            raise ValueError(f"`scale` must have shape (res,) with res >= 2, got {scale.shape}.")
        res = scale.shape[0]
        if coeffs.shape != (3, res, res, res, 3):
            raise ValueError(
                f"`coeffs` must have shape (3, res, res, res, 3) = {(3, res, res, res, 3)} for "
                f"res = {res}, got {coeffs.shape}."
            )
        self.resolution = int(res)
        self.refine_steps = check_positive_int(refine_steps, "refine_steps", minimum=0)
        self.colourspace = str(colourspace)
        if self.refine_steps:
            # The refinement's forward model, built now: tables are made eagerly (`load_lut`,
            # `fit_lut`), and its colour-science data cannot be computed inside a trace.
            forward_model(self.colourspace)
        self.scale = scale
        self.coeffs = coeffs

    def with_refinement(self, refine_steps: int) -> "RGBToSpectrumLUT":
        """The same table with `refine_steps` refinement iterations per lookup (0: pbrt's plain
        lookup)."""
        return RGBToSpectrumLUT(self.scale, self.coeffs, self.colourspace, refine_steps)

    def coefficients(self, rgb: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 3"]:
        r"""nm coefficients for linear RGB in [0, 1] (pbrt's lookup, module docstring; refined
        by the fit of eq. 2.27 where `refine_steps > 0`).

        Differentiable in `rgb` (piecewise linear, finite gradients also at black and on the
        grey axis) and in the table. Components outside [0, 1] or non-finite raise
        (`eqx.error_if` under `jit`).

        **Arguments:**

        - `rgb`: linear RGB of this table's colour space, (..., 3), components in [0, 1]. [-]

        **Returns:**

        (..., 3) coefficients $(c_0, c_1, c_2)$ for $\lambda$ in nm. [nm^-2, nm^-1, -]
        """
        rgb = check_last_axis(as_float_array(rgb, "rgb"), "rgb", 3)
        rgb = _check_rgb_values(rgb)
        return lookup(self, rgb)


def _check_rgb_values(rgb: Array, *, upper: float | None = 1.0, name: str = "rgb") -> Array:
    """Static-if-possible check: components finite, >= 0 and (if `upper`) <= upper."""
    if isinstance(rgb, jax.core.Tracer):
        bad = ~jnp.isfinite(rgb) | (rgb < 0)
        if upper is not None:
            bad = bad | (rgb > upper)
        return eqx.error_if(
            rgb, bad, f"`{name}` components must be finite and in [0, {upper}] (linear RGB)."
        )
    a = np.asarray(rgb)
    if not np.all(np.isfinite(a)):
        raise ValueError(
            f"`{name}` has non-finite components (NaN or inf); linear RGB must be finite."
        )
    if np.any(a < 0):
        raise ValueError(
            f"`{name}` has negative components (min {a.min():.6g}); linear RGB must be >= 0 "
            "(out-of-gamut colours: convert or clip them first)."
        )
    if upper is not None and np.any(a > upper):
        raise ValueError(
            f"`{name}` has components > {upper} (max {a.max():.6g}); use RGBUnboundedSpectrum "
            "or RGBIlluminantSpectrum for values above 1."
        )
    return rgb


def _argmax_pbrt(rgb: Array) -> Array:
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return jnp.where(r > g, jnp.where(r > b, 0, 2), jnp.where(g > b, 1, 2))


@eqx.filter_jit
def lookup(lut: RGBToSpectrumLUT, rgb: Array) -> Array:
    """pbrt's table lookup without argument checks (see `RGBToSpectrumLUT.coefficients`).

    Jitted (one small XLA program instead of ~40 eagerly dispatched operations); it composes
    with an outer `jit`, `vmap` or `grad` as usual.
    """
    dtype = common_float_dtype(rgb, lut.coeffs)
    rgb = rgb.astype(dtype)
    coeffs = lut.coeffs.astype(dtype)
    scale = lut.scale.astype(dtype)
    res = lut.resolution
    batch = rgb.shape[:-1]
    flat = rgb.reshape(-1, 3)

    l = _argmax_pbrt(flat)  # noqa: E741
    z = jnp.take_along_axis(flat, l[:, None], axis=1)[:, 0]
    c1 = jnp.take_along_axis(flat, ((l + 1) % 3)[:, None], axis=1)[:, 0]
    c2 = jnp.take_along_axis(flat, ((l + 2) % 3)[:, None], axis=1)[:, 0]
    positive = z > 0
    z_safe = jnp.where(positive, z, 1.0)
    x = jnp.where(positive, c1 * (res - 1) / z_safe, 0.0)
    y = jnp.where(positive, c2 * (res - 1) / z_safe, 0.0)
    xi = jnp.clip(jnp.floor(x).astype(jnp.int32), 0, res - 2)
    yi = jnp.clip(jnp.floor(y).astype(jnp.int32), 0, res - 2)
    zi = jnp.clip(jnp.searchsorted(scale, z, side="left").astype(jnp.int32) - 1, 0, res - 2)
    dx = x - xi.astype(dtype)
    dy = y - yi.astype(dtype)
    z0 = scale[zi]
    z1 = scale[zi + 1]
    dz = (z - z0) / (z1 - z0)

    def co(ox, oy, oz):
        return coeffs[l, zi + oz, yi + oy, xi + ox]  # (n, 3)

    lerp = lambda t, a, b: a + t[:, None] * (b - a)  # noqa: E731
    c = lerp(
        dz,
        lerp(dy, lerp(dx, co(0, 0, 0), co(1, 0, 0)), lerp(dx, co(0, 1, 0), co(1, 1, 0))),
        lerp(dy, lerp(dx, co(0, 0, 1), co(1, 0, 1)), lerp(dx, co(0, 1, 1), co(1, 1, 1))),
    )
    if lut.refine_steps > 0:
        c = _refine(lut, flat, c)
    grey = (flat[:, 0] == flat[:, 1]) & (flat[:, 1] == flat[:, 2])
    # Closed form for greys, with safe arguments so gradients stay finite at black and white.
    v = jnp.where(grey, flat[:, 0], 0.5)
    c_grey = grey_coefficients(v)
    c = jnp.where(grey[:, None], c_grey, c)
    return c.reshape(batch + (3,))


def _refine(lut: RGBToSpectrumLUT, rgb: Array, c_nm: Array) -> Array:
    """Finish a lookup with the fit of eq. 2.27 (module docstring, "Refined lookups").

    Two Levenberg-Marquardt runs of `lut.refine_steps` iterations, from the interpolated
    coefficients and from (0, 0, 0); the one with the lower residual wins. Where that fit has
    an infrared tail (`_tails.py`, pbrt-v4 #82), two runs with the tail hinge (from the
    interpolated coefficients and from the tail-free deep red) offer a tail-free fit, taken
    if it keeps the colour within `TAIL_TOLERANCE`: the rule of the table's tail stage. The
    iterations are detached; the derivative in `rgb` is the implicit function theorem's,
    $J^{+}$ times the derivative of the target's CIELAB, carried by a step that is zero in
    value.
    """
    # `_tails` builds on this module's table layout, hence the import here.

    dtype = rgb.dtype
    m = ModelArrays.build(forward_model(lut.colourspace), dtype)
    lab_t = target_Lab(rgb, m)
    sg = jax.lax.stop_gradient
    start = sg(nm_to_normalised_coefficients(c_nm))
    start = jnp.where(jnp.isfinite(start), start, 0.0)
    # Four runs in one batch (rows are independent, one compiled copy of the iteration): both
    # starts on eq. 2.27 alone, and on eq. 2.27 with the infrared-tail hinge (`_tails.py`) the
    # interpolated start and the tail-free deep red scaled to the colour's brightness.
    k = start.shape[0]
    z = jnp.max(sg(rgb), axis=-1)
    z = jnp.clip(z, 1e-12, 1e-2)
    deep_red = jnp.asarray(_DEEP_RED, dtype)[None, :] * jnp.sqrt(_DEEP_RED_Z / z)[:, None]
    starts = jnp.concatenate([start, jnp.zeros_like(start), start, deep_red])
    lab4 = jnp.concatenate([sg(lab_t)] * 4)
    weight = jnp.repeat(jnp.asarray([0.0, TAIL_WEIGHT], dtype), 2 * k)
    bound = jnp.asarray(np.log(TAIL_RATIO), dtype)
    c4, de4, q4, cost4 = _penalised_lm(starts, lab4, m, bound, weight, lut.refine_steps)
    cost4 = jnp.where(jnp.isfinite(cost4), cost4, jnp.inf)

    def better(i, j):  # the better of runs i and j (rows i k .. (i + 1) k) by their own cost
        a, b = slice(i * k, (i + 1) * k), slice(j * k, (j + 1) * k)
        first = cost4[a] <= cost4[b]
        pick = lambda v: jnp.where(first.reshape((k,) + (1,) * (v.ndim - 1)), v[a], v[b])  # noqa: E731
        return pick(c4), pick(de4), pick(q4)

    c_col, _, q_col = better(0, 1)
    c_pen, de_pen, _ = better(2, 3)
    # The tail-free fit wins where the colour-only fit has a tail and it keeps the colour
    # within TAIL_TOLERANCE (the trade the table's tail stage makes at its nodes).
    use_pen = (q_col > bound) & (de_pen <= TAIL_TOLERANCE)
    c = jnp.where(use_pen[:, None], c_pen, c_col)
    _, J = residual_and_jacobian(c, sg(lab_t), m)
    # dc = J^+ d Lab_t: the least-squares step for the residual change -(Lab_t - sg(Lab_t)).
    step = _lm_direction(J, sg(lab_t) - lab_t, jnp.zeros(c.shape[:1], dtype))
    return normalised_to_nm_coefficients(c + step).astype(dtype)
