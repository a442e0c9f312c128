r"""The Trowbridge-Reitz (GGX) and Beckmann microfacet distributions, with visible-normal sampling.

All directions are in the local shading frame (normal +z) and point away from the surface.
The roughness parameters $\alpha_x, \alpha_y$ broadcast against the leading axes of the
directions (an array `alpha` of shape `(...)` goes with directions `(..., 3)`).

??? cite "References"
    `Trowbridge1975`; `Walter2007` (GGX, Beckmann); `Heitz2014` (masking-shadowing);
    `Heitz2018` (visible-normal sampling); `HeitzDEon2014` (visible normals of Beckmann);
    `Pharr2016` section 8.4 (Beckmann sampling); `Pharr2023` section 9.6.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy.special as jsp
from jax import Array

from .._checks import as_float_array
from .._math import acos_fast, align_ranks, disk_concentric_xy, safe_sqrt, sincos_pi
from ._directions import _inv_norm, _sqrt_clamped, _stack3, _xyz

__all__ = ["BeckmannDistribution", "TrowbridgeReitzDistribution", "roughness_to_alpha"]

# Smallest alpha used in computations: below it D overflows in float32 (Mitsuba clamps to the
# same value). Use the smooth BxDFs for mirror-like surfaces.
ALPHA_MIN = 1e-4


def roughness_to_alpha(roughness) -> Array:
    r"""Map a perceptual roughness in [0, 1] to $\alpha = \sqrt{r}$ (`Pharr2023` section 9.6.1).

    **Arguments:**

    - `roughness`: user-facing roughness, in [0, 1]. [dimensionless]

    **Returns:**

    $\alpha$, in [0, 1]. [dimensionless]
    """
    r = as_float_array(roughness, "roughness")
    r = eqx.error_if(r, (r < 0) | (r > 1), "`roughness` must lie in [0, 1]; got a value outside.")
    return safe_sqrt(r)


def _check_alpha(alpha, name: str, what: str = "GGX") -> Array:
    alpha = as_float_array(alpha, name)
    return eqx.error_if(
        alpha,
        (alpha <= 0) | (alpha > 1),
        f"`{name}` ({what} roughness alpha) must lie in (0, 1]; got a value outside. "
        "Use the smooth BxDF for alpha = 0.",
    )


# --------------------------------------------------------------------------------------------
# Component-wise cores. Vectors are passed as separate x, y, z arrays of shape (...): on XLA's
# CPU backend a reduction over a length-3 axis (a dot product or norm of stacked vectors) is
# handed to a library kernel that is an order of magnitude slower than the few multiply-adds it
# replaces, and slicing stacked vectors inside a fusion gathers with a stride. Divisions and
# square roots are the expensive operations here, so the formulas are arranged to need few.


def _D_den(x: Array, y: Array, z: Array, ax: Array, ay: Array) -> Array:
    r"""$1/D(\omega_m) = \pi\alpha_x\alpha_y e^2$ with
    $e = m_x^2/\alpha_x^2 + m_y^2/\alpha_y^2 + m_z^2$ (see `TrowbridgeReitzDistribution.D`)."""
    # Reciprocals of the (usually scalar) alphas, so no per-element division.
    e = (x * x) * (1.0 / (ax * ax)) + (y * y) * (1.0 / (ay * ay)) + z * z
    return jnp.pi * ax * ay * (e * e)


def _slope_root(x: Array, y: Array, z: Array, ax: Array, ay: Array) -> Array:
    r"""$r = \sqrt{z^2 + \alpha_x^2x^2 + \alpha_y^2y^2}$; Smith's $\Lambda = (r/|z| - 1)/2$."""
    return jnp.sqrt(z * z + (ax * x) ** 2 + (ay * y) ** 2)


def _sample_wm_xyz(x, y, z, ax, ay, u0, u1) -> tuple[Array, Array, Array]:
    """Component-wise core of `TrowbridgeReitzDistribution.sample_wm`."""
    # Transform w to the hemispherical configuration (alpha = 1), upper hemisphere.
    hx, hy, hz = ax * x, ay * y, z
    inv, _ = _inv_norm(hx, hy, hz)
    inv = jnp.where(hz < 0, -inv, inv)
    hx, hy, hz = hx * inv, hy * inv, hz * inv
    # Orthonormal basis (T1, T2, wh); T1 = normalize(z x wh) = (-h_y, h_x, 0)/rho away from
    # the pole, T2 = wh x T1.
    rho2 = hx * hx + hy * hy
    pole = rho2 < 1e-14
    irho = 1.0 / jnp.sqrt(jnp.where(pole, 1.0, rho2))
    t1x = jnp.where(pole, 1.0, -hy * irho)
    t1y = jnp.where(pole, 0.0, hx * irho)
    t2x, t2y, t2z = -hz * t1y, hz * t1x, hx * t1y - hy * t1x
    # Uniformly distributed point on the unit disk (concentric mapping, as Mitsuba; pbrt
    # uses the polar one: any uniform disk sample gives the same distribution).
    px, py = disk_concentric_xy(u0, u1)
    # Warp the disk to the projection of the visible hemisphere.
    h = _sqrt_clamped(1.0 - px * px)
    s = 0.5 * (1.0 + hz)
    py = (1.0 - s) * h + s * py
    pz = _sqrt_clamped(1.0 - px * px - py * py)
    nx = px * t1x + py * t2x + pz * hx
    ny = px * t1y + py * t2y + pz * hy
    nz = py * t2z + pz * hz
    # Back to the ellipsoid configuration.
    mx, my, mz = ax * nx, ay * ny, jnp.maximum(1e-6, nz)
    inv, _ = _inv_norm(mx, my, mz)
    return mx * inv, my * inv, mz * inv


class TrowbridgeReitzDistribution(eqx.Module):
    r"""Anisotropic Trowbridge-Reitz (GGX) distribution of microfacet normals.

    $$D(\omega_m) = \frac{1}{\pi\alpha_x\alpha_y\left(\frac{m_x^2}{\alpha_x^2} +
      \frac{m_y^2}{\alpha_y^2} + m_z^2\right)^2}$$

    normalised so that $\int D(\omega_m)\cos\theta_m\,d\omega_m = 1$ over the upper hemisphere.

    **Fields:**

    - `alpha_x`, `alpha_y`: roughness along the tangent axes, in (0, 1] (values below 1e-4
        are raised to 1e-4, as in Mitsuba). Shape `(...)`, broadcast against directions.
        [dimensionless]

    !!! note "Thesis"
        Glossy reflection, section 3.1 (the thesis names the lobe types; the microfacet model
        fills them in following `Pharr2023` section 9.6).
    """

    alpha_x: Array
    alpha_y: Array

    def __init__(self, alpha_x, alpha_y=None):
        ax = _check_alpha(alpha_x, "alpha_x")
        ay = ax if alpha_y is None else _check_alpha(alpha_y, "alpha_y")
        self.alpha_x = jnp.maximum(ax, ALPHA_MIN)
        self.alpha_y = jnp.maximum(ay, ALPHA_MIN)

    def _axy(self, w: Array) -> tuple[Array, Array, Array, Array, Array]:
        x, y, z, ax, ay = align_ranks(w[..., 0], w[..., 1], w[..., 2], self.alpha_x, self.alpha_y)
        return x, y, z, ax, ay

    def D(self, wm) -> Array:
        """Microfacet normal density $D(\\omega_m)$ (symmetric in $\\pm z$). [sr^-1]"""
        return 1.0 / _D_den(*self._axy(wm))

    def _D_xyz(self, x, y, z) -> Array:
        """`D` of normals given as components `(...)`."""
        x, y, z, ax, ay = align_ranks(x, y, z, self.alpha_x, self.alpha_y)
        return 1.0 / _D_den(x, y, z, ax, ay)

    def _lambda_xyz(self, x, y, z) -> Array:
        """`lambda_` of directions given as components `(...)`."""
        x, y, z, ax, ay = align_ranks(x, y, z, self.alpha_x, self.alpha_y)
        az = jnp.abs(z)
        ok = az > 0
        return jnp.where(ok, 0.5 * (_slope_root(x, y, z, ax, ay) / jnp.where(ok, az, 1.0) - 1.0),
                         jnp.inf)  # fmt: skip

    def _sample_wm_xyz(self, x, y, z, u0, u1) -> tuple[Array, Array, Array]:
        """`sample_wm` with directions and normals as components `(...)`."""
        x, y, z, ax, ay, u0, u1 = align_ranks(x, y, z, self.alpha_x, self.alpha_y, u0, u1)
        return _sample_wm_xyz(x, y, z, ax, ay, u0, u1)

    def _sq_slope_term(self, w: Array) -> tuple[Array, Array]:
        """Returns (|z|, sqrt(z^2 + alpha_x^2 x^2 + alpha_y^2 y^2))."""
        x, y, z, ax, ay = self._axy(w)
        return jnp.abs(z), _slope_root(x, y, z, ax, ay)

    def lambda_(self, w) -> Array:
        r"""Smith's $\Lambda(\omega) = (\sqrt{1 + \alpha^2\tan^2\theta} - 1)/2$; inf at grazing."""
        return self._lambda_xyz(*_xyz(as_float_array(w, "w")))

    def G1(self, w) -> Array:
        r"""Smith masking function $G_1(\omega) = 1/(1 + \Lambda(\omega))$, in [0, 1]; 0 at grazing.

        Evaluated as $2|\cos\theta|/(|\cos\theta| + \sqrt{\cos^2\theta + \alpha_x^2\omega_x^2 +
        \alpha_y^2\omega_y^2})$, finite everywhere.
        """
        az, r = self._sq_slope_term(w)
        den = az + r
        ok = den > 0
        return jnp.where(ok, 2.0 * az / jnp.where(ok, den, 1.0), 0.0)

    def G(self, wo, wi) -> Array:
        r"""Height-correlated masking-shadowing (`Heitz2014`).

        $$G = 1/(1 + \Lambda(\omega_o) + \Lambda(\omega_i))$$

        Evaluated as $2|z_o||z_i|/(|z_i|\,r_o + |z_o|\,r_i)$ with
        $r = \sqrt{z^2 + \alpha_x^2 x^2 + \alpha_y^2 y^2}$, finite everywhere (0 at grazing).
        """
        zo, ro = self._sq_slope_term(wo)
        zi, ri = self._sq_slope_term(wi)
        zo, ro, zi, ri = align_ranks(zo, ro, zi, ri)
        den = zi * ro + zo * ri
        ok = den > 0
        return jnp.where(ok, 2.0 * zo * zi / jnp.where(ok, den, 1.0), 0.0)

    def D_visible(self, w, wm) -> Array:
        r"""Distribution of visible normals $D_\omega(\omega_m) = \frac{G_1(\omega)}{|\cos\theta|}
        D(\omega_m)\,|\omega\cdot\omega_m|$ (`Heitz2018`). [sr^-1]"""
        w = as_float_array(w, "w")
        wm = as_float_array(wm, "wm")
        w, wm = align_ranks(w, wm)
        x, y, z, ax, ay = self._axy(w)
        mx, my, mz = wm[..., 0], wm[..., 1], wm[..., 2]
        # G1(w) / |cos theta| = 2 / (|z| + r), finite where z != 0.
        az = jnp.abs(z)
        ok = az > 0
        den = jnp.where(ok, (az + _slope_root(x, y, z, ax, ay)) * _D_den(mx, my, mz, ax, ay), 1.0)
        dot = jnp.abs(x * mx + y * my + z * mz)
        return jnp.where(ok, 2.0 * dot / den, 0.0)

    def pdf(self, w, wm) -> Array:
        """Solid-angle density of `sample_wm(w, u)` at `wm`: `D_visible`. [sr^-1]"""
        return self.D_visible(w, wm)

    def sample_wm(self, w, u) -> Array:
        r"""Sample a visible microfacet normal for `w` (`Heitz2018`, `Pharr2023` 9.6.4).

        The hemisphere configuration: stretch `w` to the unit-roughness configuration, sample
        the projected area of the visible hemisphere (a disk with its lower half squashed by
        $(1 + \cos\theta)/2$), lift to the hemisphere and unstretch.

        **Arguments:**

        - `w`: direction `(..., 3)` in the local frame; either hemisphere (it is mirrored to +z).
        - `u`: uniform variates `(..., 2)` in [0, 1).

        **Returns:**

        Microfacet normals `(..., 3)` with $m_z > 0$, distributed with density `pdf(w, wm)`.
        """
        w = as_float_array(w, "w")
        u = as_float_array(u, "u")
        x, y, z, ax, ay = self._axy(w)
        x, y, z, ax, ay, u0, u1 = align_ranks(x, y, z, ax, ay, u[..., 0], u[..., 1])
        return _stack3(*_sample_wm_xyz(x, y, z, ax, ay, u0, u1))


# --------------------------------------------------------------------------------------------
# Beckmann

_INV_SQRT_PI = 0.5641895835477563  # 1 / sqrt(pi)
# From the fitted start, two Newton steps reach |C(b) - u| < 1e-5 for every (theta, u) tried
# (grazing to normal incidence, u within 1e-4 of 0 and 1, float32 and float64: the same
# slopes as 40 steps); one step is spare. Each step costs an erfinv and an exp per sample.
_NEWTON_STEPS = 3


def _beckmann_sample11(cos_theta: Array, u0: Array, u1: Array) -> tuple[Array, Array]:
    r"""Slopes $(x, y)$ of a visible normal of the unit-roughness Beckmann distribution, seen
    from a direction at polar angle $\theta$ in the x-z plane (`HeitzDEon2014`, `Pharr2016`
    8.4.3).

    The x-marginal of the visible slopes has the CDF
    $C(b) = (1 + b + \tan\theta\,e^{-\operatorname{erf}^{-1}(b)^2}/\sqrt\pi) /
    (1 + \operatorname{erf}(\cot\theta) + \tan\theta\,e^{-\cot^2\theta}/\sqrt\pi)$
    in $b = \operatorname{erf}(x)$, inverted by safeguarded Newton steps from a fitted start;
    $y$ is an independent unit Gaussian slope divided by $\sqrt2$ (erfinv of a uniform).
    """
    dtype = cos_theta.dtype
    eps = jnp.asarray(1e-6, dtype)
    cos_theta = jnp.clip(cos_theta, 1e-6, 1.0)
    sin_theta = _sqrt_clamped(1.0 - cos_theta * cos_theta)
    tan_theta = sin_theta / cos_theta
    cot_theta = cos_theta / jnp.maximum(sin_theta, 1e-7)
    u0 = jnp.maximum(u0, eps)
    one = jnp.asarray(1.0 - 1e-7 if dtype == jnp.float64 else 1.0 - 1e-6, dtype)
    # Newton-bisection on b = erf(slope_x) in the bracket [-1, erf(cot theta)].
    lo = -jnp.ones_like(cos_theta)
    hi = jsp.erf(cot_theta)
    theta = acos_fast(cos_theta)
    fit = 1.0 + theta * (-0.876 + theta * (0.4265 - 0.0594 * theta))
    b = hi - (1.0 + hi) * (1.0 - u0) ** fit
    norm = 1.0 / (1.0 + hi + _INV_SQRT_PI * tan_theta * jnp.exp(-cot_theta * cot_theta))
    b = jnp.where((b >= lo) & (b <= hi), b, 0.5 * (lo + hi))
    # Rows: erf(slope_x), iterated, and erf(slope_y) = 2 u1 - 1, a unit Gaussian over sqrt 2.
    b, by, lo, hi = jnp.broadcast_arrays(b, 2.0 * jnp.maximum(u1, eps) - 1.0, lo, hi)
    b = jnp.stack([b, by])
    inv = jsp.erfinv(jnp.clip(b, -one, one))

    def step(_, carry):
        b, inv, lo, hi, done = carry
        bx, ix = b[0], inv[0]
        value = norm * (1.0 + bx + _INV_SQRT_PI * tan_theta * jnp.exp(-ix * ix)) - u0
        deriv = norm * (1.0 - ix * tan_theta)
        done = done | (jnp.abs(value) < 1e-5)
        lo = jnp.where(done | (value > 0), lo, bx)
        hi = jnp.where(~done & (value > 0), bx, hi)
        safe = jnp.where(jnp.abs(deriv) > 0, deriv, 1.0)
        bx = jnp.where(done, bx, bx - value / safe)
        bx = jnp.where((bx >= lo) & (bx <= hi), bx, 0.5 * (lo + hi))
        b = jnp.stack([bx, b[1]])
        return b, jsp.erfinv(jnp.clip(b, -one, one)), lo, hi, done

    # A loop of static length, not unrolled Python steps, whose state holds both slopes'
    # erfinv: they leave it stored in a buffer. Unrolled (and with slope_y computed apart, a
    # value XLA hoists out of any loop), XLA's CPU backend copied the erfinv polynomials
    # into every fusion that reads the slopes: a rough plastic's compiled `sample_f` held
    # 1155 erfinv operations (13 copies of the last two), against 122 now.
    # (`jax.lax.optimization_barrier` does not prevent this: XLA:CPU drops the barrier
    # before fusion.)
    done = jnp.zeros(lo.shape, bool)
    _, inv, _, _, _ = jax.lax.fori_loop(0, _NEWTON_STEPS, step, (b, inv, lo, hi, done))
    # Near normal incidence the visible slopes are the plain Gaussian ones (polar form).
    normal = cos_theta > 0.9999
    r = jnp.sqrt(-jnp.log1p(-u0))
    sin, cos = sincos_pi(2.0 * u1)  # phi = 2 pi u1
    slope_x = jnp.where(normal, r * cos, inv[0])
    slope_y = jnp.where(normal, r * sin, inv[1])
    return slope_x, slope_y


class BeckmannDistribution(eqx.Module):
    r"""Anisotropic Beckmann distribution of microfacet normals (`Walter2007`), with the same
    interface as `TrowbridgeReitzDistribution` (Mitsuba's default for rough BSDFs).

    $$D(\omega_m) = \frac{\exp\!\left(-\frac{m_x^2/\alpha_x^2 + m_y^2/\alpha_y^2}{m_z^2}\right)}
      {\pi\alpha_x\alpha_y m_z^4}$$

    normalised so that $\int D(\omega_m)\cos\theta_m\,d\omega_m = 1$ over the upper
    hemisphere (zero on the lower one, where $m_z \le 0$). Smith's masking uses the exact
    $\Lambda(\omega) = \tfrac12\left(\operatorname{erf}(a) - 1 + e^{-a^2}/(a\sqrt\pi)\right)$,
    $a = |\cos\theta| / \sqrt{\alpha_x^2\omega_x^2 + \alpha_y^2\omega_y^2}$ (`Heitz2014`).

    **Fields:**

    - `alpha_x`, `alpha_y`: roughness (RMS slope times $\sqrt2$) along the tangent axes, in
        (0, 1] (values below 1e-4 are raised to 1e-4, as in Mitsuba). Shape `(...)`,
        broadcast against directions. [dimensionless]

    !!! note "Thesis"
        Glossy reflection, section 3.1 (the thesis names the lobe types; the microfacet model
        fills them in following `Pharr2016` section 8.4 and `Walter2007`).

    ??? cite "References"
        `Beckmann1963`; `Walter2007`; `Heitz2014`; `HeitzDEon2014`; `Pharr2016` §8.4.
    """

    alpha_x: Array
    alpha_y: Array

    def __init__(self, alpha_x, alpha_y=None):
        ax = _check_alpha(alpha_x, "alpha_x", "Beckmann")
        ay = ax if alpha_y is None else _check_alpha(alpha_y, "alpha_y", "Beckmann")
        self.alpha_x = jnp.maximum(ax, ALPHA_MIN)
        self.alpha_y = jnp.maximum(ay, ALPHA_MIN)

    def _D_xyz(self, x, y, z) -> Array:
        """`D` of normals given as components `(...)`."""
        x, y, z, ax, ay = align_ranks(x, y, z, self.alpha_x, self.alpha_y)
        ok = z > 0
        z2 = jnp.where(ok, z * z, 1.0)
        e = ((x / ax) ** 2 + (y / ay) ** 2) / z2
        return jnp.where(ok, jnp.exp(-e) / (jnp.pi * ax * ay * z2 * z2), 0.0)

    def D(self, wm) -> Array:
        """Microfacet normal density $D(\\omega_m)$, 0 for $m_z \\le 0$. [sr^-1]"""
        return self._D_xyz(*_xyz(as_float_array(wm, "wm")))

    def _lambda_xyz(self, x, y, z) -> Array:
        """`lambda_` of directions given as components `(...)`."""
        x, y, z, ax, ay = align_ranks(x, y, z, self.alpha_x, self.alpha_y)
        s = jnp.sqrt((ax * x) ** 2 + (ay * y) ** 2)  # alpha tan(theta) |cos theta|
        az = jnp.abs(z)
        normal = s <= 1e-12 * az
        grazing = az <= 0
        a = az / jnp.where(normal | grazing, 1.0, s)
        lam = 0.5 * (jsp.erf(a) - 1.0 + jnp.exp(-a * a) * _INV_SQRT_PI / a)
        lam = jnp.maximum(lam, 0.0)
        return jnp.where(normal, 0.0, jnp.where(grazing, jnp.inf, lam))

    def lambda_(self, w) -> Array:
        r"""Smith's $\Lambda(\omega)$ (exact form above); 0 at normal incidence, inf at grazing."""
        return self._lambda_xyz(*_xyz(as_float_array(w, "w")))

    def G1(self, w) -> Array:
        r"""Smith masking $G_1(\omega) = 1/(1 + \Lambda(\omega))$, in [0, 1]; 0 at grazing."""
        return 1.0 / (1.0 + self.lambda_(w))

    def G(self, wo, wi) -> Array:
        r"""Height-correlated masking-shadowing $1/(1 + \Lambda(\omega_o) + \Lambda(\omega_i))$
        (`Heitz2014`)."""
        lo, li = align_ranks(self.lambda_(wo), self.lambda_(wi))
        return 1.0 / (1.0 + lo + li)

    def D_visible(self, w, wm) -> Array:
        r"""Distribution of visible normals $D_\omega(\omega_m) = \frac{G_1(\omega)}{|\cos\theta|}
        D(\omega_m)\max(0, \omega\cdot\omega_m)$ for `w` mirrored to the upper hemisphere
        (`HeitzDEon2014`). [sr^-1]"""
        w = as_float_array(w, "w")
        wm = as_float_array(wm, "wm")
        w, wm = align_ranks(w, wm)
        w = jnp.where(w[..., 2:3] < 0, -w, w)
        z = w[..., 2]
        ok = z > 0
        dot = jnp.maximum(jnp.sum(w * wm, axis=-1), 0.0)
        g1 = self.G1(w)
        return jnp.where(ok, g1 * self.D(wm) * dot / jnp.where(ok, z, 1.0), 0.0)

    def pdf(self, w, wm) -> Array:
        """Solid-angle density of `sample_wm(w, u)` at `wm`: `D_visible`. [sr^-1]"""
        return self.D_visible(w, wm)

    def sample_wm(self, w, u) -> Array:
        r"""Sample a visible microfacet normal for `w` (`HeitzDEon2014`; `Pharr2016` 8.4.3).

        Stretch `w` to the unit-roughness configuration, sample the slopes visible from it
        (`_beckmann_sample11`), rotate them to the azimuth of the stretched `w`, unstretch
        them, and return the normal $(-x, -y, 1)/\|\cdot\|$.

        **Arguments:**

        - `w`: direction `(..., 3)` in the local frame; either hemisphere (it is mirrored to +z).
        - `u`: uniform variates `(..., 2)` in [0, 1).

        **Returns:**

        Microfacet normals `(..., 3)` with $m_z > 0$, distributed with density `pdf(w, wm)`.
        """
        w = as_float_array(w, "w")
        u = as_float_array(u, "u")
        return _stack3(*self._sample_wm_xyz(*_xyz(w), u[..., 0], u[..., 1]))

    def _sample_wm_xyz(self, x, y, z, u0, u1) -> tuple[Array, Array, Array]:
        """`sample_wm` with directions and normals as components `(...)`."""
        x, y, z, ax, ay, u0, u1 = align_ranks(x, y, z, self.alpha_x, self.alpha_y, u0, u1)
        sign = jnp.where(z < 0, -1.0, 1.0)
        hx, hy, hz = ax * x * sign, ay * y * sign, z * sign
        inv, _ = _inv_norm(hx, hy, hz)
        hx, hy, hz = hx * inv, hy * inv, hz * inv
        sx, sy = _beckmann_sample11(hz, u0, u1)
        rho2 = hx * hx + hy * hy
        pole = rho2 < 1e-14
        irho = 1.0 / jnp.sqrt(jnp.where(pole, 1.0, rho2))
        cphi = jnp.where(pole, 1.0, hx * irho)
        sphi = jnp.where(pole, 0.0, hy * irho)
        sx, sy = cphi * sx - sphi * sy, sphi * sx + cphi * sy
        mx, my, mz = -ax * sx, -ay * sy, jnp.ones_like(sx)
        inv, _ = _inv_norm(mx, my, mz)
        return mx * inv, my * inv, mz * inv
