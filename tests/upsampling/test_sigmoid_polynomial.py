"""The sigmoid-polynomial model (thesis eq. 2.25-2.26)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads

import radiometria.upsampling as up

THESIS = np.array([-0.000073447, 0.035354, -2.607])  # thesis fig. 2.4, nm coefficients


def test_sigmoid_jakob2019_matches_formula():
    x = np.linspace(-50.0, 50.0, 2001)
    ref = 0.5 + x / (2.0 * np.sqrt(1.0 + x * x))
    np.testing.assert_allclose(np.asarray(up.sigmoid_jakob2019(x)), ref, rtol=1e-13, atol=1e-15)


def test_sigmoid_jakob2019_limits_and_tail_precision():
    s = np.asarray(up.sigmoid_jakob2019(np.array([-np.inf, np.inf, 0.0, np.nan, -1e200, 1e200])))
    assert s[0] == 0.0 and s[1] == 1.0 and s[2] == 0.5 and np.isnan(s[3])
    assert s[4] == 0.0 and s[5] == 1.0
    # Lower tail: s(-x) ~ 1 / (4 x^2); the stable form keeps full relative precision.
    x = np.array([1e3, 1e6, 1e9])
    np.testing.assert_allclose(np.asarray(up.sigmoid_jakob2019(-x)), 1 / (4 * x * x), rtol=1e-5)
    s32 = np.asarray(up.sigmoid_jakob2019(jnp.asarray(-x, jnp.float32)))
    np.testing.assert_allclose(s32, 1 / (4 * x * x), rtol=1e-5)


def test_sigmoid_jakob2019_grad():
    g = jax.vmap(jax.grad(up.sigmoid_jakob2019))(
        jnp.array([-jnp.inf, -1e30, -3.0, 0.0, 2.0, 1e30, jnp.inf])
    )
    assert np.all(np.isfinite(np.asarray(g)))
    np.testing.assert_allclose(
        np.asarray(g)[2:5], 0.5 * (1 + np.array([9.0, 0.0, 4.0])) ** -1.5, rtol=1e-13
    )
    check_grads(up.sigmoid_jakob2019, (jnp.array([-2.0, 0.3, 5.0]),), order=2)


def test_sigmoid_polynomial_thesis_coefficients():
    wl = np.linspace(360.0, 830.0, 48)
    x = (THESIS[0] * wl + THESIS[1]) * wl + THESIS[2]
    ref = 0.5 + x / (2 * np.sqrt(1 + x * x))
    np.testing.assert_allclose(
        np.asarray(up.sigmoid_polynomial_jakob2019(THESIS, wl)), ref, rtol=1e-13
    )
    np.testing.assert_allclose(
        np.asarray(up.SigmoidPolynomialSpectrum(THESIS)(wl)), ref, rtol=1e-13
    )


def test_coefficient_conversion_roundtrip():
    c = np.random.default_rng(0).normal(size=(50, 3)) * np.array([100.0, 100.0, 10.0])
    nm = up.normalised_to_nm_coefficients(c)
    np.testing.assert_allclose(
        np.asarray(up.nm_to_normalised_coefficients(nm)), c, rtol=1e-9, atol=1e-9
    )
    wl = np.linspace(360.0, 830.0, 11)
    lam = (wl - 360.0) / 470.0
    p_norm = (c[:, :1] * lam + c[:, 1:2]) * lam + c[:, 2:]
    nm = np.asarray(nm)
    p_nm = (nm[:, :1] * wl + nm[:, 1:2]) * wl + nm[:, 2:]
    np.testing.assert_allclose(p_nm, p_norm, rtol=1e-9, atol=1e-8)


def test_spectrum_batch_shapes():
    c = np.zeros((5, 2, 3))
    spec = up.SigmoidPolynomialSpectrum(c)
    assert spec(np.linspace(400, 700, 4)).shape == (5, 2, 4)
    assert spec(np.ones((5, 2, 4)) * 500.0).shape == (5, 2, 4)
    assert spec(550.0).shape == (5, 2)
    with pytest.raises(ValueError, match="coeffs"):
        up.SigmoidPolynomialSpectrum(np.zeros((4, 2)))


def test_spectrum_jit_vmap_grad():
    spec = up.SigmoidPolynomialSpectrum(THESIS)
    wl = jnp.linspace(380.0, 780.0, 9)
    np.testing.assert_allclose(
        np.asarray(jax.jit(lambda s, w: s(w))(spec, wl)), np.asarray(spec(wl))
    )
    batch = up.SigmoidPolynomialSpectrum(np.tile(THESIS, (3, 1)))
    v = jax.vmap(lambda c: up.SigmoidPolynomialSpectrum(c)(wl))(batch.coeffs)
    np.testing.assert_allclose(np.asarray(v), np.asarray(batch(wl)))
    g = jax.grad(lambda c: up.SigmoidPolynomialSpectrum(c)(wl).sum())(jnp.asarray(THESIS))
    assert np.all(np.isfinite(np.asarray(g)))


def test_max_value():
    rng = np.random.default_rng(1)
    c = up.normalised_to_nm_coefficients(rng.normal(size=(20, 3)) * 20)
    spec = up.SigmoidPolynomialSpectrum(c)
    dense = np.asarray(spec(np.linspace(360.0, 830.0, 20001))).max(axis=-1)
    np.testing.assert_allclose(np.asarray(spec.max_value()), dense, rtol=1e-6, atol=1e-9)
