r"""The sigmoid-polynomial spectrum of Jakob & Hanika (thesis eq. 2.25-2.26).

$$S(\lambda) = s(c_0\lambda^2 + c_1\lambda + c_2),\qquad s(x) = \tfrac12 + \frac{x}{2\sqrt{1+x^2}}$$

Coefficients come in two conventions:

- **nm coefficients** (pbrt, Mitsuba, the thesis's figure 2.4 and the tables this package
  writes): the polynomial is evaluated at the wavelength in nanometres;
- **normalised coefficients** (what the fitter solves for, as pbrt's `rgb2spec_opt` does):
  the polynomial is evaluated at $\lambda' = (\lambda - 360)/(830 - 360)$, which keeps the
  three unknowns of similar magnitude and the Gauss-Newton normal equations well conditioned.

`normalised_to_nm_coefficients` / `nm_to_normalised_coefficients` convert exactly between them
(a linear change of variable of a quadratic).
"""

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_last_axis
from ..constants import VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM
from ..radiometry import AbstractSpectrum

# Normalised wavelength lambda' = (lambda - lambda_min) / (lambda_max - lambda_min) over the
# visible range of `radiometria.constants` (the CIE 1931 tables' and the fit's).


def common_float_dtype(*arrays) -> np.dtype:
    """The float dtype two or more arrays combine to, ignoring weakly typed scalars.

    Used instead of implicit promotion, so that mixing a float32 table with float64
    wavelengths works under `jax_numpy_dtype_promotion="strict"` (style.md section 10).
    """
    strong = [a.dtype for a in arrays if not getattr(a, "weak_type", False)]
    if not strong:
        strong = [a.dtype for a in arrays]
    return np.result_type(*strong)


@jax.custom_jvp
def _sigmoid(x: Array) -> Array:
    # s(-|x|) = 1/2 - |x| / (2 r) = 1 / (2 r (r + |x|)) with r = sqrt(1 + x^2): no cancellation,
    # full relative precision in the lower tail (dark spectra) and exact limits 0 and 1 for
    # x -> -inf / +inf (r overflows to inf and the quotient to 0).
    ax = jnp.abs(x)
    r = jnp.sqrt(1.0 + ax * ax)
    t = 0.5 / (r * (r + ax))
    return jnp.where(x < 0, t, 1.0 - t)


@_sigmoid.defjvp
def _sigmoid_jvp(primals, tangents):
    (x,), (dx,) = primals, tangents
    # s'(x) = 1 / (2 (1 + x^2)^(3/2)); 0 (not NaN) for |x| -> inf.
    ax = jnp.abs(x)
    r = jnp.sqrt(1.0 + ax * ax)
    return _sigmoid(x), dx * (0.5 / (r * r * r))


def sigmoid_jakob2019(x: ArrayLike) -> Array:
    r"""The algebraic sigmoid $s(x) = \tfrac12 + x / (2\sqrt{1+x^2})$ (thesis eq. 2.26).

    Evaluated in a stable form: $s(-|x|) = 1/(2r(r+|x|))$ with $r = \sqrt{1+x^2}$ and
    $s(x) = 1 - s(-x)$, so small values keep their relative precision, `+inf` gives exactly 1,
    `-inf` exactly 0, and the derivative $s'(x) = \tfrac12 (1+x^2)^{-3/2}$ is finite
    everywhere (0 at infinity).

    **Arguments:**

    - `x`: any real array. [dimensionless]

    **Returns:**

    $s(x)$ in [0, 1], same shape and dtype. [dimensionless]

    !!! note "Thesis"
        Eq. 2.26, section 2.2.3.

    ??? cite "References"
        `Jakob2019` eq. 3; `Pharr2023` section 4.6.6 (`SigmoidPolynomial`).
    """
    return _sigmoid(as_float_array(x, "x"))


def grey_coefficients(value: Array) -> Array:
    r"""Normalised (and nm) coefficients of the flat spectrum $S = v$: $(0, 0, x)$ with
    $s(x) = v$, i.e. $x = (v - 1/2)/\sqrt{v(1-v)}$; $\pm\infty$ for $v = 1$ / $v = 0$ (pbrt)."""
    v = value
    inner = v * (1.0 - v)
    safe = jnp.where(inner > 0, inner, 1.0)
    x = jnp.where(inner > 0, (v - 0.5) / jnp.sqrt(safe), jnp.where(v >= 1.0, jnp.inf, -jnp.inf))
    zero = jnp.zeros_like(x)
    return jnp.stack([zero, zero, x], axis=-1)


def _as_coeffs(coeffs, name: str = "coeffs") -> Array:
    return check_last_axis(as_float_array(coeffs, name), name, 3)


def _evaluate(coeffs: Array, wavelength: Array) -> Array:
    """s(c0 l^2 + c1 l + c2) with the coefficient batch (*b, 3) against wavelengths (..., n)."""
    dtype = common_float_dtype(coeffs, wavelength)
    c = coeffs.astype(dtype)
    lam = wavelength.astype(dtype)
    scalar = lam.ndim == 0
    if scalar:
        lam = lam[None]
    c0, c1, c2 = c[..., 0:1], c[..., 1:2], c[..., 2:3]
    # Explicit broadcasting (rank promotion may be disabled): pad both to the same rank.
    rank = max(c0.ndim, lam.ndim)
    c0, c1, c2 = (a.reshape((1,) * (rank - a.ndim) + a.shape) for a in (c0, c1, c2))
    lam = lam.reshape((1,) * (rank - lam.ndim) + lam.shape)
    x = (c0 * lam + c1) * lam + c2  # Horner, as pbrt's EvaluatePolynomial
    s = _sigmoid(x)
    return s[..., 0] if scalar else s


def sigmoid_polynomial_jakob2019(coeffs: ArrayLike, wavelength_nm: ArrayLike) -> Array:
    r"""Evaluate $S(\lambda) = s(c_0\lambda^2 + c_1\lambda + c_2)$ with nm coefficients.

    **Arguments:**

    - `coeffs`: (*batch, 3) coefficients $(c_0, c_1, c_2)$ for $\lambda$ in nm.
        [nm^-2, nm^-1, dimensionless]
    - `wavelength_nm`: wavelengths, shape (..., n_lambda) broadcasting against
        `(*batch, 1)`, or a scalar. [nm]

    **Returns:**

    Spectrum values in [0, 1], shape `broadcast((*batch, 1), wavelength_nm.shape)` (the last
    axis dropped for a scalar wavelength). [dimensionless]

    !!! note "Thesis"
        Eq. 2.25-2.26, section 2.2.3.

    ??? cite "References"
        `Jakob2019` eq. 3; `Pharr2023` section 4.6.6.
    """
    c = _as_coeffs(coeffs)
    wl = as_float_array(wavelength_nm, "wavelength_nm")
    return _evaluate(c, wl)


def normalised_to_nm_coefficients(coeffs: ArrayLike) -> Array:
    r"""Convert coefficients of the normalised wavelength to nm coefficients.

    With $\lambda' = (\lambda - a) b$, $a = 360$ nm, $b = 1/470$ nm^-1, the polynomial
    $A\lambda'^2 + B\lambda' + C$ equals $c_0\lambda^2 + c_1\lambda + c_2$ for
    $c_0 = A b^2$, $c_1 = B b - 2 A a b^2$, $c_2 = C - B a b + A (a b)^2$ (the conversion of
    pbrt's `rgb2spec_opt`).

    **Arguments:**

    - `coeffs`: (..., 3) coefficients $(A, B, C)$ of $\lambda'$. [dimensionless]

    **Returns:**

    (..., 3) nm coefficients $(c_0, c_1, c_2)$. [nm^-2, nm^-1, dimensionless]

    !!! note "Thesis"
        Eq. 2.25, section 2.2.3.

    ??? cite "References"
        `Jakob2019` section 4; `Pharr2023` section 4.6.6.
    """
    c = _as_coeffs(coeffs)
    a, b = VISIBLE_WAVELENGTH_MIN_NM, 1.0 / (VISIBLE_WAVELENGTH_MAX_NM - VISIBLE_WAVELENGTH_MIN_NM)
    A, B, C = c[..., 0], c[..., 1], c[..., 2]
    return jnp.stack([A * b * b, B * b - 2.0 * A * a * b * b, C - B * a * b + A * (a * b) ** 2], -1)


def nm_to_normalised_coefficients(coeffs: ArrayLike) -> Array:
    r"""Convert nm coefficients to coefficients of $\lambda' = (\lambda - 360)/470$.

    The exact inverse of `normalised_to_nm_coefficients`: with $\lambda = a + \lambda'/b$,
    $A = c_0 / b^2$, $B = (2 c_0 a + c_1)/b$, $C = c_0 a^2 + c_1 a + c_2$.

    **Arguments:**

    - `coeffs`: (..., 3) nm coefficients. [nm^-2, nm^-1, dimensionless]

    **Returns:**

    (..., 3) normalised coefficients. [dimensionless]

    !!! note "Thesis"
        Eq. 2.25, section 2.2.3.

    ??? cite "References"
        `Jakob2019` section 4.
    """
    c = _as_coeffs(coeffs)
    a, b = VISIBLE_WAVELENGTH_MIN_NM, 1.0 / (VISIBLE_WAVELENGTH_MAX_NM - VISIBLE_WAVELENGTH_MIN_NM)
    c0, c1, c2 = c[..., 0], c[..., 1], c[..., 2]
    return jnp.stack([c0 / (b * b), (2.0 * c0 * a + c1) / b, (c0 * a + c1) * a + c2], -1)


class SigmoidPolynomialSpectrum(AbstractSpectrum):
    r"""The spectrum $S(\lambda) = s(c_0\lambda^2 + c_1\lambda + c_2)$, bounded in [0, 1].

    A `radiometry.AbstractSpectrum` holding nm coefficients, so batches of spectra are one
    object with `coeffs` of shape (*batch, 3). Calling it evaluates the stable sigmoid
    (`sigmoid_jakob2019`): `coeffs[..., 2] = +inf` with `c0 = c1 = 0` is the constant 1 and
    `-inf` the constant 0.

    **Fields:**

    - `coeffs`: (*batch, 3) nm coefficients. [nm^-2, nm^-1, dimensionless]

    Calling with `wavelength_nm` of shape (..., n_lambda) returns
    `broadcast((*batch, 1), (..., n_lambda))` values in [0, 1], [dimensionless].

    !!! note "Thesis"
        Eq. 2.25-2.26 and figure 2.4, section 2.2.3.

    ??? cite "References"
        `Jakob2019`; `Pharr2023` section 4.6.6 (`RGBSigmoidPolynomial`).
    """

    coeffs: Float[Array, "*batch 3"]

    def __init__(self, coeffs: ArrayLike):
        self.coeffs = _as_coeffs(coeffs)

    def __call__(self, wavelength_nm: ArrayLike) -> Array:
        return _evaluate(self.coeffs, as_float_array(wavelength_nm, "wavelength_nm"))

    def max_value(self) -> Array:
        """The maximum of the spectrum over [360, 830] nm (pbrt's `MaxValue`). [dimensionless]

        The sigmoid is increasing, so the maximum is at an end of the range or at the vertex of
        the parabola; a clipped vertex lies inside the range, so taking the largest of the three
        is exact whatever the sign of $c_0$.
        """
        c = self.coeffs
        c0, c1 = c[..., 0], c[..., 1]
        lo = jnp.full(c0.shape, VISIBLE_WAVELENGTH_MIN_NM, c.dtype)
        hi = jnp.full(c0.shape, VISIBLE_WAVELENGTH_MAX_NM, c.dtype)
        vertex = jnp.clip(-c1 / (2.0 * jnp.where(c0 == 0, 1.0, c0)), lo, hi)
        lam = jnp.stack([lo, hi, vertex], -1)
        x = (c[..., 0:1] * lam + c[..., 1:2]) * lam + c[..., 2:3]
        return _sigmoid(jnp.max(x, axis=-1))


def _normalised_to_nm_np(c: np.ndarray) -> np.ndarray:
    """NumPy twin of `normalised_to_nm_coefficients` (host-side post-processing)."""
    a = VISIBLE_WAVELENGTH_MIN_NM
    b = 1.0 / (VISIBLE_WAVELENGTH_MAX_NM - VISIBLE_WAVELENGTH_MIN_NM)
    A, B, C = c[..., 0], c[..., 1], c[..., 2]
    return np.stack([A * b * b, B * b - 2.0 * A * a * b * b, C - B * a * b + A * (a * b) ** 2], -1)


def _nm_to_normalised_np(c: np.ndarray) -> np.ndarray:
    """NumPy twin of `nm_to_normalised_coefficients` (host-side, float64 without x64)."""
    a = VISIBLE_WAVELENGTH_MIN_NM
    w = VISIBLE_WAVELENGTH_MAX_NM - VISIBLE_WAVELENGTH_MIN_NM
    A, B, C = c[..., 0], c[..., 1], c[..., 2]
    return np.stack([A * w * w, (B + 2.0 * A * a) * w, C + B * a + A * a * a], -1)
