"""Validation helpers for the three error tiers of style.md section 9.

- *static* checks (`as_float_array`, `check_choice`, `check_last_axis`, `check_broadcastable`,
  `check_positive_int`, `check_axis`, `check_wavelength_grid`) raise `TypeError`/`ValueError`
  at call or trace time;
- *value* checks (`check_positive`, `check_in_range`, `check_unit_interval`) go through
  `equinox.error_if`, so they also fire under `jax.jit` (as `equinox.EquinoxRuntimeError`),
  and are controlled by the `EQX_ON_ERROR` environment variable.

Every message names the argument, the offending value (or its range) and what is valid, with the
unit in brackets.
"""

from collections.abc import Iterable, Mapping

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

__all__ = [
    "as_float_array",
    "check_axis",
    "check_broadcastable",
    "check_choice",
    "check_finite",
    "check_in_range",
    "check_last_axis",
    "check_positive",
    "check_positive_int",
    "check_unit_interval",
    "check_wavelength_grid",
    "device_array",
    "lookup",
]


def device_array(x, dtype=None) -> Array:
    """`jnp.asarray(x, dtype)` without compiling anything for host values.

    Eagerly, `jnp.asarray` of a NumPy array or a Python scalar runs a compiled identity
    program (`lax.stage`; with a cast, `convert_element_type`), one per shape and dtype: about
    10 ms each on a first run (jax 0.10), and a scene's setup converts some forty arrays.
    NumPy arrays and scalars, Python scalars and flat lists of those here go to the default
    device by `jax.device_put` (NumPy casts to `dtype` first), with the dtype (JAX's canonical one:
    float32 unless `jax_enable_x64`) and weak type `jnp.asarray` would give; anything else
    (JAX arrays, tracers, sequences that may hold them) goes through `jnp.asarray`.
    """
    host = (np.ndarray, np.generic, bool, int, float)
    if not isinstance(x, host) and not (
        isinstance(x, list | tuple) and all(isinstance(e, host) for e in x)
    ):
        return jnp.asarray(x, dtype)
    if dtype is None and isinstance(x, bool | int | float) and not isinstance(x, np.generic):
        return jax.device_put(x)  # weakly typed, like jnp.asarray
    if dtype is not None:
        dtype = jax.dtypes.canonicalize_dtype(dtype)
    return jax.device_put(np.asarray(x, dtype))


def as_float_array(x, name: str) -> Array:
    """Convert `x` to a floating JAX array, refusing integer, boolean and complex input.

    Python scalars become weakly typed arrays, so they follow the dtype of other operands.
    Integer *arrays* are rejected rather than silently cast: a wavelength grid of ints usually
    means a caller forgot a unit conversion, and strict dtype promotion would fail later anyway.
    """
    if isinstance(x, bool):
        raise TypeError(f"`{name}` must be a real floating-point value, got bool {x!r}.")
    if isinstance(x, int | float):
        return device_array(float(x))
    dtype = getattr(x, "dtype", None)
    if dtype is None:
        arr = np.asarray(x)
        dtype = arr.dtype
        if dtype.kind in "iu" and arr.ndim > 0:
            raise TypeError(
                f"`{name}` must be a floating-point array, got dtype {dtype} "
                f"(convert explicitly, e.g. `np.asarray(x, float)`)."
            )
        if dtype.kind == "O":
            raise TypeError(f"`{name}` must be numeric, got {type(x).__name__}.")
        x = arr
    if jnp.issubdtype(dtype, jnp.floating):
        return device_array(x)
    if jnp.issubdtype(dtype, jnp.integer) and getattr(x, "ndim", 1) == 0:
        return jnp.asarray(x, dtype=jnp.result_type(float))
    raise TypeError(
        f"`{name}` must be a floating-point array, got dtype {dtype} "
        f"(convert explicitly, e.g. `x.astype(float)`)."
    )


def check_positive(x: Array, name: str, unit: str = "") -> Array:
    """Value check: every element of `x` must be > 0 (NaN passes and propagates)."""
    u = f" [{unit}]" if unit else ""
    return eqx.error_if(x, x <= 0, f"`{name}` must be > 0{u}; got a value <= 0.")


def check_finite(x: Array, name: str) -> Array:
    """Value check: every element of `x` must be finite."""
    return eqx.error_if(x, ~jnp.isfinite(x), f"`{name}` must be finite; got NaN or inf.")


def check_in_range(
    x: Array,
    name: str,
    lower: float,
    upper: float,
    *,
    unit: str = "",
    closed_lower: bool = True,
    closed_upper: bool = True,
) -> Array:
    """Value check: every element of `x` must lie in the given interval (NaN passes)."""
    below = x < lower if closed_lower else x <= lower
    above = x > upper if closed_upper else x >= upper
    lb = "[" if closed_lower else "("
    ub = "]" if closed_upper else ")"
    u = f" [{unit}]" if unit else ""
    return eqx.error_if(
        x, below | above, f"`{name}` must lie in {lb}{lower}, {upper}{ub}{u}; got a value outside."
    )


def check_unit_interval(u: Array, name: str = "u") -> Array:
    """Value check for uniform variates: every element must lie in [0, 1)."""
    return check_in_range(u, name, 0.0, 1.0, closed_upper=False)


def check_positive_int(n, name: str, *, minimum: int = 1) -> int:
    """Static check: `n` must be a Python (or NumPy) integer >= `minimum`."""
    if isinstance(n, bool) or not isinstance(n, int | np.integer):
        raise TypeError(f"`{name}` must be an int, got {type(n).__name__} {n!r}.")
    if n < minimum:
        raise ValueError(f"`{name}` must be >= {minimum}, got {n}.")
    return int(n)


def check_choice(value: str, name: str, valid: Iterable[str]) -> str:
    """Static check: `value` must be one of `valid`; the message lists the valid names."""
    valid = list(valid)
    if value not in valid:
        raise ValueError(
            f"Unknown {name} {value!r}; valid values are: {', '.join(map(repr, valid))}."
        )
    return value


def lookup(mapping: Mapping, key: str, name: str):
    """`mapping[key]`, or a `ValueError` naming `name` and listing the valid keys."""
    check_choice(key, name, mapping.keys())
    return mapping[key]


def check_last_axis(x: Array, name: str, size: int) -> Array:
    """Static check: the last axis of `x` must have length `size` (channels are last)."""
    if x.ndim == 0 or x.shape[-1] != size:
        raise ValueError(f"`{name}` must have a last axis of length {size}, got shape {x.shape}.")
    return x


def check_broadcastable(*named: tuple[str, Array]) -> tuple[int, ...]:
    """Static check: the shapes of the named arrays broadcast together; returns the result shape."""
    try:
        return tuple(np.broadcast_shapes(*(jnp.shape(a) for _, a in named)))
    except ValueError:
        desc = ", ".join(f"`{n}` {jnp.shape(a)}" for n, a in named)
        raise ValueError(f"Shapes do not broadcast: {desc}.") from None


def check_axis(axis: int, ndim: int, name: str) -> int:
    """Static check: `axis` is an int valid for `ndim` dimensions; returns it in [0, ndim)."""
    if isinstance(axis, bool) or not isinstance(axis, int):
        raise TypeError(f"`axis` must be an int, got {type(axis).__name__} {axis!r}.")
    if not -ndim <= axis < ndim:
        raise ValueError(f"`axis` {axis} is out of range for `{name}` with {ndim} dimension(s).")
    return axis % ndim


def check_wavelength_grid(
    values: Array, wavelengths_nm: Array, axis: int, *, same_shape_ok: bool
) -> int:
    """Static checks of a spectrum `values` sampled on `wavelengths_nm` along `axis`.

    The grid is 1-D with `values.shape[axis]` samples (or, if `same_shape_ok`, the shape of
    `values`), with at least 2 samples. Returns the axis normalised to [0, ndim).
    """
    if values.ndim == 0:
        raise ValueError("`values` must have at least one dimension (the wavelength axis).")
    axis = check_axis(axis, values.ndim, "values")
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
