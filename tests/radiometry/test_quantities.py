"""Closed-form radiometric relations (thesis sections 1.1-1.4), checked against integrals."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads
from scipy import integrate

from radiometria import constants as c
from radiometria.radiometry import (
    basic_radiance,
    beer_lambert_transmittance,
    etendue,
    exitance_from_radiance,
    flux_from_intensity,
    frequency_to_wavelength,
    intensity_from_flux,
    irradiance_from_intensity,
    irradiance_from_radiance,
    lambert_intensity,
    photon_energy,
    radiance_from_basic_radiance,
    radiance_from_exitance,
    radiance_from_irradiance,
    radiant_energy,
    radiosity,
    spectral_density_per_hz_to_per_nm,
    spectral_density_per_nm_to_per_hz,
    wavelength_to_frequency,
)


@pytest.mark.parametrize("half_angle", [0.1, 0.7, 1.2, math.pi / 2])
def test_irradiance_from_radiance_matches_eq_1_13_integral(half_angle):
    # E = int_0^2pi int_0^theta0 L cos(theta) sin(theta) dtheta dphi (eq. 1.13), by quadrature.
    radiance = 3.5
    inner, _ = integrate.quad(lambda t: radiance * math.cos(t) * math.sin(t), 0.0, half_angle)
    assert float(irradiance_from_radiance(radiance, half_angle)) == pytest.approx(
        2 * math.pi * inner, rel=1e-12
    )


def test_irradiance_hemisphere_and_exitance_are_pi_radiance():
    radiance = jnp.asarray([0.0, 1.0, 2.5])
    np.testing.assert_allclose(irradiance_from_radiance(radiance), math.pi * radiance, rtol=1e-15)
    np.testing.assert_allclose(exitance_from_radiance(radiance), math.pi * radiance, rtol=1e-15)


def test_radiometric_inverses_roundtrip():
    x = jnp.asarray([0.5, 2.0, 7.0])
    angle = jnp.asarray([0.2, 0.9, 1.5])
    np.testing.assert_allclose(
        radiance_from_irradiance(irradiance_from_radiance(x, angle), angle), x, rtol=1e-14
    )
    np.testing.assert_allclose(radiance_from_exitance(exitance_from_radiance(x)), x, rtol=1e-15)
    np.testing.assert_allclose(flux_from_intensity(intensity_from_flux(x)), x, rtol=1e-15)
    np.testing.assert_allclose(
        radiance_from_basic_radiance(basic_radiance(x, 1.5), 1.5), x, rtol=1e-15
    )
    np.testing.assert_allclose(
        frequency_to_wavelength(wavelength_to_frequency(x * 300.0)), x * 300.0, rtol=1e-15
    )
    nu = wavelength_to_frequency(x * 300.0)
    np.testing.assert_allclose(
        spectral_density_per_hz_to_per_nm(spectral_density_per_nm_to_per_hz(x, x * 300.0), nu),
        x,
        rtol=1e-14,
    )


def test_isotropic_point_source_flux_through_sphere():
    # The flux of an isotropic source through any sphere around it is its total flux.
    flux, radius = 100.0, 2.5
    irradiance = irradiance_from_intensity(intensity_from_flux(flux), radius)
    assert float(irradiance * 4 * math.pi * radius**2) == pytest.approx(flux, rel=1e-15)


def test_irradiance_from_intensity_inverse_square_and_cosine():
    e = irradiance_from_intensity(8.0, jnp.asarray([1.0, 2.0, 4.0]))
    np.testing.assert_allclose(e, [8.0, 2.0, 0.5], rtol=1e-15)
    cosines = jnp.asarray([1.0, 0.5, 0.0, -0.5])
    np.testing.assert_allclose(
        irradiance_from_intensity(8.0, 2.0, cosines), [2.0, 1.0, 0.0, 0.0], rtol=1e-15
    )


def test_lambert_intensity_integrates_to_pi_i0():
    # The flux of a Lambertian patch is the integral of I0 cos(theta) over the hemisphere = pi I0,
    # consistent with M = pi L (eq. 1.23) for I0 = L A.
    flux, _ = integrate.dblquad(
        lambda t, p: float(lambert_intensity(2.0, math.cos(t))) * math.sin(t),
        0.0,
        2 * math.pi,
        0.0,
        math.pi / 2,
    )
    assert flux == pytest.approx(math.pi * 2.0, rel=1e-10)
    assert float(lambert_intensity(2.0, -0.3)) == 0.0


def test_etendue_is_symmetric_and_gives_flux():
    g = etendue(0.01, 0.8, 0.02, 0.6, 3.0)
    assert float(g) == pytest.approx(0.01 * 0.8 * 0.02 * 0.6 / 9.0, rel=1e-15)
    assert float(etendue(0.02, 0.6, 0.01, 0.8, 3.0)) == pytest.approx(float(g), rel=1e-15)
    # In a medium of index eta, G scales with eta^2 and the flux L/eta^2 * G does not.
    assert float(etendue(0.01, 0.8, 0.02, 0.6, 3.0, 1.5)) == pytest.approx(
        2.25 * float(g), rel=1e-15
    )
    radiance = 5.0
    flux_vacuum = radiance * float(g)
    flux_glass = float(basic_radiance(radiance * 1.5**2, 1.5)) * float(
        etendue(0.01, 0.8, 0.02, 0.6, 3.0, 1.5)
    )
    assert flux_glass == pytest.approx(flux_vacuum * 2.25, rel=1e-15)
    assert float(etendue(0.01, -0.2, 0.02, 0.6, 3.0)) == 0.0


def test_basic_radiance_across_interface_eq_1_21():
    # L_o / eta_1^2 = L_i / eta_2^2 (eq. 1.21): radiance entering glass from air grows by 1.5^2.
    l_air = 2.0
    l_glass = radiance_from_basic_radiance(basic_radiance(l_air, 1.0), 1.5)
    assert float(l_glass) == pytest.approx(4.5, rel=1e-15)


def test_photon_energy_and_frequency():
    assert float(photon_energy(550.0)) == pytest.approx(
        c.PLANCK * c.SPEED_OF_LIGHT / 550e-9, rel=1e-15
    )
    assert float(wavelength_to_frequency(c.SPEED_OF_LIGHT / 540e12 * 1e9)) == pytest.approx(
        540e12, rel=1e-15
    )
    assert float(photon_energy(550.0)) == pytest.approx(
        c.PLANCK * float(wavelength_to_frequency(550.0)), rel=1e-15
    )


def test_beer_lambert_transmittance():
    # Thesis table 1.1: water vapour absorbs 1.5% per cm at 10.6 um, kappa_a = 1.5 cm^-1 = 150 m^-1.
    assert float(beer_lambert_transmittance(150.0, 0.01)) == pytest.approx(
        math.exp(-1.5), rel=1e-15
    )
    assert float(beer_lambert_transmittance(150.0, 1 / 150.0)) == pytest.approx(
        math.exp(-1), rel=1e-15
    )
    assert float(beer_lambert_transmittance(0.0, 5.0)) == 1.0


def test_radiometric_quantities_jit_vmap_grad():
    angle = jnp.asarray([0.1, 0.5, 1.0])
    radiance = jnp.asarray([1.0, 2.0, 3.0])
    np.testing.assert_allclose(
        jax.jit(irradiance_from_radiance)(radiance, angle),
        irradiance_from_radiance(radiance, angle),
        rtol=1e-15,
    )
    np.testing.assert_allclose(
        jax.vmap(irradiance_from_radiance)(radiance, angle),
        irradiance_from_radiance(radiance, angle),
        rtol=1e-15,
    )
    check_grads(irradiance_from_radiance, (2.0, 0.7), order=2)
    check_grads(irradiance_from_intensity, (2.0, 1.5, 0.3), order=2)
    check_grads(etendue, (0.01, 0.8, 0.02, 0.6, 3.0, 1.3), order=1)
    check_grads(lambda x: spectral_density_per_nm_to_per_hz(x, 500.0), (2.0,), order=1)
    # The hemisphere (pi/2) is the end of the range: the gradient there is finite (zero in angle).
    g = jax.grad(irradiance_from_radiance, argnums=1)(1.0, math.pi / 2)
    assert abs(float(g)) < 1e-12


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: irradiance_from_radiance(1.0, 2.0), "half_angle"),
        (lambda: irradiance_from_radiance(1.0, -0.1), "half_angle"),
        (lambda: radiance_from_irradiance(1.0, 0.0), "half_angle"),
        (lambda: irradiance_from_intensity(1.0, 0.0), "distance"),
        (lambda: irradiance_from_intensity(1.0, 1.0, 1.5), "cos_theta"),
        (lambda: lambert_intensity(1.0, -1.5), "cos_theta"),
        (lambda: etendue(-1.0, 1.0, 1.0, 1.0, 1.0), "area_source"),
        (lambda: etendue(1.0, 1.0, 1.0, 1.0, 1.0, 0.0), "eta"),
        (lambda: basic_radiance(1.0, -1.0), "eta"),
        (lambda: beer_lambert_transmittance(-1.0, 1.0), "absorption_coefficient"),
        (lambda: beer_lambert_transmittance(1.0, -1.0), "distance"),
        (lambda: photon_energy(0.0), "wavelength_nm"),
        (lambda: wavelength_to_frequency(-5.0), "wavelength_nm"),
        (lambda: frequency_to_wavelength(0.0), "frequency_hz"),
        (lambda: spectral_density_per_nm_to_per_hz(1.0, 0.0), "wavelength_nm"),
        (lambda: spectral_density_per_hz_to_per_nm(1.0, -1.0), "frequency_hz"),
    ],
)
def test_radiometric_quantities_reject_out_of_domain(call, match):
    with pytest.raises(eqx.EquinoxRuntimeError, match=match):
        call()


def test_radiometric_quantities_reject_out_of_domain_under_jit():
    with pytest.raises(eqx.EquinoxRuntimeError, match="distance"):
        eqx.filter_jit(irradiance_from_intensity)(jnp.asarray(1.0), jnp.asarray([1.0, -2.0]))


def test_radiometric_quantities_reject_integer_arrays():
    with pytest.raises(TypeError, match="radiance"):
        irradiance_from_radiance(np.array([1, 2]))
    with pytest.raises(TypeError, match="wavelength_nm"):
        photon_energy(np.array([500, 600]))


# --- Table 1.2: radiant energy and radiosity ---------------------------------------------------


def test_radiant_energy_constant_flux_and_samples():
    # Q_e = Phi_e Delta t for a constant flux; the trapezoid rule over samples is exact for a
    # flux linear in time.
    np.testing.assert_allclose(radiant_energy(2.5, duration_s=4.0), 10.0)
    flux = np.array([[1.0, 2.0], [3.0, 4.0]])
    np.testing.assert_allclose(
        radiant_energy(flux, duration_s=np.array([2.0, 0.5])), flux * [2.0, 0.5]
    )
    t = np.array([0.0, 0.5, 2.0, 3.0])  # irregular times [s]
    np.testing.assert_allclose(radiant_energy(1.0 + 2.0 * t, t), 3.0 + 9.0, rtol=1e-15)
    np.testing.assert_allclose(
        radiant_energy(np.full(4, 7.0), t), radiant_energy(7.0, duration_s=3.0)
    )
    # Euler-Maclaurin: the trapezoid error for int_0^1 t^3 dt = 1/4 is exactly h^2 (f'(1) - f'(0))
    # / 12 = h^2 / 4 (order 2).
    for n in (11, 41):
        ts = np.linspace(0.0, 1.0, n)
        h = 1.0 / (n - 1)
        np.testing.assert_allclose(radiant_energy(ts**3, ts) - 0.25, h**2 / 4.0, rtol=1e-9)
    ts = np.linspace(0.0, 2.0, 101)
    series = np.exp(-ts) * 3.0
    np.testing.assert_allclose(
        radiant_energy(series, ts), integrate.trapezoid(series, ts), rtol=1e-14
    )
    # The time axis may be any axis; other axes are batch (e.g. spectral) axes.
    batch = np.stack([series, 2.0 * series], axis=0)  # (2, n)
    np.testing.assert_allclose(
        radiant_energy(batch.T, ts, axis=0), radiant_energy(batch, ts), rtol=1e-15
    )


def test_radiant_energy_rejects_bad_input():
    with pytest.raises(ValueError, match="exactly one"):
        radiant_energy(1.0)
    with pytest.raises(ValueError, match="exactly one"):
        radiant_energy(np.ones(3), np.arange(3.0), duration_s=1.0)
    with pytest.raises(ValueError, match="time_s"):
        radiant_energy(np.ones(3), np.arange(4.0))
    with pytest.raises(ValueError, match="time_s"):
        radiant_energy(np.ones(1), np.zeros(1))
    with pytest.raises(eqx.EquinoxRuntimeError, match="time_s"):
        radiant_energy(np.ones(3), np.array([0.0, 2.0, 1.0]))
    with pytest.raises(eqx.EquinoxRuntimeError, match="duration_s"):
        eqx.filter_jit(radiant_energy)(jnp.ones(2), duration_s=jnp.asarray(-1.0))


def test_radiosity_sums_exitances():
    # J_e = M_e + M_r + M_t; a Lambertian reflector of albedo rho under E reflects rho E.
    np.testing.assert_allclose(radiosity(3.0), 3.0)
    rho, E = np.array([0.2, 0.5, 0.9]), 100.0
    J = radiosity(np.zeros(3), rho * E, 1.0)
    np.testing.assert_allclose(J, rho * E + 1.0)
    # With spectral densities the radiosity integrates like any other flux density.
    wl = np.linspace(400.0, 700.0, 31)
    M = np.linspace(0.1, 0.3, 31)
    np.testing.assert_allclose(
        integrate.trapezoid(np.asarray(radiosity(M, 0.5 * M)), wl), 1.5 * integrate.trapezoid(M, wl)
    )
    with pytest.raises(eqx.EquinoxRuntimeError, match="reflected_exitance"):
        radiosity(1.0, -0.5)
    with pytest.raises(ValueError, match="broadcast"):
        radiosity(np.ones(3), np.ones(2))


def test_radiant_energy_radiosity_jit_vmap_grad():
    ts = jnp.linspace(0.0, 1.0, 5)
    f = jnp.array([1.0, 2.0, 0.5, 3.0, 1.0])
    np.testing.assert_allclose(jax.jit(radiant_energy)(f, ts), radiant_energy(f, ts), rtol=1e-15)
    batch = jnp.stack([f, 2.0 * f])
    np.testing.assert_allclose(
        jax.vmap(radiant_energy, in_axes=(0, None))(batch, ts), radiant_energy(batch, ts)
    )
    # dQ/dPhi_i are the trapezoid weights; dQ/d(duration) = Phi.
    np.testing.assert_allclose(
        jax.grad(radiant_energy)(f, ts), [0.125, 0.25, 0.25, 0.25, 0.125], rtol=1e-15
    )
    check_grads(lambda f: radiant_energy(f, ts), (f,), order=1, modes="rev")
    np.testing.assert_allclose(
        jax.grad(lambda d: radiant_energy(2.5, duration_s=d))(1.0), 2.5, rtol=1e-15
    )
    g = jax.grad(lambda m: radiosity(m, 2.0 * m, 1.0))(jnp.asarray(0.3))
    np.testing.assert_allclose(g, 3.0)
    np.testing.assert_allclose(
        jax.jit(jax.vmap(radiosity))(jnp.ones(3), jnp.ones(3), jnp.ones(3)), 3.0 * np.ones(3)
    )
