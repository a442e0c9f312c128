"""The fit of thesis eq. 2.27: forward model, residual, Jacobian, solvers."""

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
import pytest

import radiometria.colorimetry as cm
import radiometria.upsampling as up
from radiometria.upsampling._lm import (
    ModelArrays,
    _lm_direction,
    residual,
    residual_and_jacobian,
    target_Lab,
)


def test_forward_model_white_is_exact():
    for space in ["sRGB", "Display P3", "Rec.2020", "ACES2065-1", "ProPhoto RGB"]:
        m = up.forward_model(space)
        assert m.wavelengths_nm.shape == (471,) and m.wavelengths_nm[1] - m.wavelengths_nm[0] == 1.0
        # A flat spectrum maps exactly to the space's white: RGB (1, 1, 1).
        np.testing.assert_allclose(m.weights_XYZ.sum(0), m.white_XYZ, rtol=1e-14)
        rgb = m.weights_XYZ.sum(0) @ m.matrix_XYZ_to_RGB.T
        np.testing.assert_allclose(rgb, 1.0, rtol=1e-13)
        assert np.all(np.abs(m.rgb_gain - 1) < 5e-4), m.rgb_gain


def test_forward_model_uses_the_colorimetry():
    m = up.forward_model("sRGB")
    with jax.enable_x64(True):
        w = np.asarray(cm.tristimulus_weights(jnp.asarray(m.wavelengths_nm), "D65"))
        xyz = jnp.asarray([[0.2, 0.3, 0.4], [0.9, 1.0, 1.05]])
        lab_ref = np.asarray(cm.XYZ_to_Lab(xyz, jnp.asarray(m.white_XYZ)))
        from radiometria.upsampling._forward import XYZ_to_Lab_white

        lab = np.asarray(XYZ_to_Lab_white(xyz, jnp.asarray(m.white_XYZ)))
    # The balanced weights differ from the plain CIE weights only by the white-balance gain.
    balanced = (w @ m.matrix_XYZ_to_RGB.T * m.rgb_gain) @ m.matrix_RGB_to_XYZ.T
    np.testing.assert_allclose(m.weights_XYZ, balanced, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(lab, lab_ref, rtol=1e-13)
    # Illuminant normalised to unit relative luminance.
    cmf = np.asarray(cm.get_cmfs().values)[:, 1]
    np.testing.assert_allclose((m.illuminant * cmf).sum() / cmf.sum(), 1.0, rtol=1e-12)


def test_forward_model_rejects_bad_arguments():
    with pytest.raises(ValueError, match="colourspace"):
        up.forward_model("no such space")
    with pytest.raises(ValueError, match="step_nm"):
        up.forward_model("sRGB", step_nm=0.7)


def test_residual_and_jacobian_match_jacfwd():
    m = ModelArrays.build(up.forward_model("sRGB"), jnp.float64)
    rng = np.random.default_rng(0)
    c = jnp.asarray(rng.normal(size=(16, 3)) * np.array([30.0, 30.0, 5.0]))
    rgb = jnp.asarray(rng.random((16, 3)))
    r, J = jax.jit(lambda c, t: residual_and_jacobian(c, target_Lab(t, m), m))(c, rgb)
    r_ref = jax.jit(lambda c, t: residual(c, t, m))(c, rgb)
    J_ref = jax.jit(jax.vmap(jax.jacfwd(lambda cc, t: residual(cc, t, m))))(c, rgb)
    np.testing.assert_allclose(np.asarray(r), np.asarray(r_ref), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.asarray(J), np.asarray(J_ref), rtol=1e-9, atol=1e-12)
    # Chunked evaluation gives the same.
    r2, J2 = jax.jit(lambda c, t: residual_and_jacobian(c, target_Lab(t, m), m, chunk=5))(c, rgb)
    np.testing.assert_allclose(np.asarray(J2), np.asarray(J), rtol=1e-12, atol=1e-14)


def test_lm_direction_is_the_damped_least_squares_step():
    rng = np.random.default_rng(1)
    J = rng.normal(size=(20, 3, 3))
    r = rng.normal(size=(20, 3))
    mu = 10.0 ** rng.uniform(-8, 2, size=20)
    delta = np.asarray(_lm_direction(jnp.asarray(J), jnp.asarray(r), jnp.asarray(mu)))
    for k in range(20):
        d = np.sqrt(mu[k]) * np.linalg.norm(J[k], axis=0)
        A = np.vstack([J[k], np.diag(d)])
        b = np.concatenate([-r[k], np.zeros(3)])
        np.testing.assert_allclose(
            delta[k], np.linalg.lstsq(A, b, rcond=None)[0], rtol=1e-8, atol=1e-10
        )


def test_fit_rgb_converges(direct_fit):
    rgb, fit = direct_fit
    ok = np.asarray(fit.result._value == optx.RESULTS.successful._value)
    assert ok.all(), rgb[~ok]
    assert np.asarray(fit.residual).max() < 1e-8
    # nm and normalised coefficients describe the same polynomial.
    np.testing.assert_allclose(
        np.asarray(up.nm_to_normalised_coefficients(fit.coeffs))[:24],
        np.asarray(fit.coeffs_normalised)[:24],
        rtol=1e-9,
        atol=1e-9,
    )


def test_fit_rgb_greys_black_white(direct_fit):
    rgb, fit = direct_fit
    c = np.asarray(fit.coeffs)
    black, white, grey = c[24], c[25], c[26]
    assert black[0] == black[1] == 0 and black[2] == -np.inf
    assert white[0] == white[1] == 0 and white[2] == np.inf
    wl = np.linspace(360.0, 830.0, 50)
    np.testing.assert_array_equal(np.asarray(up.SigmoidPolynomialSpectrum(black)(wl)), 0.0)
    np.testing.assert_array_equal(np.asarray(up.SigmoidPolynomialSpectrum(white)(wl)), 1.0)
    np.testing.assert_allclose(np.asarray(up.SigmoidPolynomialSpectrum(grey)(wl)), 0.3, rtol=1e-14)


def test_lut_agrees_with_direct_fit(direct_fit):
    """Table nodes: the lookup returns the entry, which is the direct fit's solution."""
    rgb, fit = direct_fit
    lut = up.get_lut()
    c_lut = np.asarray(lut.coefficients(rgb[27:]))
    c_fit = np.asarray(fit.coeffs)[27:]
    np.testing.assert_allclose(c_lut, c_fit, rtol=2e-3, atol=1e-7)
    # Between nodes both reproduce the colour; the direct fit exactly, the table within 0.5.
    de_lut, _ = up.roundtrip_delta_E(lut, rgb[:24])
    assert de_lut.max() < 0.5


def test_fit_rgb_rejects_bad_rgb():
    for bad, match in [([-0.1, 0.2, 0.3], "negative"), ([np.nan, 0.2, 0.3], "non-finite"),
                       ([1.5, 0.2, 0.3], "> 1")]:  # fmt: skip
        with pytest.raises(ValueError, match=match):
            up.fit_rgb(np.array(bad))
    with pytest.raises((ValueError, TypeError), match="last axis|3"):
        up.fit_rgb(np.zeros((2, 4)))


@pytest.mark.slow
def test_fit_rgb_gauss_newton():
    rgb = np.array([[0.2, 0.5, 0.1], [0.7, 0.3, 0.6]])
    lm = up.fit_rgb(rgb)
    gn = up.fit_rgb(
        rgb, solver=optx.GaussNewton(rtol=1e-10, atol=1e-10), y0=lm.coeffs_normalised * 0.9
    )
    np.testing.assert_allclose(
        np.asarray(gn.coeffs_normalised), np.asarray(lm.coeffs_normalised), rtol=1e-6
    )
