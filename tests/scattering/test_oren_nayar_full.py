r"""The qualitative Oren-Nayar BRDF against the full Oren-Nayar model it simplifies.

Reference: the *full* direct-illumination model of Oren & Nayar (SIGGRAPH 1994, eq. 30),
their functional fit to the numerically integrated V-cavity model, written here in plain
NumPy in angle form (the library works with dot products). With d = phi_r - phi_i,
alpha = max(theta_i, theta_r), beta = min(theta_i, theta_r):

    L_r / (rho E0 cos(theta_i) / pi)
        = C1 + cos(d) C2 tan(beta) + (1 - |cos(d)|) C3 tan((alpha + beta) / 2),
    C1 = 1 - 0.5 s2 / (s2 + 0.33),                 s2 = sigma^2 [rad^2],
    C2 = 0.45 s2 / (s2 + 0.09) sin(alpha)                       if cos(d) >= 0,
         0.45 s2 / (s2 + 0.09) (sin(alpha) - (2 beta / pi)^3)    otherwise,
    C3 = 0.125 s2 / (s2 + 0.09) (4 alpha beta / pi^2)^2.

The paper obtains its "qualitative model" from eq. 30 by dropping the C3 term and the
cos(d) < 0 (forward-scattering) part of the C2 term (and the interreflection term, which
eq. 30 does not contain). So the qualitative model must be:

1. exactly eq. 30 with those two terms removed, for every geometry and roughness;
2. exactly eq. 30 itself where both removed terms vanish: in the plane of incidence on the
   retroreflection side (d = 0) for any sigma, and everywhere for sigma = 0 (Lambert);
3. close to eq. 30 in the backscatter half (cos(d) >= 0) away from grazing: there the only
   difference is the dropped term (1 - cos d) C3 tan((alpha + beta)/2), which for
   sigma <= 0.5 and theta_i, theta_r <= 60 deg is at most
   0.125 (0.25/0.34) (4/9)^2 tan(60 deg) = 0.0314 against C1 >= 0.784, i.e. 4.0 % of the full
   value: the tolerance is that bound, 4.1 %. (The paper states no numerical accuracy for
   the qualitative model; in the forward half it differs from eq. 30 by up to tens of
   percent by construction, e.g. 25 % at 60/30 deg in the plane, and is not compared.)

Cases 1 and 2 are float64 identities (rtol 1e-12). A slip in the constants, in the
assignment of alpha and beta (e.g. sin(beta) tan(alpha)) or in the azimuth clamp fails them.
A direct numerical integration of the V-cavity model is not used: the paper's roughness
convention could not be matched to it (the fit's C1 ~ 1 - 1.5 sigma^2 at normal incidence
implies a mean squared facet angle of 3 sigma^2, not the sigma^2 of a half-normal slope
angle nor the 2 sigma^2 of an isotropic 2-D Gaussian).
"""

import jax.numpy as jnp
import numpy as np

import radiometria.scattering as sc

DEG = np.pi / 180
RHO = 0.8
SIGMAS = (0.0, 0.1, 0.25, 0.5, 1.0, np.pi / 2)


def _full_direct(theta_i, theta_r, dphi, sigma, *, drop_c3=False, drop_forward=False):
    """Oren & Nayar (1994) eq. 30, divided by rho E0 cos(theta_i) / pi (so: f pi / rho)."""
    alpha, beta = np.maximum(theta_i, theta_r), np.minimum(theta_i, theta_r)
    s2 = sigma * sigma
    c = np.cos(dphi)
    c1 = 1.0 - 0.5 * s2 / (s2 + 0.33)
    c2 = 0.45 * s2 / (s2 + 0.09)
    c2 = c2 * np.where(c >= 0, np.sin(alpha), np.sin(alpha) - (2 * beta / np.pi) ** 3)
    c3 = 0.125 * s2 / (s2 + 0.09) * (4 * alpha * beta / np.pi**2) ** 2
    c2_term = c * c2 * np.tan(beta)
    if drop_forward:
        c2_term = np.where(c >= 0, c2_term, 0.0)
    c3_term = 0.0 if drop_c3 else (1 - np.abs(c)) * c3 * np.tan((alpha + beta) / 2)
    return c1 + c2_term + c3_term


def _grid(theta_max_deg, dphi):
    th = np.linspace(0.0, theta_max_deg, 18) * DEG
    ti, tr, dp = np.meshgrid(th, th, np.asarray(dphi, np.float64), indexing="ij")
    return ti.ravel(), tr.ravel(), dp.ravel()


def _qualitative(theta_i, theta_r, dphi, sigma):
    """Our BRDF times pi / rho, at light (theta_i, phi_i) and viewer (theta_r, phi_i + dphi)."""
    phi_i = 0.7  # any azimuth: the model is isotropic
    wi = np.stack(
        [np.sin(theta_i) * np.cos(phi_i), np.sin(theta_i) * np.sin(phi_i), np.cos(theta_i)], -1
    )
    phi_r = phi_i + dphi
    wo = np.stack(
        [np.sin(theta_r) * np.cos(phi_r), np.sin(theta_r) * np.sin(phi_r), np.cos(theta_r)], -1
    )
    f = sc.OrenNayarBxDF(jnp.array([RHO]), sigma).f(jnp.asarray(wo), jnp.asarray(wi))
    return np.asarray(f)[:, 0] * np.pi / RHO


def test_oren_nayar_qualitative_is_full_model_without_dropped_terms():
    ti, tr, dp = _grid(89.0, np.linspace(0.0, np.pi, 13))
    for sigma in SIGMAS:
        ref = _full_direct(ti, tr, dp, sigma, drop_c3=True, drop_forward=True)
        np.testing.assert_allclose(_qualitative(ti, tr, dp, sigma), ref, rtol=1e-12, err_msg=sigma)


def test_oren_nayar_qualitative_equals_full_model_where_dropped_terms_vanish():
    ti, tr, dp = _grid(89.0, [0.0])  # retroreflection side of the plane of incidence
    for sigma in SIGMAS:
        ref = _full_direct(ti, tr, dp, sigma)
        np.testing.assert_allclose(_qualitative(ti, tr, dp, sigma), ref, rtol=1e-12, err_msg=sigma)
    ti, tr, dp = _grid(89.0, np.linspace(0.0, np.pi, 13))  # smooth: Lambert
    np.testing.assert_allclose(_qualitative(ti, tr, dp, 0.0), _full_direct(ti, tr, dp, 0.0))
    np.testing.assert_allclose(_full_direct(ti, tr, dp, 0.0), 1.0, rtol=1e-15)


def test_oren_nayar_qualitative_close_to_full_model_in_backscatter_half():
    ti, tr, dp = _grid(60.0, np.linspace(0.0, np.pi / 2, 7))
    worst = 0.0
    for sigma in (0.1, 0.25, 0.5):
        ref = _full_direct(ti, tr, dp, sigma)
        rel = np.abs(_qualitative(ti, tr, dp, sigma) / ref - 1.0)
        assert rel.max() <= 0.041, (sigma, rel.max())
        worst = max(worst, rel.max())
    assert worst > 0.02  # the grid reaches the region where the dropped C3 term matters
