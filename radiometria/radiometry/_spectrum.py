r"""Spectra as callables: the `AbstractSpectrum` hierarchy (pbrt-v4's `Spectrum` classes).

A spectral power distribution (thesis section 1.5) or a spectral reflectance is a function of
wavelength. The renderer, the colorimetry and the RGB upsampling all need to evaluate such a
function at arbitrary wavelengths (at the hero wavelengths of a path, on a CMF grid), so every
spectrum of the package is an `equinox.Module` with one method, `__call__(wavelength_nm)`:

- `AbstractSpectrum`: the interface and its batching rule;
- `ConstantSpectrum`: a wavelength-independent value;
- `PiecewiseLinearSpectrum`: tabulated samples, linear in between, zero outside;
- `BlackbodySpectrum`: a scaled Planck spectrum (thesis eq. 1.24).

Elsewhere: `upsampling.SigmoidPolynomialSpectrum` and the RGB spectra
(`RGBAlbedoSpectrum`, `RGBUnboundedSpectrum`, `RGBIlluminantSpectrum`), and
`colorimetry.TabulatedSpectra` (the CIE tables) are members of the same hierarchy.

Batching rule. A spectrum object holds a batch of spectra, batch shape `(*batch,)` (the shape
of its parameters without their own trailing axes, e.g. `coeffs (*batch, 3)` or
`values (*batch, n)`). Wavelengths `(..., n_lambda)` are evaluated against every spectrum as
`broadcast((*batch, 1), (..., n_lambda))`: one spectrum on a grid gives `(n_lambda,)`, a batch
of `b` spectra on one grid gives `(b, n_lambda)`, and `b` spectra each at their own
wavelengths `(b, n_lambda)` give `(b, n_lambda)`. A scalar wavelength gives `(*batch,)`. The
broadcasting is explicit, so it also holds under `jax_numpy_rank_promotion="raise"`.
"""

import abc

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array
from ._planck import planck


def _common_float_dtype(*arrays: Array) -> np.dtype:
    """The float dtype the arrays combine to, ignoring weakly typed scalars (so that mixing a
    float32 table with float64 wavelengths works under strict dtype promotion)."""
    strong = [a.dtype for a in arrays if not getattr(a, "weak_type", False)]
    return np.result_type(*(strong or [a.dtype for a in arrays]))


def _pad(a: Array, rank: int) -> Array:
    """`a` with leading unit axes up to `rank` (NumPy broadcasting made explicit)."""
    return a.reshape((1,) * (rank - a.ndim) + a.shape)


def _output_shape(batch: tuple[int, ...], wavelength_nm: Array) -> tuple[int, ...]:
    """`broadcast((*batch, 1), wavelength_nm.shape)`, or a ValueError naming both shapes."""
    try:
        return tuple(np.broadcast_shapes(batch + (1,), wavelength_nm.shape))
    except ValueError:
        raise ValueError(
            f"`wavelength_nm` of shape {wavelength_nm.shape} does not broadcast against the "
            f"spectrum's batch shape {batch} (as {batch + (1,)}: the last axis of "
            f"`wavelength_nm` is the wavelength axis)."
        ) from None


def _is_concrete(x) -> bool:
    return not isinstance(x, jax.core.Tracer)


class AbstractSpectrum(eqx.Module):
    r"""A spectrum: a function from wavelength [nm] to a spectral value, batched.

    Subclasses hold their parameters as array fields (so a spectrum is a pytree that passes
    through `jax.jit`, `jax.vmap` and `jax.grad`) and implement `__call__`.

    **Calling:** `spectrum(wavelength_nm)` with wavelengths [nm] returns the values in the
    spectrum's unit (stated by each subclass: dimensionless for reflectances, W m^-2 sr^-1
    nm^-1 for radiances, relative for normalised illuminants).

    **Batching rule:** a spectrum with batch shape `(*batch,)` called with wavelengths of shape
    `(..., n_lambda)` returns shape `broadcast((*batch, 1), (..., n_lambda))`; with a scalar
    wavelength it returns `(*batch,)`. A subclass whose values carry a channel axis (the three
    colour-matching functions of `colorimetry.TabulatedSpectra`) appends it last and says so.

    The output dtype is the common float dtype of the wavelengths and the parameters (weakly
    typed Python floats follow the others).

    !!! note "Thesis"
        Thesis section 1.5 (the SPD); thesis section 2.2.3 (products of spectra in light
        transport).

    ??? cite "References"
        `Pharr2023` §4.5.1 (the `Spectrum` interface).
    """

    @abc.abstractmethod
    def __call__(self, wavelength_nm: ArrayLike) -> Array:
        """Spectral values at `wavelength_nm` [nm], shaped by the batching rule."""


class ConstantSpectrum(AbstractSpectrum):
    r"""A wavelength-independent spectrum, $S(\lambda) = c$.

    **Arguments:**

    - `value`: the constant $c$, a scalar or a batch `(*batch,)`. [the spectrum's unit, e.g.
        dimensionless for a grey reflectance or W m^-2 sr^-1 nm^-1 for a radiance]

    Calling with wavelengths `(..., n_lambda)` [nm] returns `value` broadcast to
    `broadcast((*batch, 1), (..., n_lambda))` (a scalar wavelength: `(*batch,)`), in the unit
    of `value`. The wavelengths are not checked: every wavelength has the same value.

    !!! note "Thesis"
        Thesis section 1.5 (a flat SPD, like the equal-energy illuminant E).

    ??? cite "References"
        `Pharr2023` §4.5.2 (`ConstantSpectrum`).
    """

    value: Float[Array, "*batch"]

    def __init__(self, value: ArrayLike):
        self.value = as_float_array(value, "value")

    def __call__(self, wavelength_nm: ArrayLike) -> Array:
        wl = as_float_array(wavelength_nm, "wavelength_nm")
        value = self.value.astype(_common_float_dtype(self.value, wl))
        if wl.ndim == 0:
            return value
        return jnp.broadcast_to(value[..., None], _output_shape(value.shape, wl))


class PiecewiseLinearSpectrum(AbstractSpectrum):
    r"""A tabulated spectrum: linear between the samples, zero outside the tabulated range.

    $$S(\lambda) = v_j + \frac{v_{j+1} - v_j}{\lambda_{j+1} - \lambda_j}(\lambda - \lambda_j)
      \quad\text{for } \lambda_j \le \lambda < \lambda_{j+1},\qquad
      S(\lambda) = 0 \text{ outside } [\lambda_0, \lambda_{n-1}]$$

    Zero outside is the convention of measured spectra, such as the Cornell box's: nothing is
    known there, and nothing is emitted or reflected. Evaluated eagerly (outside `jit`) the
    result is bit-identical to `numpy.interp(wavelength_nm, wavelengths_nm, values, left=0.0,
    right=0.0)`, which uses the same formula in the same order; under `jit`, XLA may fuse the
    multiply-add into one FMA, which can differ from it in the last bit.

    **Arguments:**

    - `wavelengths_nm`: (n,) sample wavelengths, n >= 2, strictly increasing (checked at
        construction when the values are concrete). [nm]
    - `values`: (*batch, n) samples: the last axis runs along `wavelengths_nm`, leading axes
        are a batch of spectra on the same grid. [the spectrum's unit]

    Calling with wavelengths `(..., n_lambda)` [nm] returns
    `broadcast((*batch, 1), (..., n_lambda))` values (a scalar wavelength: `(*batch,)`), in the
    unit of `values`. Differentiable in the wavelengths (the slope of the segment), in `values`
    and in `wavelengths_nm`.

    !!! note "Thesis"
        Thesis section 1.5 (a measured SPD); thesis section 2.2 (tabulated CMFs, illuminants).

    ??? cite "References"
        `Pharr2023` §4.5.2 (`PiecewiseLinearSpectrum`).
    """

    wavelengths_nm: Float[Array, " n"]
    values: Float[Array, "*batch n"]

    def __init__(self, wavelengths_nm: ArrayLike, values: ArrayLike):
        wl = as_float_array(wavelengths_nm, "wavelengths_nm")
        v = as_float_array(values, "values")
        if wl.ndim != 1 or wl.shape[0] < 2:
            raise ValueError(
                f"`wavelengths_nm` must be 1-D with at least 2 samples [nm], got shape {wl.shape}."
            )
        if v.ndim == 0 or v.shape[-1] != wl.shape[0]:
            raise ValueError(
                f"`values` must have shape (*batch, {wl.shape[0]}) (its last axis along "
                f"`wavelengths_nm`), got shape {v.shape}."
            )
        if not _is_concrete(wl):
            # Traced grid (under jit/vmap): the check runs with the computation.
            wl = eqx.error_if(
                wl,
                jnp.diff(wl) <= 0,
                "`wavelengths_nm` must be strictly increasing [nm]; got a step <= 0.",
            )
        self.wavelengths_nm = wl
        self.values = v

    def __check_init__(self):
        if _is_concrete(self.wavelengths_nm):
            wl = np.asarray(self.wavelengths_nm)
            if not np.all(np.diff(wl) > 0):
                raise ValueError(
                    "`wavelengths_nm` must be strictly increasing (and not NaN) [nm], got "
                    f"{wl.tolist() if wl.size <= 8 else wl}."
                )

    def __call__(self, wavelength_nm: ArrayLike) -> Array:
        x = as_float_array(wavelength_nm, "wavelength_nm")
        dtype = _common_float_dtype(x, self.wavelengths_nm, self.values)
        x, xp, fp = (a.astype(dtype) for a in (x, self.wavelengths_nm, self.values))
        scalar = x.ndim == 0
        if scalar:
            x = x[None]
        n = xp.shape[0]
        # The segment [xp[j], xp[j+1]] holding x: xp[j] <= x < xp[j+1] (NumPy's choice).
        j = jnp.clip(jnp.searchsorted(xp, x, side="right") - 1, 0, n - 2)
        # Slopes (*batch, n - 1). The grid steps are broadcast first: XLA rewrites a division
        # by a broadcast into a multiplication by a reciprocal, which rounds differently.
        df = jnp.diff(fp, axis=-1)
        slope = df / jnp.broadcast_to(jnp.diff(xp), df.shape)
        if fp.ndim == 1:
            s, v0, v_last = slope[j], fp[j], fp[-1]
        else:
            shape = _output_shape(fp.shape[:-1], x)
            x, j = jnp.broadcast_to(x, shape), jnp.broadcast_to(j, shape)
            rows = shape[:-1]
            s = jnp.take_along_axis(
                jnp.broadcast_to(_pad(slope, len(shape)), rows + (n - 1,)), j, axis=-1
            )
            fp = jnp.broadcast_to(_pad(fp, len(shape)), rows + (n,))
            v0, v_last = jnp.take_along_axis(fp, j, axis=-1), fp[..., -1:]
        # np.interp's formula and order of operations: slope * (x - x_j) + v_j, and the
        # last sample exactly at the right end.
        value = s * (x - xp[j]) + v0
        value = jnp.where(x == xp[-1], v_last, value)
        value = jnp.where((x < xp[0]) | (x > xp[-1]), 0.0, value)
        return value[..., 0] if scalar else value


class BlackbodySpectrum(AbstractSpectrum):
    r"""A blackbody's spectral radiance times a scale, $S(\lambda) = s\,L_{bb,\lambda}(\lambda, T)$.

    $$L_{bb,\lambda}(\lambda, T) = \frac{2 h c^2}{\lambda^5\left(e^{hc/(\lambda k T)} - 1\right)}$$

    evaluated by `radiometry.planck` (so with `scale = 1` it equals `planck(wavelength_nm,
    temperature)` exactly). Unlike pbrt's `BlackbodySpectrum` it is not normalised to a peak of
    1: `scale` is explicit, and the unit is the radiance's.

    **Arguments:**

    - `temperature`: thermodynamic temperature, > 0, a scalar or a batch `(*batch,)` (checked
        at construction when concrete; `planck` checks it again under `jit`). [K]
    - `scale`: a factor, broadcasting with `temperature`; default 1. [dimensionless]

    Calling with wavelengths `(..., n_lambda)`, > 0 [nm], returns the spectral radiance of shape
    `broadcast((*batch, 1), (..., n_lambda))` (a scalar wavelength: `(*batch,)`).
    [W m^-2 sr^-1 nm^-1] Differentiable in `temperature`, `scale` and the wavelengths.

    !!! note "Thesis"
        Thesis eq. (1.24), section 1.5.

    ??? cite "References"
        `Planck1901`; `Pharr2023` §4.4.1 (Planck's law) and §4.5.2 (`BlackbodySpectrum`).
    """

    temperature: Float[Array, "*batch"]
    scale: Float[Array, "..."]  # broadcasts with `temperature`

    def __init__(self, temperature: ArrayLike, scale: ArrayLike = 1.0):
        t = as_float_array(temperature, "temperature")
        s = as_float_array(scale, "scale")
        try:
            np.broadcast_shapes(t.shape, s.shape)
        except ValueError:
            raise ValueError(
                f"`scale` of shape {s.shape} does not broadcast with `temperature` of shape "
                f"{t.shape}."
            ) from None
        self.temperature = t
        self.scale = s

    def __check_init__(self):
        if _is_concrete(self.temperature):
            t = np.asarray(self.temperature)
            if np.any(t <= 0):
                raise ValueError(
                    f"`temperature` must be > 0 [K], got {t.tolist() if t.size <= 8 else t}."
                )

    def __call__(self, wavelength_nm: ArrayLike) -> Array:
        wl = as_float_array(wavelength_nm, "wavelength_nm")
        dtype = _common_float_dtype(wl, self.temperature, self.scale)
        wl, t, s = (a.astype(dtype) for a in (wl, self.temperature, self.scale))
        if wl.ndim == 0:
            radiance = planck(wl, t)
        else:
            # A readable error for mismatched batch shapes (before planck's own).
            _output_shape(tuple(np.broadcast_shapes(t.shape, s.shape)), wl)
            radiance = planck(wl, t[..., None])
            s = s[..., None]
        rank = max(s.ndim, radiance.ndim)
        return _pad(s, rank) * _pad(radiance, rank)
