"""The infrared-tail ratio of `_tails.py` (pbrt-v4 #82): value against the spectrum evaluated
by the public sigmoid polynomial, gradient against finite differences."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.upsampling as up
from radiometria.upsampling._lm import ModelArrays
from radiometria.upsampling._sigmoid_polynomial import normalised_to_nm_coefficients
from radiometria.upsampling._tails import log_tail_ratio, penalised_residual_and_jacobian


@pytest.fixture(scope="module")
def model():
    fm = up.forward_model("sRGB")
    return fm, ModelArrays.build(fm, jnp.float64)


def _coefficients(n, seed):
    """Normalised coefficients of bright, dark, rising and bump-shaped spectra."""
    rng = np.random.default_rng(seed)
    u = lambda lo, hi: rng.uniform(lo, hi, n)  # noqa: E731
    return np.concatenate([
        rng.normal(0.0, 20.0, (n, 3)),
        np.column_stack([u(-1500, -200), u(300, 2500), u(-900, -100)]),
        np.column_stack([u(100, 400), u(-300, -100), u(-40, 0)]),
    ])  # fmt: skip


def test_log_tail_ratio_matches_the_evaluated_spectrum(model):
    """The closed-form maxima against the spectrum on a 0.01 nm grid (public evaluator)."""
    _, m = model
    c = _coefficients(40, 0)
    q, _ = log_tail_ratio(jnp.asarray(c), m)
    wl = np.linspace(360.0, 830.0, 47_001)
    s = np.asarray(up.sigmoid_polynomial_jakob2019(normalised_to_nm_coefficients(c), wl))
    expected = np.log(s[:, wl >= 730].max(1)) - np.log(s[:, wl <= 730].max(1))
    np.testing.assert_allclose(np.asarray(q), expected, rtol=1e-6, atol=1e-6)


def test_log_tail_ratio_gradient_matches_finite_differences(model):
    _, m = model
    c = _coefficients(10, 1)
    _, g = log_tail_ratio(jnp.asarray(c), m)
    h = 1e-6 * np.maximum(1.0, np.abs(c))
    for i in range(3):
        e = np.zeros(3)
        e[i] = 1.0
        qp, _ = log_tail_ratio(jnp.asarray(c + h[:, i : i + 1] * e), m)
        qm, _ = log_tail_ratio(jnp.asarray(c - h[:, i : i + 1] * e), m)
        fd = (np.asarray(qp) - np.asarray(qm)) / (2 * h[:, i])
        np.testing.assert_allclose(np.asarray(g)[:, i], fd, rtol=1e-5, atol=1e-7)


def test_penalised_residual_is_the_colour_residual_without_a_tail(model):
    """The hinge is zero (value and Jacobian) below the bound; above it, w (ln q - ln T)."""
    _, m = model
    c = jnp.asarray(_coefficients(20, 2))
    lab_t = jnp.zeros((c.shape[0], 3))
    q, g = log_tail_ratio(c, m)
    bound = jnp.log(2.0)
    r, J = penalised_residual_and_jacobian(c, lab_t, m, bound, 10.0)
    tail = np.asarray(q) > np.log(2.0)
    assert tail.any() and (~tail).any()
    np.testing.assert_array_equal(np.asarray(r)[~tail, 3], 0.0)
    np.testing.assert_array_equal(np.asarray(J)[~tail, 3], 0.0)
    np.testing.assert_allclose(np.asarray(r)[tail, 3], 10.0 * (np.asarray(q)[tail] - np.log(2.0)))
    np.testing.assert_allclose(np.asarray(J)[tail, 3], 10.0 * np.asarray(g)[tail])
    # The colour rows are eq. 2.27's, whose Jacobian matches jax.jacfwd of the residual.
    jac = jax.vmap(
        jax.jacfwd(
            lambda c1: penalised_residual_and_jacobian(c1[None], lab_t[:1], m, bound, 10.0)[0][0]
        )
    )(c)
    np.testing.assert_allclose(np.asarray(J), np.asarray(jac), rtol=1e-7, atol=1e-9)
