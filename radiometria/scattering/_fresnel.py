r"""Fresnel equations for dielectric and conducting interfaces (thesis section 3.1.1).

All functions are elementwise in `cos_theta_i` and the optical constants and broadcast their
arguments, so a spectral call passes `eta` / `k` of shape `(..., n_lambda)` and a matching
`cos_theta_i[..., None]`.

Notation (thesis eq. 3.13-3.18): $\mu = \cos\theta_i$; $\eta = \eta_t/\eta_i$ is the relative
index of refraction of the far side (opposite to the normal) over the near side; for a
conductor the relative complex index is $\eta + i\kappa$ ($\kappa$ = `k`, the extinction
coefficient). Subscript $\perp$ (s) is the polarisation with the electric field perpendicular
to the plane of incidence, $\parallel$ (p) the one parallel to it (thesis footnote 9).

Input policy: `cos_theta_i` is clamped to [-1, 1] (rounding makes `|w_z|` exceed 1 by an ulp);
`eta <= 0` and `k < 0` are out of the physical domain and raise (`equinox.error_if`, also under
`jit`). NaN propagates.
"""

import equinox as eqx
import jax.numpy as jnp
from jax import Array

from .._checks import as_float_array, check_broadcastable, check_positive
from .._math import align_ranks, safe_sqrt
from ._directions import _bcast, _sqrt_clamped

__all__ = [
    "fresnel_complex",
    "fresnel_conductor",
    "fresnel_conductor_polarized",
    "fresnel_dielectric",
    "fresnel_dielectric_amplitudes",
    "fresnel_dielectric_polarized",
    "fresnel_dielectric_transmittance",
    "fresnel_schlick",
    "fresnel_schlick_f0",
]


def _check_eta(eta) -> Array:
    eta = as_float_array(eta, "eta")
    return check_positive(eta, "eta", "dimensionless, relative index of refraction")


def _check_k(k) -> Array:
    k = as_float_array(k, "k")
    return eqx.error_if(k, k < 0, "`k` (extinction coefficient) must be >= 0; got a value < 0.")


def _dielectric_cosines(cos_i: Array, eta: Array):
    """Unchecked core: flip the interface for rays from inside, then Snell's law.

    `cos_i` and `eta` must already have equal ranks. Returns (|cos_i|, eta_eff, cos_t >= 0, tir).
    """
    cos_i = jnp.clip(cos_i, -1.0, 1.0)
    # A ray arriving from inside the object sees the inverse relative index.
    inside = cos_i < 0
    eta = jnp.where(inside, 1.0 / eta, eta)
    cos_i = jnp.abs(cos_i)
    # Snell's law: sin^2(theta_t) = sin^2(theta_i) / eta^2   (thesis eq. 3.7, 3.10)
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    tir = sin2_t >= 1.0
    cos_t = safe_sqrt(jnp.where(tir, 0.0, 1.0 - sin2_t))
    return cos_i, eta, cos_t, tir


def _amplitudes(cos_i: Array, eta: Array):
    """Unchecked core of `fresnel_dielectric_amplitudes` (equal-rank inputs)."""
    cos_i, eta, cos_t, tir = _dielectric_cosines(cos_i, eta)
    den_s = cos_i + eta * cos_t
    den_p = eta * cos_i + cos_t
    # The denominators vanish only at grazing incidence under TIR, which is masked.
    bad_s = tir | ~(den_s > 0)
    bad_p = tir | ~(den_p > 0)
    den_s = jnp.where(bad_s, 1.0, den_s)
    den_p = jnp.where(bad_p, 1.0, den_p)
    # An index-matched interface (eta = 1) has no interface at all, even at grazing incidence.
    matched = eta == 1.0
    r_s = jnp.where(matched, 0.0, jnp.where(bad_s, 1.0, (cos_i - eta * cos_t) / den_s))
    r_p = jnp.where(matched, 0.0, jnp.where(bad_p, 1.0, (eta * cos_i - cos_t) / den_p))
    t_s = jnp.where(matched, 1.0, jnp.where(bad_s, 0.0, 2.0 * cos_i / den_s))
    t_p = jnp.where(matched, 1.0, jnp.where(bad_p, 0.0, 2.0 * cos_i / den_p))
    return r_s, r_p, t_s, t_p, eta


def _fr_dielectric_snell(cos_i: Array, eta: Array, inv_eta: Array):
    r"""Unpolarised reflectance and Snell's law for the BxDFs' inner loop (unchecked).

    `inv_eta` is `1 / eta`, computed once per material by the caller. Returns
    `(F, |cos_i|, eta_eff, inv_eta_eff, cos_t, tir)`, where `eta_eff` is the relative index seen
    from the side of `cos_i` (`eta`, or `1 / eta` from inside) and `cos_t >= 0` (0 under total
    internal reflection). Same values as `_amplitudes` up to rounding, with one square root and
    one division: $F = \tfrac12(n_\perp^2 d_\parallel^2 + n_\parallel^2 d_\perp^2) /
    (d_\perp d_\parallel)^2$ for $r = n/d$.
    """
    cos_i = jnp.clip(cos_i, -1.0, 1.0)
    # A ray arriving from inside the object sees the inverse relative index.
    inside = cos_i < 0
    eta, inv_eta = jnp.where(inside, inv_eta, eta), jnp.where(inside, eta, inv_eta)
    cos_i = jnp.abs(cos_i)
    # Snell's law: sin^2(theta_t) = sin^2(theta_i) / eta^2   (thesis eq. 3.7, 3.10)
    sin2_t = (1.0 - cos_i * cos_i) * (inv_eta * inv_eta)
    tir = sin2_t >= 1.0
    cos_t = _sqrt_clamped(1.0 - sin2_t)
    n_s, d_s = cos_i - eta * cos_t, cos_i + eta * cos_t
    n_p, d_p = eta * cos_i - cos_t, eta * cos_i + cos_t
    d_s2, d_p2 = d_s * d_s, d_p * d_p
    den = d_s2 * d_p2
    # The denominators vanish only at grazing incidence under TIR (masked: F = 1); an
    # index-matched interface (eta = 1) has no interface at all, even at grazing incidence.
    ok = ~tir & (den > 0)
    f = 0.5 * (n_s * n_s * d_p2 + n_p * n_p * d_s2) / jnp.where(ok, den, 1.0)
    f = jnp.where(eta == 1.0, 0.0, jnp.where(ok, f, 1.0))
    return f, cos_i, eta, inv_eta, cos_t, tir


def _inputs(cos_theta_i, eta) -> tuple[Array, Array]:
    cos_i = as_float_array(cos_theta_i, "cos_theta_i")
    eta = _check_eta(eta)
    check_broadcastable(("cos_theta_i", cos_i), ("eta", eta))
    return align_ranks(cos_i, eta)


def fresnel_dielectric_amplitudes(cos_theta_i, eta) -> tuple[Array, Array, Array, Array]:
    r"""Fresnel amplitudes $(r_\perp, r_\parallel, t_\perp, t_\parallel)$ of a dielectric interface.

    $$r_\perp = \frac{\cos\theta_i - \eta\cos\theta_t}{\cos\theta_i + \eta\cos\theta_t},\quad
      r_\parallel = \frac{\eta\cos\theta_i - \cos\theta_t}{\eta\cos\theta_i + \cos\theta_t},$$
    $$t_\perp = \frac{2\cos\theta_i}{\cos\theta_i + \eta\cos\theta_t},\quad
      t_\parallel = \frac{2\cos\theta_i}{\eta\cos\theta_i + \cos\theta_t}.$$

    Ratios of reflected (transmitted) to incident electric-field amplitude, in the sign
    convention of `Born1999` section 1.5.2 (the "Verdet" convention, also Mitsuba's), in which
    $r_\parallel = -r_\perp$ at normal incidence. The power fractions are $R = r^2$ and
    $T = \frac{\eta\cos\theta_t}{\cos\theta_i}\,t^2$, with $R + T = 1$ per polarisation.

    **Arguments:**

    - `cos_theta_i`: cosine of the incident angle, in [-1, 1]; negative means the ray arrives
        from inside and the interface is flipped (`eta -> 1/eta`). [dimensionless]
    - `eta`: relative index of refraction $\eta_t/\eta_i$, > 0. [dimensionless]

    **Returns:**

    `(r_s, r_p, t_s, t_p)`, broadcast over the inputs. [dimensionless] Under total internal
    reflection the amplitudes are complex with unit modulus; this function then returns
    `r_s = r_p = 1` and `t_s = t_p = 0` (the moduli of the reflected and the zero transmitted
    power).

    !!! note "Thesis"
        Section 3.1.1, footnote 9; the power forms are eq. (3.13)-(3.16) with $\kappa = 0$.

    ??? cite "References"
        `Born1999` section 1.5.2; `Hecht2002` section 4.6.
    """
    r_s, r_p, t_s, t_p, _ = _amplitudes(*_inputs(cos_theta_i, eta))
    return r_s, r_p, t_s, t_p


def fresnel_dielectric_polarized(cos_theta_i, eta) -> tuple[Array, Array]:
    r"""Fresnel reflectances $(\bar\rho_\perp, \bar\rho_\parallel)$ of a dielectric interface.

    The s- and p-polarised power reflectances $r_\perp^2$, $r_\parallel^2$, identical to thesis
    eq. (3.13)-(3.14) with $\kappa = 0$. At Brewster's angle
    $\theta_B = \arctan\eta$ the p part vanishes.

    **Arguments:**

    - `cos_theta_i`: cosine of the incident angle, in [-1, 1] (negative: from inside).
        [dimensionless]
    - `eta`: relative index of refraction $\eta_t/\eta_i$, > 0. [dimensionless]

    **Returns:**

    `(R_s, R_p)`, each in [0, 1]; exactly 1 under total internal reflection. [dimensionless]

    !!! note "Thesis"
        Eq. (3.13)-(3.14), section 3.1.1.

    ??? cite "References"
        `Born1999` section 1.5.3; `Pharr2023` section 9.3.2.
    """
    r_s, r_p, _, _ = fresnel_dielectric_amplitudes(cos_theta_i, eta)
    return r_s * r_s, r_p * r_p


def fresnel_dielectric(cos_theta_i, eta) -> Array:
    r"""Unpolarised Fresnel reflectance of a smooth dielectric interface (exact).

    $$F_r = \tfrac12\left(r_\parallel^2 + r_\perp^2\right)$$

    **Arguments:**

    - `cos_theta_i`: cosine of the incident angle, in [-1, 1]. A negative value means the ray
        arrives from inside, and the interface is flipped (`eta -> 1/eta`). [dimensionless]
    - `eta`: relative index of refraction $\eta_t/\eta_i$, > 0. [dimensionless]

    **Returns:**

    Reflectance in [0, 1], broadcast over the inputs. Total internal reflection gives exactly 1.
    At normal incidence it equals $((\eta - 1)/(\eta + 1))^2$.

    !!! note "Thesis"
        Eq. (3.18) with (3.13)-(3.14) for $\kappa = 0$, section 3.1.1.

    ??? cite "References"
        `Born1999` section 1.5.2; `Pharr2023` section 9.3.
    """
    r_s, r_p = fresnel_dielectric_polarized(cos_theta_i, eta)
    return 0.5 * (r_s + r_p)


def fresnel_dielectric_transmittance(cos_theta_i, eta, *, radiance: bool = True) -> Array:
    r"""Unpolarised Fresnel transmittance of a smooth dielectric interface.

    With `radiance=True` (thesis eq. 3.15-3.16, averaged over the two polarisations):

    $$\bar\tau = \left(\frac{\eta_t}{\eta_i}\right)^2 (1 - F_r)$$

    With `radiance=False`, the transmitted fraction of *flux* (power), $1 - F_r$.

    Why the two differ (thesis footnote 10): energy is conserved at the interface,
    $\bar\rho + \bar\tau = 1$ for flux (eq. 3.1). Radiance, however, is flux per unit
    *projected area and solid angle*, and refraction compresses (or expands) the solid angle of
    a beam: from Snell's law, $\eta_i^2\cos\theta_i\,d\omega_i = \eta_t^2\cos\theta_t\,d\omega_t$.
    The conserved quantity along a ray is therefore the basic radiance $L/\eta^2$
    (thesis eq. 1.14), so the transmitted radiance is
    $L_t = (\eta_t/\eta_i)^2 (1 - F_r) L_i$: larger than $L_i$ when entering a denser medium,
    although less power goes through. The $(\eta_t/\eta_i)^2$ factor is the one a BTDF carries
    in radiance transport (`Pharr2023` section 9.5.2); it is absent for importance transport.

    **Arguments:**

    - `cos_theta_i`: cosine of the incident angle, in [-1, 1] (negative: from inside, and the
        roles of $\eta_i, \eta_t$ swap). [dimensionless]
    - `eta`: relative index of refraction $\eta_t/\eta_i$, > 0. [dimensionless]
    - `radiance`: include the $(\eta_t/\eta_i)^2$ radiance factor (default) or return the flux
        transmittance $1 - F_r$.

    **Returns:**

    The transmittance, broadcast over the inputs; 0 under total internal reflection. [dimensionless]

    !!! note "Thesis"
        Eq. (3.15)-(3.16) and footnote 10, section 3.1.1; basic radiance, eq. (1.14).

    ??? cite "References"
        `Pharr2023` section 9.5.2; `Veach1997` section 5.2.
    """
    r_s, r_p, _, _, eta_eff = _amplitudes(*_inputs(cos_theta_i, eta))
    t = 1.0 - 0.5 * (r_s * r_s + r_p * r_p)
    if radiance:
        t = t * eta_eff * eta_eff
    return t


def fresnel_conductor_polarized(cos_theta_i, eta, k) -> tuple[Array, Array]:
    r"""s- and p-polarised Fresnel reflectances for a complex relative index $\eta + i\kappa$.

    $$\bar\rho_\perp = \frac{(a-\mu)^2 + b^2}{(a+\mu)^2 + b^2},\qquad
      \bar\rho_\parallel = \bar\rho_\perp\,
      \frac{(a\mu - \sin^2\theta)^2 + b^2\mu^2}{(a\mu + \sin^2\theta)^2 + b^2\mu^2},$$
    $$a^2 = \frac{\sqrt{c^2 + 4\eta^2\kappa^2} + c}{2},\quad
      b^2 = \frac{\sqrt{c^2 + 4\eta^2\kappa^2} - c}{2},\quad c = \eta^2 - \kappa^2 - \sin^2\theta.$$

    This is thesis eq. (3.13)-(3.14) with two misprints corrected (checked against the general
    complex form, `fresnel_complex`): under the root the term is $4\eta^2\kappa^2$ (the thesis
    prints $4\eta\kappa$), and the p factor is
    $\frac{(a - \sin\theta\tan\theta)^2 + b^2}{(a + \sin\theta\tan\theta)^2 + b^2}$ (the thesis
    prints $(1 + \mu^2)/\mu$ with a minus sign in the denominator). The form above multiplies that
    factor by $\mu^2/\mu^2$ so it stays finite at grazing incidence. $a$ and $b$ are computed
    without cancellation from $ab = \eta\kappa$.

    **Arguments:**

    - `cos_theta_i`: cosine of the incident angle; its absolute value is used (a conductor is
        opaque, light only arrives from the outside). [dimensionless]
    - `eta`: real part of the relative complex index of refraction, > 0. [dimensionless]
    - `k`: imaginary part (extinction coefficient) $\kappa \ge 0$; `k = 0` gives the
        dielectric result, including total internal reflection for `eta < 1`. [dimensionless]

    **Returns:**

    `(R_s, R_p)`, each in [0, 1], broadcast over the inputs. [dimensionless]

    !!! note "Thesis"
        Eq. (3.13)-(3.14), section 3.1.1 (with the relative complex index of footnote 18).

    ??? cite "References"
        `Pegoraro2016` section 6.2; `Cook1982`; `Pharr2023` section 9.3.6.
    """
    mu = as_float_array(cos_theta_i, "cos_theta_i")
    eta = _check_eta(eta)
    k = _check_k(k)
    check_broadcastable(("cos_theta_i", mu), ("eta", eta), ("k", k))
    return _fr_conductor_polarized(*align_ranks(mu, eta, k))


def _conductor_terms(mu: Array, eta: Array, k: Array):
    r"""Numerators and denominators of the s and p parts (`fresnel_conductor_polarized`).

    Returns (num_s, den_s, num_p, den_p) with $R_s$ = num_s/den_s and
    $R_p = R_s\cdot$ num_p/den_p. Two square roots and one division.
    """
    mu = jnp.minimum(jnp.abs(mu), 1.0)
    mu2 = mu * mu
    sin2 = 1.0 - mu2
    c = eta * eta - k * k - sin2
    ek = eta * k
    s = _sqrt_clamped(c * c + 4.0 * ek * ek)  # = a^2 + b^2
    # a^2 = (s + c)/2 and b^2 = (s - c)/2; take the one without cancellation, q, and get the
    # other from a b = eta k: a^2 b^2 = (eta k)^2.
    pos = c >= 0
    q = 0.5 * (s + jnp.abs(c))
    q_ok = q > 0
    sqrt_q = _sqrt_clamped(q)
    inv_q = jnp.where(q_ok, 1.0 / jnp.where(q_ok, q, 1.0), 0.0)
    a = jnp.where(pos, sqrt_q, ek * sqrt_q * inv_q)  # sqrt(q) or eta k / sqrt(q)
    b2 = jnp.where(pos, ek * ek * inv_q, q)
    num_s = (a - mu) ** 2 + b2
    den_s = (a + mu) ** 2 + b2
    am = a * mu
    num_p = (am - sin2) ** 2 + b2 * mu2
    den_p = (am + sin2) ** 2 + b2 * mu2
    return num_s, den_s, num_p, den_p


def _fr_conductor_polarized(mu: Array, eta: Array, k: Array) -> tuple[Array, Array]:
    """Unchecked core of `fresnel_conductor_polarized` (equal-rank inputs)."""
    num_s, den_s, num_p, den_p = _conductor_terms(mu, eta, k)
    ok_s = den_s > 0
    r_s = jnp.where(ok_s, num_s / jnp.where(ok_s, den_s, 1.0), 1.0)
    ok_p = den_p > 0
    r_p = r_s * jnp.where(ok_p, num_p / jnp.where(ok_p, den_p, 1.0), 1.0)
    return r_s, r_p


def _fr_conductor(mu: Array, eta: Array, k: Array) -> Array:
    r"""Unchecked unpolarised conductor reflectance (equal-rank inputs).

    $F_r = \tfrac12 R_s(1 + \text{num}_p/\text{den}_p)$ over one common denominator, so a
    single division (the BxDFs evaluate it per wavelength in the renderer's inner loop).
    """
    num_s, den_s, num_p, den_p = _conductor_terms(mu, eta, k)
    den = den_s * den_p
    ok = den > 0
    # The product vanishes only in the limit of grazing incidence (den_s) or of eta, k -> 0 at
    # normal incidence (den_p), where the reflectance tends to 1.
    return jnp.where(ok, 0.5 * num_s * (den_p + num_p) / jnp.where(ok, den, 1.0), 1.0)


def fresnel_conductor(cos_theta_i, eta, k) -> Array:
    r"""Unpolarised Fresnel reflectance of a conductor with complex relative index $\eta + i\kappa$.

    $$F_r(\mu) = \frac{\bar\rho_\perp(\mu) + \bar\rho_\parallel(\mu)}{2}$$

    See `fresnel_conductor_polarized` for the two parts and the corrected thesis formulas.

    **Arguments:**

    - `cos_theta_i`: cosine of the incident angle (absolute value used). [dimensionless]
    - `eta`: real part of the relative index, > 0, e.g. `(..., n_lambda)` spectral. [dimensionless]
    - `k`: extinction coefficient, >= 0, same broadcasting. [dimensionless]

    **Returns:**

    Reflectance in [0, 1], broadcast over the inputs. At normal incidence it equals
    $((\eta-1)^2 + \kappa^2)/((\eta+1)^2 + \kappa^2)$.

    !!! note "Thesis"
        Eq. (3.13)-(3.18), section 3.1.1.

    ??? cite "References"
        `Pegoraro2016` section 6.2; `Pharr2023` section 9.3.6.
    """
    r_s, r_p = fresnel_conductor_polarized(cos_theta_i, eta, k)
    return 0.5 * (r_s + r_p)


def fresnel_complex(cos_theta_i, eta, k) -> tuple[Array, Array]:
    r"""Complex Fresnel reflection amplitudes $(r_\perp, r_\parallel)$ for a complex relative index.

    The general form, valid for dielectrics and conductors alike, evaluated in complex
    arithmetic ($\tilde\eta = \eta + i\kappa$,
    $\cos\theta_t = \sqrt{1 - \sin^2\theta_i/\tilde\eta^2}$ on the principal branch):

    $$r_\perp = \frac{\cos\theta_i - \tilde\eta\cos\theta_t}
      {\cos\theta_i + \tilde\eta\cos\theta_t},\qquad
      r_\parallel = \frac{\tilde\eta\cos\theta_i - \cos\theta_t}
      {\tilde\eta\cos\theta_i + \cos\theta_t}.$$

    `|r_s|**2`, `|r_p|**2` equal `fresnel_conductor_polarized`; this function exists to check
    the real-arithmetic formulas of the thesis and to provide the phase. The output dtype is
    the complex type matching the inputs.

    **Arguments:**

    - `cos_theta_i`: cosine of the incident angle (absolute value used). [dimensionless]
    - `eta`: real part of the relative index, > 0. [dimensionless]
    - `k`: extinction coefficient, >= 0. [dimensionless]

    **Returns:**

    `(r_s, r_p)`, complex, broadcast over the inputs. [dimensionless]

    ??? cite "References"
        `Born1999` section 14.2; `Pharr2023` section 9.3.6 (`FrComplex`).
    """
    mu = jnp.abs(jnp.clip(as_float_array(cos_theta_i, "cos_theta_i"), -1.0, 1.0))
    eta = _check_eta(eta)
    k = _check_k(k)
    check_broadcastable(("cos_theta_i", mu), ("eta", eta), ("k", k))
    mu, eta, k = _bcast(mu, eta, k)
    cdtype = jnp.result_type(mu.dtype, eta.dtype, k.dtype)
    cdtype = jnp.complex128 if cdtype == jnp.float64 else jnp.complex64
    n = _complex(eta, k, cdtype)
    mu_c = mu.astype(cdtype)
    sin2_i = (1.0 - mu * mu).astype(cdtype)
    cos_t = jnp.sqrt(1.0 - sin2_i / (n * n))
    r_s = (mu_c - n * cos_t) / (mu_c + n * cos_t)
    r_p = (n * mu_c - cos_t) / (n * mu_c + cos_t)
    return r_s, r_p


def _complex(re: Array, im: Array, dtype) -> Array:
    return re.astype(dtype) + 1j * im.astype(dtype)


def fresnel_schlick_f0(eta) -> Array:
    r"""Normal-incidence reflectance $F_0 = ((\eta - 1)/(\eta + 1))^2$ of a dielectric.

    **Arguments:**

    - `eta`: relative index of refraction, > 0. [dimensionless]

    **Returns:**

    $F_0$ in [0, 1). [dimensionless]

    ??? cite "References"
        `Schlick1994`; thesis eq. (3.18) at normal incidence.
    """
    eta = _check_eta(eta)
    return ((eta - 1.0) / (eta + 1.0)) ** 2


def fresnel_schlick(cos_theta_i, f0) -> Array:
    r"""Schlick's approximation of the Fresnel reflectance.

    $$F \approx F_0 + (1 - F_0)(1 - \cos\theta)^5$$

    Exact at normal ($F_0$) and grazing (1) incidence; in between the absolute error for glass
    (eta = 1.5) is at most 0.036. For a ray inside the denser medium, pass $\cos\theta_t$ of the
    outside ray (and handle total internal reflection, where $F = 1$) as in `Schlick1994`.

    **Arguments:**

    - `cos_theta_i`: cosine of the angle to the normal (absolute value used). [dimensionless]
    - `f0`: reflectance at normal incidence, in [0, 1], may be spectral `(..., n_lambda)`
        (see `fresnel_schlick_f0`). [dimensionless]

    **Returns:**

    Approximate reflectance, broadcast over the inputs. [dimensionless]

    ??? cite "References"
        `Schlick1994`; `Pharr2023` section 9.3.
    """
    mu = jnp.abs(jnp.clip(as_float_array(cos_theta_i, "cos_theta_i"), -1.0, 1.0))
    f0 = as_float_array(f0, "f0")
    check_broadcastable(("cos_theta_i", mu), ("f0", f0))
    mu, f0 = align_ranks(mu, f0)
    m = 1.0 - mu
    m2 = m * m
    return f0 + (1.0 - f0) * (m2 * m2 * m)
