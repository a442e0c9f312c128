"""Eq. 1.13 for any radiance distribution: closed forms, SciPy's dblquad, jit/vmap/grad."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate

from radiometria.radiometry import (
    irradiance_from_radiance,
    irradiance_from_radiance_distribution,
)


@pytest.mark.parametrize("half_angle", [0.05, 0.6, 1.2, math.pi / 2])
def test_irradiance_distribution_uniform_cone_matches_closed_form(half_angle):
    # Uniform L over the cone theta <= theta_0: E = pi L sin^2(theta_0) (irradiance_from_radiance).
    radiance = 2.5
    E = irradiance_from_radiance_distribution(
        lambda t, p: jnp.full_like(t, radiance), (0.0, half_angle), n_theta=8, n_phi=1
    )
    np.testing.assert_allclose(E, irradiance_from_radiance(radiance, half_angle), rtol=1e-14)
    # A scalar-returning (constant) radiance function is broadcast.
    E_scalar = irradiance_from_radiance_distribution(lambda t, p: 2.5, (0.0, half_angle))
    np.testing.assert_allclose(E_scalar, E, rtol=1e-14)


@pytest.mark.parametrize("n", [0, 1, 2, 5, 10])
@pytest.mark.parametrize("theta_0", [0.7, math.pi / 2])
def test_irradiance_distribution_cosine_power_closed_form(n, theta_0):
    # L = cos^n(theta): E = 2 pi int_0^theta0 cos^(n+1) sin = 2 pi (1 - cos^(n+2) theta0) / (n + 2)
    E = irradiance_from_radiance_distribution(
        lambda t, p: jnp.cos(t) ** n, (0.0, theta_0), n_theta=16, n_phi=2
    )
    expected = 2.0 * math.pi * (1.0 - math.cos(theta_0) ** (n + 2)) / (n + 2)
    np.testing.assert_allclose(E, expected, rtol=1e-13)


def _radiance(t, p, xp=jnp):
    """A smooth, anisotropic sky-like radiance [W sr^-1 m^-2] (theta, phi in rad)."""
    return (
        1.0
        + 0.6 * xp.cos(p - 0.4) * xp.sin(t)
        + 0.3 * xp.exp(-3.0 * (t - 0.8) ** 2) * (1.0 + xp.sin(2.0 * p))
    )


@pytest.mark.parametrize(
    ("theta_bounds", "phi_bounds"),
    [((0.0, math.pi / 2), (0.0, 2 * math.pi)), ((0.2, 1.1), (0.3, 4.0)), ((0.5, 0.6), (-1.0, 1.0))],
)
def test_irradiance_distribution_matches_scipy_dblquad(theta_bounds, phi_bounds):
    E = irradiance_from_radiance_distribution(_radiance, theta_bounds, phi_bounds, n_theta=24)
    # dblquad integrates func(y, x) with x in [a, b] outer: x = theta, y = phi.
    ref, err = integrate.dblquad(
        lambda p, t: _radiance(t, p, np) * math.cos(t) * math.sin(t),
        *theta_bounds,
        *phi_bounds,
        epsabs=1e-13,
        epsrel=1e-13,
    )
    np.testing.assert_allclose(E, ref, rtol=1e-11)


def test_irradiance_distribution_spectral_channels_and_convergence():
    # A spectral radiance (theta, phi, 3 wavelengths) integrates channel by channel.
    scale = jnp.array([1.0, 2.0, 0.5])
    E = irradiance_from_radiance_distribution(
        lambda t, p: jnp.cos(t)[..., None] * scale[None, None, :], n_theta=16, n_phi=3
    )
    assert E.shape == (3,)
    np.testing.assert_allclose(E, 2.0 * math.pi / 3.0 * np.asarray(scale), rtol=1e-14)
    # A radiance with a kink (|phi - pi|) converges, but only algebraically.
    errors = []
    for n in (4, 16, 64):
        E_n = irradiance_from_radiance_distribution(
            lambda t, p: jnp.abs(p - math.pi), n_theta=4, n_phi=n
        )
        errors.append(abs(float(E_n) - 0.5 * math.pi**2))  # (1/2) int_0^2pi |phi - pi| dphi
    assert errors[0] > errors[1] > errors[2] and errors[2] < 1e-3


def test_irradiance_distribution_jit_vmap_grad():
    def E_of(theta_0, k):
        return irradiance_from_radiance_distribution(
            lambda t, p: k * jnp.cos(t), (0.0, theta_0), n_theta=8, n_phi=1
        )

    theta_0, k = jnp.asarray(0.9), jnp.asarray(1.7)
    eager = E_of(theta_0, k)
    np.testing.assert_allclose(jax.jit(E_of)(theta_0, k), eager, rtol=1e-15)
    thetas = jnp.linspace(0.1, 1.5, 5)
    np.testing.assert_allclose(
        jax.vmap(E_of, in_axes=(0, None))(thetas, k),
        2.0 * math.pi * float(k) * (1.0 - np.cos(thetas) ** 3) / 3.0,
        rtol=1e-12,
    )
    # dE/dtheta_0 = 2 pi L(theta_0) cos sin (the integrand on the boundary); dE/dk = E / k.
    g_theta, g_k = jax.grad(E_of, argnums=(0, 1))(theta_0, k)
    np.testing.assert_allclose(
        g_theta, 2.0 * math.pi * 1.7 * math.cos(0.9) ** 2 * math.sin(0.9), rtol=1e-13
    )
    np.testing.assert_allclose(g_k, eager / k, rtol=1e-14)
    # Through equinox.filter_jit, with the radiance function passed as an argument.
    jitted = eqx.filter_jit(irradiance_from_radiance_distribution)
    np.testing.assert_allclose(jitted(_radiance, n_theta=24), _reference_hemisphere(), rtol=1e-11)


def _reference_hemisphere():
    ref, _ = integrate.dblquad(
        lambda p, t: _radiance(t, p, np) * math.cos(t) * math.sin(t),
        0.0,
        math.pi / 2,
        0.0,
        2 * math.pi,
        epsabs=1e-13,
        epsrel=1e-13,
    )
    return ref


@pytest.mark.parametrize("dtype", [jnp.float32, jnp.float64])
def test_irradiance_distribution_dtype(dtype):
    bounds = (jnp.asarray(0.0, dtype), jnp.asarray(1.0, dtype))
    E = irradiance_from_radiance_distribution(
        lambda t, p: jnp.cos(t) ** 2, bounds, (jnp.asarray(0.0, dtype), jnp.asarray(2.0, dtype))
    )
    assert E.dtype == dtype
    rtol = {jnp.float32: 1e-6, jnp.float64: 1e-14}[dtype]
    np.testing.assert_allclose(E, 2.0 * (1.0 - math.cos(1.0) ** 4) / 4.0, rtol=rtol)


def test_irradiance_distribution_rejects_bad_input():
    def L(t, p):
        return jnp.ones_like(t)

    with pytest.raises(eqx.EquinoxRuntimeError, match="theta_bounds"):
        irradiance_from_radiance_distribution(L, (0.0, 2.0))
    with pytest.raises(eqx.EquinoxRuntimeError, match="theta_bounds"):
        irradiance_from_radiance_distribution(L, (1.0, 0.5))
    with pytest.raises(eqx.EquinoxRuntimeError, match="phi_bounds"):
        irradiance_from_radiance_distribution(L, phi_bounds=(1.0, 0.0))
    with pytest.raises(eqx.EquinoxRuntimeError, match="theta_bounds"):
        eqx.filter_jit(irradiance_from_radiance_distribution)(L, (jnp.asarray(-0.1), 1.0))
    with pytest.raises(ValueError, match="theta_bounds"):
        irradiance_from_radiance_distribution(L, (0.0, 0.5, 1.0))
    with pytest.raises(ValueError, match="phi_bounds"):
        irradiance_from_radiance_distribution(L, phi_bounds=(jnp.zeros(2), 1.0))
    with pytest.raises(ValueError, match="radiance_fn"):
        irradiance_from_radiance_distribution(lambda t, p: jnp.ones(3), n_theta=4, n_phi=4)
    with pytest.raises(TypeError, match="radiance_fn"):
        irradiance_from_radiance_distribution(lambda t, p: jnp.ones(t.shape, dtype=jnp.int32))
    with pytest.raises(TypeError, match="radiance_fn"):
        irradiance_from_radiance_distribution(3.0)
    with pytest.raises(ValueError, match="n_theta"):
        irradiance_from_radiance_distribution(L, n_theta=0)
    with pytest.raises(TypeError, match="n_phi"):
        irradiance_from_radiance_distribution(L, n_phi=4.0)
