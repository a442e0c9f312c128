"""HomogeneousMedium: exact transmittance, the free-flight distribution (chi-square), the weight
convention checked against single-scattering integrals with closed forms, spectra, errors."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.media as md
from radiometria.montecarlo import chi2_test
from radiometria.radiometry import (
    ConstantSpectrum,
    PiecewiseLinearSpectrum,
    beer_lambert_transmittance,
)

SIGMA = np.array([0.5, 1.2, 3.0])
RHO = np.array([0.9, 0.5, 0.2])
LAM = np.array([450.0, 550.0, 650.0])
D = 1.3
Z_MAX = 5.5


def _rays(n, d=D):
    o = jnp.zeros((n, 3))
    w = jnp.broadcast_to(jnp.array([0.0, 0.0, 1.0]), (n, 3))
    return o, w, jnp.full((n,), d), jnp.broadcast_to(jnp.asarray(LAM), (n, 3))


def _medium():
    return md.HomogeneousMedium(jnp.asarray(SIGMA), jnp.asarray(RHO), md.HenyeyGreenstein(0.4))


def test_homogeneous_transmittance_exact():
    o, w, _, lam = _rays(5)
    d = jnp.array([0.0, 0.1, 1.0, 4.0, jnp.inf])
    T = _medium().transmittance(o, w, d, lam)
    np.testing.assert_allclose(T, np.exp(-SIGMA[None, :] * np.asarray(d)[:, None]), rtol=1e-15)
    np.testing.assert_allclose(
        T[:4], beer_lambert_transmittance(jnp.asarray(SIGMA)[None, :], d[:4, None]), rtol=1e-15
    )
    vacuum = md.HomogeneousMedium(0.0, 0.5, md.IsotropicPhaseFunction())
    np.testing.assert_allclose(vacuum.transmittance(o, w, d, lam), 1.0)


@pytest.mark.slow
def test_homogeneous_spectra_match_arrays():
    o, w, d, lam = _rays(4)
    spec = PiecewiseLinearSpectrum(jnp.asarray(LAM), jnp.asarray(SIGMA))
    a = md.HomogeneousMedium(spec, ConstantSpectrum(0.7), md.RayleighPhaseFunction())
    b = md.HomogeneousMedium(jnp.asarray(SIGMA), 0.7, md.RayleighPhaseFunction())
    np.testing.assert_allclose(a.transmittance(o, w, d, lam), b.transmittance(o, w, d, lam))
    u = jax.random.uniform(jax.random.key(0), (4, 1))
    ma, mb = a.sample_free_flight(o, w, d, lam, u), b.sample_free_flight(o, w, d, lam, u)
    np.testing.assert_allclose(ma.weight, mb.weight, rtol=1e-14)


def test_homogeneous_free_flight_chi2():
    """t follows the wavelength mixture (1/k) sum_j sigma_j e^{-sigma_j t} on (0, D), with the
    rest of the mass at D; escaped samples are replaced by uniform ones (density P / D)."""
    n = 60_000
    med = _medium()
    p_none = float(np.mean(np.exp(-SIGMA * D)))

    def sample(u):
        mi = med.sample_free_flight(*_rays(n), u[:, :1])
        return jnp.where(mi.scattered, mi.t, D * u[:, 1])

    def pdf(t):
        s = jnp.asarray(SIGMA)[None, :]
        return jnp.mean(s * jnp.exp(-s * t[:, None]), axis=1) + p_none / D

    res = chi2_test(
        sample, pdf, domain="interval", bounds=(0.0, D), n_samples=n, u_dim=2,
        key=jax.random.key(1),
    )  # fmt: skip
    assert res.passed, res.message


def _z(values, want):
    values = np.asarray(values)
    se = values.std(axis=0, ddof=1) / math.sqrt(values.shape[0])
    return (values.mean(axis=0) - want) / se


def test_homogeneous_weights_single_scattering_integrals():
    """Per wavelength j: E[w 1_event] = rho (1 - e^{-sigma D}) (the probability of scattering
    before D), E[w 1_event t] = rho (1 - e^{-sigma D}(1 + sigma D)) / sigma, and
    E[w 1_no event] = e^{-sigma D}."""
    n = 200_000
    med = _medium()
    u = jax.random.uniform(jax.random.key(2), (n, 1))
    mi = eqx.filter_jit(med.sample_free_flight)(*_rays(n), u)
    ev = np.asarray(mi.scattered)[:, None]
    w = np.asarray(mi.weight)
    t = np.asarray(mi.t)[:, None]
    e = np.exp(-SIGMA * D)
    z1 = _z(np.where(ev, w, 0.0), RHO * (1 - e))
    z2 = _z(np.where(ev, w * t, 0.0), RHO * (1 - e * (1 + SIGMA * D)) / SIGMA)
    z3 = _z(np.where(ev, 0.0, w), e)
    for z in (z1, z2, z3):
        assert np.all(np.abs(z) < Z_MAX), (z1, z2, z3)
    # Past the segment the weights are T_j / P exactly.
    np.testing.assert_allclose(w[~ev[:, 0]], np.broadcast_to(e / e.mean(), w[~ev[:, 0]].shape))


def test_homogeneous_single_wavelength_classical_weights():
    n = 1000
    o, w, d, _ = _rays(n)
    lam = jnp.full((n, 1), 550.0)
    med = md.HomogeneousMedium(2.0, 0.6, md.IsotropicPhaseFunction())
    mi = med.sample_free_flight(o, w, d, lam, jax.random.uniform(jax.random.key(3), (n, 2)))
    np.testing.assert_allclose(jnp.where(mi.scattered[:, None], mi.weight, 0.6), 0.6, rtol=1e-13)
    np.testing.assert_allclose(jnp.where(mi.scattered[:, None], 1.0, mi.weight), 1.0, rtol=1e-13)
    assert bool(jnp.all(mi.t <= D))


def test_homogeneous_infinite_segment_always_scatters():
    o, w, _, lam = _rays(100)
    mi = _medium().sample_free_flight(
        o, w, jnp.full((100,), jnp.inf), lam, jax.random.uniform(jax.random.key(4), (100, 1))
    )
    assert bool(jnp.all(mi.scattered)) and bool(jnp.all(jnp.isfinite(mi.weight)))


@pytest.mark.parametrize(
    "kwargs,name",
    [
        ({"sigma_t": -1.0, "albedo": 0.5}, "sigma_t"),
        ({"sigma_t": jnp.array([1.0, jnp.nan]), "albedo": 0.5}, "sigma_t"),
        ({"sigma_t": jnp.inf, "albedo": 0.5}, "sigma_t"),
        ({"sigma_t": 1.0, "albedo": 1.5}, "albedo"),
        ({"sigma_t": 1.0, "albedo": -0.1}, "albedo"),
    ],
)
def test_homogeneous_rejects_bad_coefficients(kwargs, name):
    with pytest.raises(ValueError, match=f"`{name}`"):
        md.HomogeneousMedium(phase=md.IsotropicPhaseFunction(), **kwargs)


def test_homogeneous_rejects_bad_phase_and_shapes():
    with pytest.raises(TypeError, match="phase"):
        md.HomogeneousMedium(1.0, 0.5, phase=0.3)
    med = md.HomogeneousMedium(jnp.ones(4), 0.5, md.IsotropicPhaseFunction())
    with pytest.raises(ValueError, match="sigma_t"):
        med.transmittance(*_rays(2))  # 4 coefficients, 3 wavelengths
    bad = md.HomogeneousMedium(ConstantSpectrum(-1.0), 0.5, md.IsotropicPhaseFunction())
    with pytest.raises(eqx.EquinoxRuntimeError, match="sigma_t"):
        bad.transmittance(*_rays(2))


@pytest.mark.slow
def test_homogeneous_jit_vmap_grad():
    o, w, d, lam = _rays(8)
    u = jax.random.uniform(jax.random.key(5), (8, 1))
    med = _medium()
    a = med.sample_free_flight(o, w, d, lam, u)
    b = eqx.filter_jit(lambda m: m.sample_free_flight(o, w, d, lam, u))(med)
    np.testing.assert_allclose(a.weight, b.weight, rtol=1e-14)

    def t_of(sigma):
        m = md.HomogeneousMedium(sigma, 0.5, md.IsotropicPhaseFunction())
        return m.transmittance(o, w, d, lam)

    g = jax.jacfwd(lambda s: t_of(s)[0, 0])(1.0)
    np.testing.assert_allclose(g, -D * math.exp(-D), rtol=1e-12)
    batched = jax.vmap(lambda s: t_of(s)[0, 0])(jnp.array([0.5, 1.0]))
    np.testing.assert_allclose(batched, np.exp(-np.array([0.5, 1.0]) * D), rtol=1e-14)
