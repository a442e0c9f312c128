r"""Absorption, scattering and extinction coefficients (thesis section 1.3, eq. 1.11-1.12).

A participating medium absorbs light at the rate $\sigma_a$ (the thesis's $\kappa_a$, the
*absorption coefficient*) and scatters it at the rate $\sigma_s$, both per unit length; the
*extinction coefficient* $\sigma_t = \sigma_a + \sigma_s$ is the rate at which light leaves a
beam, and the *single-scattering albedo* $\varrho = \sigma_s/\sigma_t$ the probability that an
interaction scatters rather than absorbs. Along a segment the *optical depth*
$\tau = \int_0^d \sigma_t(\mathbf o + t\boldsymbol\omega)\,\mathrm dt$ gives the transmittance
$T = e^{-\tau}$ (Beer-Lambert, eq. 1.12, with $\sigma_t$ in place of $\kappa_a$), and the
*penetration depth* $1/\sigma_t$ is where $T = 1/e$.

The same absorption has a wave description (section 1.3): a complex wavenumber
$\underline k = k + i\kappa_a/2$, whose imaginary part damps the field as $e^{-\kappa_a z/2}$ so
the intensity decays as $e^{-\kappa_a z}$ (eq. 1.11-1.12), and a complex refractive index
$\underline\eta = \underline k/k_0 = \eta + i\kappa$ with the *absorption index*
$\kappa = \kappa_a/(2k_0)$, $k_0 = 2\pi/\lambda_0$ (`radiometry.wavenumber_vacuum`, eq. 1.5).

Coefficients are per metre here (SI); the renderer reads them per scene unit. Wavelengths are
in nm.
"""

import math
from collections.abc import Callable

import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array, Complex, Float

from .._checks import as_float_array, check_in_range, check_last_axis, check_positive_int
from .._math import align_ranks, safe_div
from .._types import FloatLike
from ..radiometry import wavenumber_vacuum


def _nonneg(x, name: str, unit: str) -> Array:
    return check_in_range(as_float_array(x, name), name, 0.0, math.inf, unit=unit)


def extinction_coefficient(sigma_a: FloatLike, sigma_s: FloatLike) -> Float[Array, "..."]:
    r"""Extinction (attenuation) coefficient $\sigma_t = \sigma_a + \sigma_s$.

    **Arguments:**

    - `sigma_a`: absorption coefficient $\sigma_a$ (the thesis's $\kappa_a$), >= 0. [m^-1]
    - `sigma_s`: scattering coefficient $\sigma_s$, >= 0. [m^-1]

    **Returns:**

    $\sigma_t$, broadcast over the inputs. [m^-1]

    !!! note "Thesis"
        Section 1.3 ($\kappa_a$); chapter 4 (energy transport in a medium; title only).

    ??? cite "References"
        `Pharr2023` §11.1; `Chandrasekhar1960` §1.
    """
    a, s = align_ranks(_nonneg(sigma_a, "sigma_a", "m^-1"), _nonneg(sigma_s, "sigma_s", "m^-1"))
    return a + s


def single_scattering_albedo(sigma_s: FloatLike, sigma_t: FloatLike) -> Float[Array, "..."]:
    r"""Single-scattering albedo $\varrho = \sigma_s/\sigma_t$.

    **Arguments:**

    - `sigma_s`: scattering coefficient, >= 0. [m^-1]
    - `sigma_t`: extinction coefficient, >= `sigma_s`. [m^-1]

    **Returns:**

    $\varrho$ in [0, 1]; 0 where $\sigma_t = 0$ (a vacuum neither scatters nor absorbs), with
    finite gradients there. [dimensionless]

    !!! note "Thesis"
        Chapter 4 (energy transport in a medium; title only in the text).

    ??? cite "References"
        `Pharr2023` §11.1.4; `Chandrasekhar1960` §1.
    """
    s, t = align_ranks(_nonneg(sigma_s, "sigma_s", "m^-1"), _nonneg(sigma_t, "sigma_t", "m^-1"))
    return safe_div(s, t)


def coefficients_from_albedo(
    sigma_t: FloatLike, albedo: FloatLike
) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
    r"""Absorption and scattering coefficients from extinction and albedo, the inverse of
    `extinction_coefficient` and `single_scattering_albedo`:
    $\sigma_s = \varrho\,\sigma_t$, $\sigma_a = (1 - \varrho)\,\sigma_t$.

    **Arguments:**

    - `sigma_t`: extinction coefficient, >= 0. [m^-1]
    - `albedo`: single-scattering albedo $\varrho$ in [0, 1]. [dimensionless]

    **Returns:**

    `(sigma_a, sigma_s)`, broadcast over the inputs. [m^-1]

    ??? cite "References"
        `Pharr2023` §11.1.4.
    """
    t = _nonneg(sigma_t, "sigma_t", "m^-1")
    rho = check_in_range(as_float_array(albedo, "albedo"), "albedo", 0.0, 1.0)
    t, rho = align_ranks(t, rho)
    return (1.0 - rho) * t, rho * t


def optical_depth(sigma_t: FloatLike, distance: FloatLike) -> Float[Array, "..."]:
    r"""Optical depth (optical thickness) of a homogeneous segment, $\tau = \sigma_t d$.

    **Arguments:**

    - `sigma_t`: extinction coefficient, >= 0. [m^-1]
    - `distance`: segment length $d$, >= 0; may be infinite. [m]

    **Returns:**

    $\tau$ [dimensionless]; 0 where $\sigma_t = 0$, also for an infinite `distance`, so that
    $e^{-\tau}$ is the Beer-Lambert transmittance (thesis eq. 1.12) everywhere.

    !!! note "Thesis"
        Eq. (1.12), section 1.3 (with $\kappa_a z$ as the optical depth of pure absorption).

    ??? cite "References"
        `Pharr2023` §11.2 (eq. 11.6).
    """
    t, d = align_ranks(_nonneg(sigma_t, "sigma_t", "m^-1"), _nonneg(distance, "distance", "m"))
    zero = t == 0
    # Double where: 0 * inf would be NaN, and its gradient too.
    return jnp.where(zero, 0.0, jnp.where(zero, 1.0, t) * jnp.where(zero, 1.0, d))


def optical_depth_along_ray(
    sigma_t_fn: Callable[[Array], Array],
    origins: Float[Array, "*batch 3"],
    directions: Float[Array, "*batch 3"],
    t_max: FloatLike,
    *,
    n_points: int = 64,
) -> Float[Array, "*batch"]:
    r"""Optical depth $\tau = \int_0^{t_{max}}\sigma_t(\mathbf o + t\boldsymbol\omega)\,\mathrm dt$
    of a heterogeneous medium, by Gauss-Legendre quadrature along each segment.

    **Arguments:**

    - `sigma_t_fn`: the extinction field, a JAX callable from points `(..., 3)` to
        coefficients `(...)` (the leading shape is kept). [m^-1]
    - `origins`: segment origins `(..., 3)`. [m]
    - `directions`: unit directions `(..., 3)`. [dimensionless]
    - `t_max`: segment lengths `(...)`, >= 0 and finite. [m]
    - `n_points`: quadrature nodes per segment (static); exact for a field that is a
        polynomial of degree `2 n_points - 1` along the ray. [dimensionless]

    **Returns:**

    $\tau$ `(...)`. [dimensionless] Differentiable in the field's parameters.

    !!! note "Thesis"
        Eq. (1.12), section 1.3; chapter 4 (title only in the text).

    ??? cite "References"
        `Pharr2023` §11.2 (eq. 11.6); `Novak2018` §2.
    """
    n_points = check_positive_int(n_points, "n_points")
    o = check_last_axis(as_float_array(origins, "origins"), "origins", 3)
    w = check_last_axis(as_float_array(directions, "directions"), "directions", 3)
    d = check_in_range(as_float_array(t_max, "t_max"), "t_max", 0.0, math.inf, unit="m")
    d = check_in_range(d, "t_max", -math.inf, math.inf, closed_lower=False, closed_upper=False)
    x, wq = np.polynomial.legendre.leggauss(n_points)
    dtype = jnp.result_type(o, w, d)
    x = jnp.asarray(x, dtype)
    wq = jnp.asarray(wq, dtype)
    batch = jnp.broadcast_shapes(o.shape[:-1], w.shape[:-1], d.shape)
    o = jnp.broadcast_to(o, batch + (3,))
    w = jnp.broadcast_to(w, batch + (3,))
    d = jnp.broadcast_to(d, batch)
    # Nodes t_j = d (1 + x_j) / 2 on [0, d], weights d w_j / 2.
    lead = (1,) * len(batch)
    t = d[..., None] * (0.5 * (1.0 + x)).reshape(lead + x.shape)  # (..., q)
    pts = o[..., None, :] + t[..., None] * w[..., None, :]  # (..., q, 3)
    sig = jnp.asarray(sigma_t_fn(pts))
    sig, wq = align_ranks(sig, wq)
    return 0.5 * d * jnp.sum(sig * wq, axis=-1)


def penetration_depth(sigma_t: FloatLike) -> Float[Array, "..."]:
    r"""Penetration depth $\delta = 1/\sigma_t$, where the transmittance falls to $1/e$.

    **Arguments:**

    - `sigma_t`: extinction coefficient (or absorption coefficient $\kappa_a$ for pure
        absorption), >= 0. [m^-1]

    **Returns:**

    $\delta$ [m]; infinite where $\sigma_t = 0$ (a vacuum), with a zero gradient there.

    !!! note "Thesis"
        Section 1.3, after eq. (1.12) ($z = \kappa_a^{-1}$).

    ??? cite "References"
        `Pharr2023` §11.1 (mean free path).
    """
    t = _nonneg(sigma_t, "sigma_t", "m^-1")
    zero = t == 0
    return jnp.where(zero, jnp.inf, 1.0 / jnp.where(zero, 1.0, t))


def absorption_index_from_coefficient(
    kappa_a: FloatLike, wavelength_nm: FloatLike
) -> Float[Array, "..."]:
    r"""Absorption index $\kappa = \kappa_a/(2k_0)$, the imaginary part of the complex
    refractive index, from the absorption coefficient.

    **Arguments:**

    - `kappa_a`: absorption coefficient $\kappa_a$, >= 0. [m^-1]
    - `wavelength_nm`: vacuum wavelength $\lambda_0$, > 0. [nm]

    **Returns:**

    $\kappa$ [dimensionless]. The inverse is `absorption_coefficient_from_index`.
    (Glass, with $\kappa_a = 10$ m^-1 at 550 nm, has $\kappa \approx 4.4\cdot
    10^{-7}$.)

    !!! note "Thesis"
        Section 1.3 (complex refractive index, $\kappa = \kappa_a/2k_0$).

    ??? cite "References"
        `Born1999` §14.1.
    """
    ka = _nonneg(kappa_a, "kappa_a", "m^-1")
    ka, k0 = align_ranks(ka, wavenumber_vacuum(wavelength_nm))
    return ka / (2.0 * k0)


def absorption_coefficient_from_index(
    kappa: FloatLike, wavelength_nm: FloatLike
) -> Float[Array, "..."]:
    r"""Absorption coefficient $\kappa_a = 2k_0\kappa$ from the absorption index.

    **Arguments:**

    - `kappa`: absorption index $\kappa$ (imaginary part of the complex refractive index),
        >= 0. [dimensionless]
    - `wavelength_nm`: vacuum wavelength $\lambda_0$, > 0. [nm]

    **Returns:**

    $\kappa_a$. [m^-1] The inverse of `absorption_index_from_coefficient`.

    !!! note "Thesis"
        Section 1.3 (complex refractive index).

    ??? cite "References"
        `Born1999` §14.1.
    """
    k = _nonneg(kappa, "kappa", "")
    k, k0 = align_ranks(k, wavenumber_vacuum(wavelength_nm))
    return 2.0 * k0 * k


def _complex(re: Array, im: Array) -> Array:
    re, im = align_ranks(re, im)
    dtype = jnp.result_type(re, im)
    shape = jnp.broadcast_shapes(re.shape, im.shape)
    re = jnp.broadcast_to(re.astype(dtype), shape)
    im = jnp.broadcast_to(im.astype(dtype), shape)
    return lax.complex(re, im)


def complex_refractive_index(
    eta: FloatLike, kappa_a: FloatLike, wavelength_nm: FloatLike
) -> Complex[Array, "..."]:
    r"""Complex refractive index $\underline\eta = \eta + i\kappa$, with $\kappa = \kappa_a/(2k_0)$.

    **Arguments:**

    - `eta`: real refractive index $\eta = k/k_0$, > 0. [dimensionless]
    - `kappa_a`: absorption coefficient, >= 0. [m^-1]
    - `wavelength_nm`: vacuum wavelength, > 0. [nm]

    **Returns:**

    $\underline\eta$, a complex array (complex128 from float64 input). [dimensionless]
    `absorption_coefficient_from_complex_refractive_index` recovers $\kappa_a$, and
    `complex_wavenumber` is $k_0\underline\eta$.

    !!! note "Thesis"
        Section 1.3 (complex refractive index $\underline\eta = k/k_0 + i\kappa_a/2k_0$).

    ??? cite "References"
        `Born1999` §14.1; `Pharr2023` §9.3.6.
    """
    e = check_in_range(as_float_array(eta, "eta"), "eta", 0.0, math.inf, closed_lower=False)
    return _complex(e, absorption_index_from_coefficient(kappa_a, wavelength_nm))


def absorption_coefficient_from_complex_refractive_index(
    eta_complex, wavelength_nm: FloatLike
) -> Float[Array, "..."]:
    r"""Absorption coefficient $\kappa_a = 2k_0\,\Im\underline\eta$ of a complex refractive index.

    **Arguments:**

    - `eta_complex`: complex refractive index $\eta + i\kappa$, $\kappa >= 0$.
        [dimensionless]
    - `wavelength_nm`: vacuum wavelength, > 0. [nm]

    **Returns:**

    $\kappa_a$. [m^-1] The inverse of `complex_refractive_index` (whose real part is
    $\Re\underline\eta$).

    !!! note "Thesis"
        Section 1.3 (complex refractive index).
    """
    return absorption_coefficient_from_index(jnp.imag(jnp.asarray(eta_complex)), wavelength_nm)


def complex_wavenumber(
    eta: FloatLike, kappa_a: FloatLike, wavelength_nm: FloatLike
) -> Complex[Array, "..."]:
    r"""Complex wavenumber $\underline k = k + i\kappa_a/2$ of an absorbing medium, with
    $k = \eta k_0$.

    The field of a plane wave along $z$ is $E_0 e^{i(\underline kz - \omega t)} =
    e^{-\kappa_a z/2}E_0e^{i(kz - \omega t)}$, so its intensity decays as $e^{-\kappa_a z}$
    (thesis eq. 1.11-1.12).

    **Arguments:**

    - `eta`: real refractive index, > 0. [dimensionless]
    - `kappa_a`: absorption coefficient, >= 0. [m^-1]
    - `wavelength_nm`: vacuum wavelength, > 0. [nm]

    **Returns:**

    $\underline k = k_0\underline\eta$, complex. [rad m^-1]
    `absorption_coefficient_from_complex_wavenumber` recovers $\kappa_a$.

    !!! note "Thesis"
        Section 1.3 (complex wavenumber), eq. (1.11)-(1.12).

    ??? cite "References"
        `Born1999` §14.1.
    """
    e = check_in_range(as_float_array(eta, "eta"), "eta", 0.0, math.inf, closed_lower=False)
    ka = _nonneg(kappa_a, "kappa_a", "m^-1")
    e, k0 = align_ranks(e, wavenumber_vacuum(wavelength_nm))
    k = e * k0
    k, ka = align_ranks(k, ka)
    return _complex(k, 0.5 * ka)


def absorption_coefficient_from_complex_wavenumber(k_complex) -> Float[Array, "..."]:
    r"""Absorption coefficient $\kappa_a = 2\,\Im\underline k$ of a complex wavenumber.

    **Arguments:**

    - `k_complex`: complex wavenumber $k + i\kappa_a/2$. [rad m^-1]

    **Returns:**

    $\kappa_a$. [m^-1] The inverse of `complex_wavenumber` in its absorption part.

    !!! note "Thesis"
        Section 1.3 (complex wavenumber).
    """
    return 2.0 * jnp.imag(jnp.asarray(k_complex))
