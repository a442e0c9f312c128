"""Monochromatic waves (thesis eq. 1.1-1.6): closed-form identities, round trips, SciPy."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.constants as sc
from jax.test_util import check_grads

from radiometria import constants as c
from radiometria.radiometry import (
    angular_frequency,
    frequency_from_angular_frequency,
    frequency_from_period,
    frequency_to_wavelength,
    period,
    phase_velocity,
    refractive_index_from_permittivity,
    refractive_index_from_phase_velocity,
    wavelength_from_wavenumber,
    wavelength_in_medium_nm,
    wavelength_in_vacuum_nm,
    wavelength_to_frequency,
    wavenumber_in_medium,
    wavenumber_vacuum,
)

RNG = np.random.default_rng(0)
WL = RNG.uniform(200.0, 2000.0, 50)  # nm
ETA = RNG.uniform(1.0, 2.5, 50)
NU = wavelength_to_frequency(WL)  # Hz


def test_waves_period_and_angular_frequency_eq_1_1_1_2():
    T = period(NU)
    np.testing.assert_allclose(T * NU, 1.0, rtol=1e-15)  # nu = 1 / T
    omega = angular_frequency(NU)
    np.testing.assert_allclose(omega, 2.0 * math.pi / T, rtol=1e-15)  # omega = 2 pi / T
    # Green light at 545 THz: T = 1.835 fs.
    assert float(period(545e12)) == pytest.approx(1.0 / 545e12, rel=1e-15)


def test_waves_vacuum_wavelength_eq_1_3():
    # lambda_0 = c T = c / nu, with the period from eq. 1.1.
    np.testing.assert_allclose(c.SPEED_OF_LIGHT * period(NU) * 1e9, WL, rtol=1e-14)


def test_waves_wavenumbers_eq_1_5_1_6():
    k0 = wavenumber_vacuum(WL)
    # k_0 = 2 pi / lambda_0 = 2 pi nu / c = omega / c
    np.testing.assert_allclose(k0, 2.0 * math.pi / (WL * 1e-9), rtol=1e-15)
    np.testing.assert_allclose(k0, angular_frequency(NU) / sc.c, rtol=1e-14)
    k = wavenumber_in_medium(WL, ETA)
    # k = 2 pi / lambda = omega / v = eta k_0, with lambda from eq. 1.4 and v = c / eta
    np.testing.assert_allclose(k, 2.0 * math.pi / (wavelength_in_medium_nm(WL, ETA) * 1e-9))
    np.testing.assert_allclose(k, angular_frequency(NU) / phase_velocity(ETA), rtol=1e-14)
    np.testing.assert_allclose(k / k0, ETA, rtol=1e-14)  # eta = k / k_0
    # 550 nm: k_0 = 1.1424e7 rad/m.
    assert float(wavenumber_vacuum(550.0)) == pytest.approx(11423973.285781066, rel=1e-14)


def test_waves_wavelength_in_medium_eq_1_4():
    lam = wavelength_in_medium_nm(WL, ETA)
    # lambda = v T = v / nu with v = c / eta; the frequency is the same in both media
    np.testing.assert_allclose(lam, phase_velocity(ETA) / NU * 1e9, rtol=1e-14)
    np.testing.assert_allclose(lam * ETA, WL, rtol=1e-15)  # eta = lambda_0 / lambda
    # Water (eta = 1.333) shortens 589 nm sodium light to 441.9 nm.
    assert float(wavelength_in_medium_nm(589.0, 1.333)) == pytest.approx(441.8605, rel=1e-6)


def test_waves_refractive_index_identities():
    eps_r = RNG.uniform(1.0, 6.0, 20)
    mu_r = RNG.uniform(0.9, 1.1, 20)
    eta = refractive_index_from_permittivity(eps_r, mu_r)
    np.testing.assert_allclose(eta, np.sqrt(eps_r * mu_r), rtol=1e-15)
    np.testing.assert_allclose(refractive_index_from_permittivity(eps_r), np.sqrt(eps_r))
    # eta = sqrt(mu eps / (mu_0 eps_0)) = c / v with eps mu = 1 / v^2 (thesis section 1.1)
    eps = eps_r * c.VACUUM_PERMITTIVITY
    mu = mu_r * c.VACUUM_PERMEABILITY
    v = 1.0 / np.sqrt(eps * mu)
    np.testing.assert_allclose(phase_velocity(eta), v, rtol=1e-14)
    np.testing.assert_allclose(refractive_index_from_phase_velocity(v), eta, rtol=1e-14)
    # Vacuum: eta = 1, v = c exactly.
    assert float(phase_velocity(1.0)) == sc.c
    assert float(refractive_index_from_permittivity(1.0)) == 1.0


def test_waves_roundtrips():
    np.testing.assert_allclose(frequency_from_period(period(NU)), NU, rtol=1e-15)
    np.testing.assert_allclose(
        frequency_from_angular_frequency(angular_frequency(NU)), NU, rtol=1e-15
    )
    np.testing.assert_allclose(wavelength_from_wavenumber(wavenumber_vacuum(WL)), WL, rtol=1e-15)
    np.testing.assert_allclose(
        wavelength_in_vacuum_nm(wavelength_in_medium_nm(WL, ETA), ETA), WL, rtol=1e-15
    )
    np.testing.assert_allclose(
        refractive_index_from_phase_velocity(phase_velocity(ETA)), ETA, rtol=1e-15
    )
    # In a medium the same inverse gives the medium's wavelength from k.
    np.testing.assert_allclose(
        wavelength_from_wavenumber(wavenumber_in_medium(WL, ETA)),
        wavelength_in_medium_nm(WL, ETA),
        rtol=1e-14,
    )
    np.testing.assert_allclose(frequency_to_wavelength(frequency_from_period(period(NU))), WL)


# (function, arguments, exponents): each relation is a power law f = C prod(x_i^p_i), so the
# gradient of log f with respect to log x_i is exactly p_i.
WAVE_FUNCTIONS = [
    (period, (5e14,), (-1.0,)),
    (frequency_from_period, (2e-15,), (-1.0,)),
    (angular_frequency, (5e14,), (1.0,)),
    (frequency_from_angular_frequency, (3e15,), (1.0,)),
    (phase_velocity, (1.5,), (-1.0,)),
    (refractive_index_from_phase_velocity, (2e8,), (-1.0,)),
    (refractive_index_from_permittivity, (2.25, 1.05), (0.5, 0.5)),
    (wavelength_in_medium_nm, (550.0, 1.5), (1.0, -1.0)),
    (wavelength_in_vacuum_nm, (400.0, 1.5), (1.0, 1.0)),
    (wavenumber_vacuum, (550.0,), (-1.0,)),
    (wavelength_from_wavenumber, (1e7,), (-1.0,)),
    (wavenumber_in_medium, (550.0, 1.33), (-1.0, 1.0)),
]


def test_waves_jit_vmap_grad():
    args = [tuple(jnp.asarray(a) for a in a_) for _, a_, _ in WAVE_FUNCTIONS]
    fns = [f for f, _, _ in WAVE_FUNCTIONS]

    def all_fns(args):
        return [f(*a) for f, a in zip(fns, args, strict=True)]

    eager = all_fns(args)
    np.testing.assert_allclose(jax.jit(all_fns)(args), eager, rtol=1e-15)
    # vmap over a batch equals the (elementwise, broadcasting) batched call
    scale = jnp.linspace(0.9, 1.1, 4)
    batched = [tuple(a * scale for a in a_) for a_ in args]
    for got, want in zip(jax.vmap(all_fns)(batched), all_fns(batched), strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-15)

    # d log f / d log x_i = p_i, exactly; plus a finite-difference check of the first one
    def log_log(f):
        return lambda *la: jnp.log(f(*(jnp.exp(x) for x in la)))

    grads = jax.jit(
        lambda args: [
            jax.grad(log_log(f), argnums=tuple(range(len(a))))(*(jnp.log(x) for x in a))
            for f, a in zip(fns, args, strict=True)
        ]
    )(args)
    for (fn, _, exponents), g in zip(WAVE_FUNCTIONS, grads, strict=True):
        np.testing.assert_allclose(g, exponents, rtol=1e-12, err_msg=fn.__name__)
    check_grads(log_log(wavenumber_in_medium), (jnp.log(550.0), jnp.log(1.33)), 1, modes="rev")


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: period(0.0), "frequency_hz"),
        (lambda: frequency_from_period(-1.0), "period_s"),
        (lambda: angular_frequency(-5e14), "frequency_hz"),
        (lambda: frequency_from_angular_frequency(0.0), "omega"),
        (lambda: phase_velocity(0.0), "eta"),
        (lambda: refractive_index_from_phase_velocity(-3.0), "velocity"),
        (lambda: refractive_index_from_permittivity(-2.0), "eps_r"),
        (lambda: refractive_index_from_permittivity(2.0, 0.0), "mu_r"),
        (lambda: wavelength_in_medium_nm(550.0, -1.0), "eta"),
        (lambda: wavelength_in_vacuum_nm(0.0, 1.5), "wavelength_medium_nm"),
        (lambda: wavenumber_vacuum(0.0), "wavelength_nm"),
        (lambda: wavelength_from_wavenumber(-1.0), "k0"),
        (lambda: wavenumber_in_medium(550.0, 0.0), "eta"),
    ],
)
def test_waves_reject_out_of_domain(call, match):
    with pytest.raises(eqx.EquinoxRuntimeError, match=match):
        call()


def test_waves_reject_out_of_domain_under_jit():
    with pytest.raises(eqx.EquinoxRuntimeError, match="wavelength_nm"):
        eqx.filter_jit(wavenumber_vacuum)(jnp.array([550.0, -1.0]))
    with pytest.raises(eqx.EquinoxRuntimeError, match="eps_r"):
        eqx.filter_jit(refractive_index_from_permittivity)(jnp.array(-1.0), jnp.array(1.0))


def test_waves_reject_integer_arrays():
    with pytest.raises(TypeError, match="wavelength_nm"):
        wavenumber_vacuum(np.array([500, 600]))


@pytest.mark.parametrize("dtype", [jnp.float32, jnp.float64])
def test_waves_dtype_follows_input(dtype):
    wl = jnp.asarray([450.0, 550.0, 650.0], dtype=dtype)
    eta = jnp.asarray(1.5, dtype=dtype)
    for out in (
        wavenumber_vacuum(wl),
        wavenumber_in_medium(wl, eta),
        wavelength_in_medium_nm(wl, eta),
        angular_frequency(wavelength_to_frequency(wl)),
        period(wavelength_to_frequency(wl)),
    ):
        assert out.dtype == dtype
    rtol = {jnp.float32: 1e-6, jnp.float64: 1e-15}[dtype]
    np.testing.assert_allclose(
        wavenumber_vacuum(wl), 2.0 * np.pi / (np.array([450.0, 550.0, 650.0]) * 1e-9), rtol=rtol
    )
