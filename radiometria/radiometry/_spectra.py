"""Sampled spectra: integration and resampling on (possibly irregular) nanometre grids.

Spectral densities are per nm and grids are in nm (style.md section 4), so the trapezoid
integral of a spectral radiance over its grid is a radiance, with no unit factor.
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_choice, check_wavelength_grid
from .._math import interpolation_weights

EXTRAPOLATIONS = ("zero", "constant")


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
    axis = check_wavelength_grid(values, wavelengths_nm, axis, same_shape_ok=True)
    values = jnp.moveaxis(values, axis, -1)
    if wavelengths_nm.ndim == 1:
        wavelengths_nm = _check_increasing(wavelengths_nm, 0)
    else:
        wavelengths_nm = _check_increasing(jnp.moveaxis(wavelengths_nm, axis, -1), -1)
    step = jnp.diff(wavelengths_nm, axis=-1)
    step = jnp.broadcast_to(step, values.shape[:-1] + step.shape[-1:])
    return 0.5 * jnp.sum(step * (values[..., 1:] + values[..., :-1]), axis=-1)


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
    axis = check_wavelength_grid(values, wavelengths_nm, axis, same_shape_ok=False)
    wavelengths_nm = _check_increasing(wavelengths_nm, 0)
    i0, i1, t, outside = interpolation_weights(wavelengths_nm, new_wavelengths_nm, extrapolation)
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
