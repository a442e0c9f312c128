r"""The fit of thesis eq. 2.27: sigmoid-polynomial coefficients reproducing an RGB colour.

$$c^* = \arg\min_c \big\| \mathrm{Lab}(M\,\mathrm{rgb}) -
  \mathrm{Lab}\big(\textstyle\sum_i S(\lambda_i; c)\, W_i\big) \big\|^2$$

with $W$ the forward model's reflectance -> XYZ weights (`_forward.py`), CIELAB relative to
the colour space's white, and the polynomial in the normalised wavelength
$\lambda' = (\lambda - 360)/470$ (pbrt's `rgb2spec_opt` does the same). The residual is the
CIE 1976 colour difference $\Delta E^*_{ab}$ (the thesis's norm).

Two solvers share this residual:

- `fit_rgb`, the reference: `optimistix.least_squares` with `optimistix.LevenbergMarquardt`
  (or any optimistix least-squares solver), Jacobians by JAX autodiff, a full
  `optimistix.RESULTS` per colour;
- `lm_step` / `lm_iterate` / `lm_solve` (in `_lm.py`, importable without optimistix): the
  table builder's inner solver and the wide-gamut lookups' refinement, a hand-written damped
  Gauss-Newton (Levenberg-Marquardt with Marquardt's diagonal scaling) for millions of
  colours at once, with a fixed number of iterations inside `lax.fori_loop`, a closed-form
  3x3 solve, and the exact Jacobian: the sigmoid's derivative by `jax.jvp`, the linear
  quadrature and polynomial parts folded into precomputed (n, 9) moment weights, and the
  CIELAB Jacobian by `jax.jacfwd`. A test checks it against `jax.jacfwd` of the plain
  residual. Each entry reports whether it reached the tolerance.

All of them use the same forward model, the one the renderer's colorimetry uses.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_last_axis
from ._forward import XYZ_to_Lab_white, forward_model
from ._lm import (
    DEFAULT_TOLERANCE as DEFAULT_TOLERANCE,
    LMState as LMState,
    ModelArrays as ModelArrays,
    lm_init as lm_init,
    lm_iterate as lm_iterate,
    lm_retarget as lm_retarget,
    lm_solve as lm_solve,
    lm_step as lm_step,
    model_XYZ as model_XYZ,
    residual as residual,
    residual_and_jacobian as residual_and_jacobian,
    target_Lab as target_Lab,
)
from ._lut import _check_rgb_values as _check_rgb_values
from ._sigmoid_polynomial import (
    grey_coefficients as grey_coefficients,
    normalised_to_nm_coefficients,
)

# --- The reference solver: optimistix -------------------------------------------------------


class FitResult(eqx.Module):
    """Result of `fit_rgb` for a batch of colours.

    - `coeffs` (..., 3): nm coefficients (pbrt / thesis convention). [nm^-2, nm^-1, -]
    - `coeffs_normalised` (..., 3): coefficients of $\\lambda' = (\\lambda-360)/470$. [-]
    - `residual` (...,): $\\Delta E^*_{ab}$ between target and reproduction. [-]
    - `result`: `optimistix.RESULTS` per colour (`successful` or why not).
    - `num_steps` (...,): solver steps taken.
    """

    coeffs: Array
    coeffs_normalised: Array
    residual: Array
    result: optx.RESULTS
    num_steps: Array


@eqx.filter_jit
def _fit_rgb_jit(rgb, y0, m, solver, max_steps):
    def one(rgb1, y01):
        grey = (rgb1[0] == rgb1[1]) & (rgb1[1] == rgb1[2])
        # Greys have the closed form; the solver runs on a harmless stand-in there.
        rgb_s = jnp.where(grey, jnp.asarray([0.4, 0.5, 0.6], rgb1.dtype), rgb1)
        lab_t = target_Lab(rgb_s, m)
        fn = lambda c, args: XYZ_to_Lab_white(model_XYZ(c, m), m.white) - lab_t  # noqa: E731
        sol = optx.least_squares(fn, solver, y01, max_steps=max_steps, throw=False)
        c = jnp.where(grey, grey_coefficients(rgb1[0]), sol.value)
        r = XYZ_to_Lab_white(model_XYZ(c, m), m.white) - target_Lab(rgb1, m)
        res = optx.RESULTS.where(grey, optx.RESULTS.successful, sol.result)
        return c, jnp.sqrt(jnp.sum(r * r)), res, sol.stats["num_steps"]

    return jax.vmap(one)(rgb, y0)


def fit_rgb(
    rgb: Float[ArrayLike, "*batch 3"],
    colourspace="sRGB",
    *,
    y0: ArrayLike | None = None,
    solver: optx.AbstractLeastSquaresSolver | None = None,
    max_steps: int = 512,
    throw: bool = True,
    step_nm: float = 1.0,
) -> FitResult:
    r"""Fit sigmoid-polynomial coefficients to linear RGB colours directly (thesis eq. 2.27).

    The reference for the coefficient table: one `optimistix.least_squares` solve per colour
    (vectorised with `vmap`), Levenberg-Marquardt by default, the Jacobian by JAX autodiff, the
    residual in CIELAB. Greys use the closed form $c = (0, 0, (v-\tfrac12)/\sqrt{v(1-v)})$,
    which is exact (black $\to -\infty$, white $\to +\infty$, evaluated as 0 and 1).

    **Arguments:**

    - `rgb`: linear RGB (..., 3) of the colour space, components in [0, 1]. [-]
    - `colourspace`: name of a space of `colorimetry.RGB_COLOURSPACES`.
    - `y0`: starting normalised coefficients (..., 3); default (0, 0, 0) (S = 1/2). [-]
    - `solver`: an optimistix least-squares solver; default
        `optx.LevenbergMarquardt(rtol=1e-10, atol=1e-10)` (`GaussNewton` works too).
    - `max_steps`: solver step limit.
    - `throw`: raise if any colour failed (optimistix's convention); else see `result`.
    - `step_nm`: quadrature step of the forward model. [nm]

    **Returns:**

    A `FitResult`; `residual` is $\Delta E^*_{ab}$ of the reproduction.

    !!! note "Thesis"
        Eq. 2.25-2.27, section 2.2.3; Gauss-Newton, appendix C.1.

    ??? cite "References"
        `Jakob2019` section 4; `Pharr2023` section 4.6.6; `Rader2024` (optimistix).
    """
    rgb = check_last_axis(as_float_array(rgb, "rgb"), "rgb", 3)
    _check_rgb_values(rgb)
    model = forward_model(colourspace, step_nm=step_nm)
    dtype = rgb.dtype
    m = ModelArrays.build(model, dtype)
    batch = rgb.shape[:-1]
    flat = rgb.reshape(-1, 3)
    if y0 is None:
        y0f = jnp.zeros_like(flat)
    else:
        y0f = jnp.broadcast_to(as_float_array(y0, "y0").astype(dtype), rgb.shape).reshape(-1, 3)
    if solver is None:
        solver = optx.LevenbergMarquardt(rtol=1e-10, atol=1e-10)
    c, res, result, steps = _fit_rgb_jit(flat, y0f, m, solver, max_steps)
    if throw:
        failed = np.asarray(result._value != optx.RESULTS.successful._value)
        if failed.any():
            idx = int(np.flatnonzero(failed)[0])
            raise RuntimeError(
                f"fit_rgb: {int(failed.sum())} of {failed.size} colours did not converge; the "
                f"first is rgb={np.asarray(flat[idx]).tolist()} (residual "
                f"{float(res[idx]):.3g} Delta E*ab). Pass throw=False to inspect `result`."
            )
    return FitResult(
        coeffs=normalised_to_nm_coefficients(c).reshape(batch + (3,)),
        coeffs_normalised=c.reshape(batch + (3,)),
        residual=res.reshape(batch),
        result=jax.tree_util.tree_map(lambda a: a.reshape(batch), result),
        num_steps=steps.reshape(batch),
    )
