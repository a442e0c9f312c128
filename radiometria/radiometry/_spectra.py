"""Sampled spectra: integration and resampling on (possibly irregular) nanometre grids.

Spectral densities are per nm and grids are in nm (style.md section 4), so the trapezoid
integral of a spectral radiance over its grid is a radiance, with no unit factor.
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_choice

EXTRAPOLATIONS = ("zero", "constant")


def _normalize_axis(axis: int, ndim: int, name: str) -> int:
    if isinstance(axis, bool) or not isinstance(axis, int):
        raise TypeError(f"`axis` must be an int, got {type(axis).__name__} {axis!r}.")
    if not -ndim <= axis < ndim:
        raise ValueError(f"`axis` {axis} is out of range for `{name}` with {ndim} dimension(s).")
    return axis % ndim


def _check_grid(values: Array, wavelengths_nm: Array, axis: int, *, same_shape_ok: bool) -> int:
    """Static checks of a (values, grid) pair; returns the normalised axis."""
    if values.ndim == 0:
        raise ValueError("`values` must have at least one dimension (the wavelength axis).")
    axis = _normalize_axis(axis, values.ndim, "values")
    n = values.shape[axis]
    if wavelengths_nm.ndim == 1:
        if wavelengths_nm.shape[0] != n:
            raise ValueError(
                f"`wavelengths_nm` has {wavelengths_nm.shape[0]} samples but `values` has {n} "
                f"along axis {axis} (shape {values.shape}); they must match."
            )
    elif not (same_shape_ok and wavelengths_nm.shape == values.shape):
        allowed = "1-D (n,) or the shape of `values`" if same_shape_ok else "1-D (n,)"
        raise ValueError(
            f"`wavelengths_nm` must be {allowed}, got shape {wavelengths_nm.shape} for "
            f"`values` of shape {values.shape}."
        )
    if n < 2:
        raise ValueError(f"A spectrum needs at least 2 samples along axis {axis}, got {n}.")
    return axis


def _check_increasing(wavelengths_nm: Array, axis: int) -> Array:
    """Value check: the grid must be strictly increasing along `axis` (NaN passes)."""
    step = jnp.diff(wavelengths_nm, axis=axis)
    return eqx.error_if(
        wavelengths_nm,
        step <= 0,
        "`wavelengths_nm` must be strictly increasing [nm]; got a step <= 0.",
    )


def integrate_spectrum(
    values: ArrayLike, wavelengths_nm: ArrayLike, axis: int = -1
) -> Float[Array, "..."]:
    r"""Integral of a sampled spectrum over wavelength, by the trapezoid rule.

    $$\int f(\lambda)\,\mathrm d\lambda \approx \sum_i \tfrac12 (f_i + f_{i+1})
      (\lambda_{i+1} - \lambda_i)$$

    on any strictly increasing grid, regular or not. Nothing is assumed outside the grid (the
    integral runs from the first to the last sample).

    **Arguments:**

    - `values`: samples of a spectral density, with the wavelength axis `axis`.
        [quantity nm^-1, e.g. W sr^-1 m^-2 nm^-1]
    - `wavelengths_nm`: the grid, strictly increasing: either 1-D with
        `values.shape[axis]` entries, or of the same shape as `values` (one grid per spectrum).
        [nm]
    - `axis`: the wavelength axis of `values` (static int).

    **Returns:**

    The integral, with `axis` removed from the shape. [quantity, e.g. W sr^-1 m^-2]

    Shapes that do not match raise `ValueError`; integer arrays raise `TypeError`; a grid that is
    not strictly increasing raises `equinox.EquinoxRuntimeError` (also under `jax.jit`). NaN
    samples propagate.

    !!! note "Thesis"
        Thesis section 1.4 (spectral quantities, def. 1.4.2-1.4.6: a quantity is the integral
        of its spectral density over wavelength).

    ??? cite "References"
        `Pharr2023` section 4.5.
    """
    values = as_float_array(values, "values")
    wavelengths_nm = as_float_array(wavelengths_nm, "wavelengths_nm")
    axis = _check_grid(values, wavelengths_nm, axis, same_shape_ok=True)
    values = jnp.moveaxis(values, axis, -1)
    if wavelengths_nm.ndim == 1:
        wavelengths_nm = _check_increasing(wavelengths_nm, 0)
    else:
        wavelengths_nm = _check_increasing(jnp.moveaxis(wavelengths_nm, axis, -1), -1)
    step = jnp.diff(wavelengths_nm, axis=-1)
    step = jnp.broadcast_to(step, values.shape[:-1] + step.shape[-1:])
    return 0.5 * jnp.sum(step * (values[..., 1:] + values[..., :-1]), axis=-1)


def _interpolation_weights(grid: Array, x: Array, extrapolation: str):
    """Indices `i0`, `i1 = i0 + 1`, weight `t` of `grid[i1]`, and the outside mask for `x`.

    `grid` is 1-D, strictly increasing; `x` has any shape. For "constant" extrapolation `x` is
    clamped into the grid (so `t` is 0 or 1 outside); for "zero" the mask zeroes the result.
    NaN in `x` gives a NaN weight (and is never "outside"), so it propagates.
    """
    n = grid.shape[0]
    below, above = x < grid[0], x > grid[-1]
    # Clamp with `where`, not `clip`: at x == an end sample `clip` passes half the gradient.
    x_in = jnp.where(below, grid[0], jnp.where(above, grid[-1], x))
    i1 = jnp.clip(jnp.searchsorted(grid, x_in, side="right"), 1, n - 1)
    i0 = i1 - 1
    g0, g1 = grid[i0], grid[i1]
    t = (x_in - g0) / (g1 - g0)
    outside = below | above if extrapolation == "zero" else None
    return i0, i1, t, outside


def resample_spectrum(
    values: ArrayLike,
    wavelengths_nm: ArrayLike,
    new_wavelengths_nm: ArrayLike,
    *,
    extrapolation: str = "zero",
    axis: int = -1,
) -> Float[Array, "..."]:
    r"""Resample a spectrum onto new wavelengths by linear interpolation.

    Inside the grid the result is the piecewise-linear interpolant of the samples (exact at
    the samples). Outside `[wavelengths_nm[0], wavelengths_nm[-1]]` the policy is explicit:

    - `extrapolation="zero"` (default): 0, the CIE convention for tables such as V(lambda) and
      the colour-matching functions, whose tabulated range covers all of their support;
    - `extrapolation="constant"`: the nearest end sample (the value is held flat).

    **Arguments:**

    - `values`: samples of the spectrum, with the wavelength axis `axis`. [any unit]
    - `wavelengths_nm`: 1-D grid of `values.shape[axis]` strictly increasing wavelengths. [nm]
    - `new_wavelengths_nm`: wavelengths to evaluate at, any shape, in any order. [nm]
    - `extrapolation`: `"zero"` or `"constant"` (see above).
    - `axis`: the wavelength axis of `values` (static int).

    **Returns:**

    `values` with `axis` replaced by the shape of `new_wavelengths_nm`. [unit of `values`]

    Errors as for `integrate_spectrum`; an unknown `extrapolation` raises `ValueError`. A NaN
    new wavelength gives NaN. Gradients flow to `values` and to both grids.

    !!! note "Thesis"
        Thesis section 1.4 (spectral quantities sampled on a wavelength grid).

    ??? cite "References"
        `Pharr2023` section 4.5 (`PiecewiseLinearSpectrum`).
    """
    check_choice(extrapolation, "extrapolation", EXTRAPOLATIONS)
    values = as_float_array(values, "values")
    wavelengths_nm = as_float_array(wavelengths_nm, "wavelengths_nm")
    new_wavelengths_nm = as_float_array(new_wavelengths_nm, "new_wavelengths_nm")
    axis = _check_grid(values, wavelengths_nm, axis, same_shape_ok=False)
    wavelengths_nm = _check_increasing(wavelengths_nm, 0)
    i0, i1, t, outside = _interpolation_weights(wavelengths_nm, new_wavelengths_nm, extrapolation)
    values = jnp.moveaxis(values, axis, -1)
    v0 = jnp.take(values, i0, axis=-1)  # shape values.shape[:-1] + new.shape
    v1 = jnp.take(values, i1, axis=-1)
    t = jnp.broadcast_to(t, v0.shape)
    out = (1.0 - t) * v0 + t * v1  # exact at both ends of each interval
    if outside is not None:
        out = jnp.where(jnp.broadcast_to(outside, out.shape), 0.0, out)
    # Put the new wavelength dimensions where the old axis was.
    batch, k = values.ndim - 1, new_wavelengths_nm.ndim
    return jnp.moveaxis(out, list(range(batch, batch + k)), list(range(axis, axis + k)))
