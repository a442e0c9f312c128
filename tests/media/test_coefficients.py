"""Coefficients, optical depth and the absorption index / complex index of thesis section 1.3."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads
from scipy import integrate

import radiometria.media as md
from radiometria.radiometry import beer_lambert_transmittance, wavenumber_vacuum


def test_extinction_and_albedo_roundtrip():
    rng = np.random.default_rng(0)
    sa, ss = rng.uniform(0, 5, 50), rng.uniform(0, 5, 50)
    st = md.extinction_coefficient(sa, ss)
    np.testing.assert_allclose(st, sa + ss, rtol=1e-15)
    rho = md.single_scattering_albedo(ss, st)
    a2, s2 = md.coefficients_from_albedo(st, rho)
    np.testing.assert_allclose(a2, sa, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(s2, ss, rtol=1e-12)


def test_single_scattering_albedo_vacuum_is_zero_with_finite_grad():
    assert float(md.single_scattering_albedo(0.0, 0.0)) == 0.0
    g = jax.grad(lambda s: md.single_scattering_albedo(0.0, s))(0.0)
    assert np.isfinite(g)


def test_optical_depth_homogeneous_and_beer_lambert():
    st = jnp.array([0.0, 0.3, 2.0, 10.0])
    d = jnp.array([5.0, 1.5, 0.25, 0.1])
    tau = md.optical_depth(st, d)
    np.testing.assert_allclose(tau, st * d, rtol=1e-15)
    # Pure absorption: e^{-tau} is thesis eq. 1.12.
    np.testing.assert_allclose(
        md.homogeneous_transmittance(st, d), beer_lambert_transmittance(st, d), rtol=1e-15
    )


def test_optical_depth_vacuum_infinite_distance():
    assert float(md.optical_depth(0.0, jnp.inf)) == 0.0
    assert float(md.homogeneous_transmittance(0.0, jnp.inf)) == 1.0
    assert float(md.homogeneous_transmittance(0.5, jnp.inf)) == 0.0
    g = jax.grad(lambda s: md.optical_depth(s, jnp.inf))(0.0)
    assert not np.isnan(g)


def test_penetration_depth_is_one_over_e():
    st = jnp.array([0.1, 1.0, 25.0])
    delta = md.penetration_depth(st)
    np.testing.assert_allclose(beer_lambert_transmittance(st, delta), math.exp(-1), rtol=1e-14)
    assert float(md.penetration_depth(0.0)) == math.inf


def _ray(direction=(0.3, -0.4, 0.866)):
    w = np.asarray(direction, float)
    w = w / np.linalg.norm(w)
    return jnp.array([[0.1, 0.2, -0.3]]), jnp.asarray(w[None, :])


FIELDS = {
    # name: (field of points (..., 3), tau(o, w, d) closed form)
    "constant": (lambda x: 1.7 + 0.0 * x[..., 0], lambda o, w, d: 1.7 * d),
    "ramp": (
        lambda x: 0.5 + 0.8 * x[..., 2] + 0.3 * x[..., 0],
        lambda o, w, d: (0.5 + 0.8 * o[2] + 0.3 * o[0]) * d + (0.8 * w[2] + 0.3 * w[0]) * d**2 / 2,
    ),
    "sinusoid": (
        lambda x: 1.0 + 0.6 * jnp.sin(4.0 * x[..., 2]),
        lambda o, w, d: d + 0.6 * (np.cos(4 * o[2]) - np.cos(4 * (o[2] + w[2] * d))) / (4 * w[2]),
    ),
}


@pytest.mark.parametrize("name", list(FIELDS))
def test_optical_depth_along_ray_closed_forms(name):
    f, tau = FIELDS[name]
    o, w = _ray()
    for d in [0.0, 0.4, 2.5]:
        got = md.optical_depth_along_ray(f, o, w, jnp.array([d]))
        want = tau(np.asarray(o[0]), np.asarray(w[0]), d)
        np.testing.assert_allclose(got, [want], rtol=1e-12, atol=1e-14)


def test_optical_depth_along_ray_matches_scipy_quad():
    def f(x):
        return 2.0 * jnp.exp(-jnp.sum((x - 0.5) ** 2, axis=-1) / 0.1)

    o, w = _ray((1.0, 1.0, 1.0))
    d = 2.0
    want, _ = integrate.quad(lambda t: float(f(o[0] + t * w[0])), 0.0, d, epsabs=1e-13)
    got = md.optical_depth_along_ray(f, o, w, jnp.array([d]), n_points=64)
    np.testing.assert_allclose(got, [want], rtol=1e-10)


def test_optical_depth_along_ray_grad_and_batch():
    o = jnp.zeros((4, 3))
    w = jnp.tile(jnp.array([0.0, 0.0, 1.0]), (4, 1))
    d = jnp.array([0.5, 1.0, 1.5, 2.0])

    def tau(a):
        return md.optical_depth_along_ray(lambda x: a * (1.0 + x[..., 2]), o, w, d)

    np.testing.assert_allclose(tau(2.0), 2.0 * (d + d**2 / 2), rtol=1e-13)
    check_grads(tau, (2.0,), order=1, modes=["rev"])
    np.testing.assert_allclose(jax.jit(tau)(2.0), tau(2.0), rtol=1e-14)


def test_absorption_index_glass_and_roundtrip():
    # Thesis table 1.1: glass at 550 nm, kappa_a = 0.1 cm^-1 = 10 m^-1.
    kappa = md.absorption_index_from_coefficient(10.0, 550.0)
    np.testing.assert_allclose(kappa, 10.0 * 550e-9 / (4 * math.pi), rtol=1e-14)
    rng = np.random.default_rng(1)
    ka = rng.uniform(0, 1e7, 20)
    lam = rng.uniform(300, 900, 20)
    back = md.absorption_coefficient_from_index(md.absorption_index_from_coefficient(ka, lam), lam)
    np.testing.assert_allclose(back, ka, rtol=1e-14)


def test_complex_index_and_wavenumber_relations():
    rng = np.random.default_rng(2)
    eta = rng.uniform(1.0, 3.0, 16)
    ka = rng.uniform(0, 1e6, 16)
    lam = rng.uniform(380, 780, 16)
    n_c = md.complex_refractive_index(eta, ka, lam)
    k_c = md.complex_wavenumber(eta, ka, lam)
    assert n_c.dtype == jnp.complex128
    k0 = np.asarray(wavenumber_vacuum(lam))
    np.testing.assert_allclose(np.real(n_c), eta, rtol=1e-15)
    np.testing.assert_allclose(np.imag(n_c), ka / (2 * k0), rtol=1e-14)
    np.testing.assert_allclose(k_c, k0 * np.asarray(n_c), rtol=1e-14)  # k = k0 eta_complex
    np.testing.assert_allclose(
        md.absorption_coefficient_from_complex_wavenumber(k_c), ka, rtol=1e-14
    )
    np.testing.assert_allclose(
        md.absorption_coefficient_from_complex_refractive_index(n_c, lam), ka, rtol=1e-13
    )


def test_complex_wavenumber_intensity_decay_is_beer_lambert():
    # Eq. 1.11-1.12: |E0 exp(i k_c z)|^2 = exp(-kappa_a z) I0.
    ka, lam = 2.5e3, 600.0
    z = jnp.linspace(0.0, 2e-3, 9)
    k_c = md.complex_wavenumber(1.5, ka, lam)
    intensity = np.abs(np.exp(1j * np.asarray(k_c) * np.asarray(z))) ** 2
    np.testing.assert_allclose(intensity, beer_lambert_transmittance(ka, z), rtol=1e-12)


@pytest.mark.parametrize(
    "fn,args,name",
    [
        (md.extinction_coefficient, (-1.0, 1.0), "sigma_a"),
        (md.single_scattering_albedo, (1.0, -2.0), "sigma_t"),
        (md.coefficients_from_albedo, (1.0, 1.5), "albedo"),
        (md.optical_depth, (1.0, -1.0), "distance"),
        (md.absorption_index_from_coefficient, (-1.0, 500.0), "kappa_a"),
        (md.complex_refractive_index, (0.0, 1.0, 500.0), "eta"),
    ],
)
def test_coefficients_reject_bad_input(fn, args, name):
    with pytest.raises(eqx.EquinoxRuntimeError, match=name):
        eqx.filter_jit(fn)(*args)
