"""Optical properties of section 3.1: eq. 3.2, table 3.1, slabs and the glossary's -ivities."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads

import radiometria.scattering as sc
from radiometria.radiometry import beer_lambert_transmittance, planck

WL = jnp.linspace(380.0, 780.0, 81)


def _spectra(key, n=5):
    k1, k2 = jax.random.split(key)
    rho = 0.6 * jax.random.uniform(k1, (n, WL.shape[0]))
    tau = (1.0 - rho) * jax.random.uniform(k2, (n, WL.shape[0]))
    return rho, tau


def test_absorptance_energy_balance():
    rho, tau = _spectra(jax.random.key(0))
    alpha = sc.absorptance(rho, tau)
    np.testing.assert_allclose(alpha + rho + tau, 1.0, atol=1e-12)
    assert float(jnp.min(alpha)) >= 0
    # Scalars and broadcasting (thesis eq. 3.2).
    np.testing.assert_allclose(sc.absorptance(0.25, jnp.array([0.0, 0.5, 0.75])), [0.75, 0.25, 0])


def test_flux_weighted_quantities_balance_and_closed_forms():
    rho, tau = _spectra(jax.random.key(1))
    alpha = sc.absorptance(rho, tau)
    phi = planck(WL, 5000.0)  # incident spectrum: a 5000 K blackbody
    r = sc.flux_weighted_reflectance(rho, phi, WL)
    t = sc.flux_weighted_transmittance(tau, phi, WL)
    a = sc.flux_weighted_absorptance(alpha, phi, WL)
    assert r.shape == (5,)
    # Table 3.1 quantities obey eq. 3.2 (the weighting is linear).
    np.testing.assert_allclose(a + r + t, 1.0, atol=1e-12)
    # Closed forms: a constant spectral reflectance is its own flux-weighted value; the ratio of
    # trapezoid integrals equals a direct NumPy computation.
    np.testing.assert_allclose(sc.flux_weighted_reflectance(0.37, phi, WL), 0.37, rtol=1e-13)
    expect = np.trapezoid(np.asarray(rho) * np.asarray(phi), WL) / np.trapezoid(phi, WL)
    np.testing.assert_allclose(r, expect, rtol=1e-12)
    # The flux-weighted value depends on the illuminant (table 3.1: it is not the spectral mean).
    step = jnp.where(WL > 600.0, 0.9, 0.1)
    warm = sc.flux_weighted_reflectance(step, planck(WL, 2000.0), WL)
    cold = sc.flux_weighted_reflectance(step, planck(WL, 20000.0), WL)
    assert float(warm) > float(cold) + 0.2


def test_slab_series_summed_numerically():
    r = jnp.array([0.0, 0.04, 0.3, 0.7, 0.95, 1.0])[:, None]
    ti = jnp.array([0.0, 0.2, 0.6, 0.99, 1.0])[None, :]
    rho, tau, alpha = sc.slab_reflectance_transmittance(r, ti)
    # Direct sum of the incoherent multiple reflections inside the layer.
    rn, tn = np.asarray(r), np.asarray(ti)
    k = np.arange(4000)[:, None, None]
    x = rn * tn
    rho_s = rn + np.sum((1 - rn) ** 2 * rn * tn**2 * x ** (2 * k), axis=0)
    tau_s = np.sum((1 - rn) ** 2 * tn * x ** (2 * k), axis=0)
    # Absorbed: each crossing loses (1 - tau_i) of the flux travelling inside.
    alpha_s = np.sum((1 - rn) * (1 - tn) * x**k, axis=0)
    fine = (rn * tn < 0.99) | (rn * tn == 1.0)  # converged series (r = t_i = 1: lossless)
    np.testing.assert_allclose(rho[fine], np.broadcast_to(rho_s, fine.shape)[fine], atol=1e-12)
    np.testing.assert_allclose(tau[fine], np.broadcast_to(tau_s, fine.shape)[fine], atol=1e-12)
    np.testing.assert_allclose(alpha[fine], np.broadcast_to(alpha_s, fine.shape)[fine], atol=1e-12)
    # Energy balance (eq. 3.2) everywhere, including r = 1 (a perfect mirror face).
    np.testing.assert_allclose(rho + tau + alpha, 1.0, atol=1e-12)
    np.testing.assert_allclose(sc.slab_reflectance_transmittance(1.0, 0.5)[0], 1.0)
    # Non-absorbing layer: tau = (1 - r)/(1 + r), the pile-of-plates result of Stokes.
    np.testing.assert_allclose(tau[:-1, -1], (1 - r[:-1, 0]) / (1 + r[:-1, 0]), rtol=1e-13)


def test_slab_reflectance_tends_to_reflectivity_with_thickness():
    # A glass plate of increasing thickness: R -> r (the non-scattering reflectivity) and T -> 0.
    r = sc.fresnel_dielectric(1.0, 1.5)
    d = jnp.array([1e-4, 1e-3, 1e-2, 1e-1, 1.0])  # m
    ti = beer_lambert_transmittance(100.0, d)
    rho, tau, alpha = sc.slab_reflectance_transmittance(r, ti)
    assert np.all(np.diff(np.asarray(rho)) < 0) and np.all(np.diff(np.asarray(tau)) < 0)
    np.testing.assert_allclose(rho[-1], r, rtol=1e-12)
    np.testing.assert_allclose(tau[-1], 0.0, atol=1e-40)


def test_reflectivity_kubelka1931():
    K = jnp.array([0.0, 1e-8, 0.1, 1.0, 10.0, 1e3])
    S = jnp.array([1.0, 1.0, 2.0, 1.0, 0.5, 1.0])
    R = sc.reflectivity_kubelka1931(K, S)
    # Closed form and its inverse, the Kubelka-Munk remission function K/S = (1-R)^2 / (2R).
    ks = np.asarray(K / S)
    np.testing.assert_allclose(R, 1 + ks - np.sqrt(ks**2 + 2 * ks), rtol=1e-7)
    np.testing.assert_allclose((1 - R) ** 2 / (2 * R), ks, rtol=1e-10, atol=1e-15)
    np.testing.assert_allclose(R[0], 1.0)
    np.testing.assert_allclose(sc.reflectivity_kubelka1931(1.0, 0.0), 0.0)
    np.testing.assert_allclose(sc.reflectivity_kubelka1931(0.0, 0.0), 0.0)
    # Only the ratio matters.
    np.testing.assert_allclose(sc.reflectivity_kubelka1931(3 * K, 3 * S), R, rtol=1e-14)
    g = jax.grad(lambda k: sc.reflectivity_kubelka1931(k, 1.0))(jnp.array(0.5))
    assert np.isfinite(float(g)) and float(g) < 0


def test_transmissivity_and_absorptivity():
    kappa = jnp.array([0.0, 1e-12, 0.5, 3.0])
    tu = sc.transmissivity(kappa)
    au = sc.absorptivity(kappa)
    np.testing.assert_allclose(tu, np.exp(-np.asarray(kappa)), rtol=1e-15)
    np.testing.assert_allclose(tu + au, 1.0, atol=1e-15)
    np.testing.assert_allclose(au[1], 1e-12, rtol=1e-9)  # expm1 keeps weak absorption exact
    # Per-centimetre unit path: kappa in m^-1 over 0.01 m.
    np.testing.assert_allclose(sc.transmissivity(kappa, 0.01), np.exp(-np.asarray(kappa) * 0.01))
    # Transmissivity of a unit path composes: a path of length L has tau_u^L.
    np.testing.assert_allclose(
        beer_lambert_transmittance(kappa, 2.5), sc.transmissivity(kappa) ** 2.5, rtol=1e-13
    )


def test_properties_jit_vmap_grad():
    rho, tau = _spectra(jax.random.key(2), n=3)
    phi = planck(WL, 6500.0)
    f = jax.jit(sc.flux_weighted_reflectance)
    np.testing.assert_allclose(f(rho, phi, WL), sc.flux_weighted_reflectance(rho, phi, WL))
    v = jax.vmap(sc.flux_weighted_reflectance, in_axes=(0, None, None))(rho, phi, WL)
    np.testing.assert_allclose(v, sc.flux_weighted_reflectance(rho, phi, WL), rtol=1e-14)
    check_grads(lambda r, t: sc.slab_reflectance_transmittance(r, t)[0], (0.3, 0.6), order=1)
    check_grads(lambda x: sc.flux_weighted_reflectance(x, phi, WL), (rho,), 1)
    g = jax.grad(lambda r: sc.slab_reflectance_transmittance(r, 1.0)[0])(jnp.array(1.0))
    assert np.isfinite(float(g))


def test_properties_reject_bad_input():
    with pytest.raises(eqx.EquinoxRuntimeError, match="eq. 3.2"):
        eqx.filter_jit(sc.absorptance)(0.7, 0.5)
    with pytest.raises(eqx.EquinoxRuntimeError, match="reflectance"):
        sc.absorptance(-0.1, 0.5)
    with pytest.raises(eqx.EquinoxRuntimeError, match="incident_spectrum"):
        sc.flux_weighted_reflectance(0.5, -jnp.ones(81), WL)
    with pytest.raises(ValueError, match="incident_spectrum"):
        sc.flux_weighted_reflectance(jnp.ones((2, 81)) * 0.5, jnp.ones((3, 81)), WL)
    with pytest.raises(eqx.EquinoxRuntimeError, match="internal_transmittance"):
        sc.slab_reflectance_transmittance(0.5, 1.5)
    with pytest.raises(eqx.EquinoxRuntimeError, match="scattering_coefficient"):
        sc.reflectivity_kubelka1931(1.0, -1.0)
    with pytest.raises(eqx.EquinoxRuntimeError, match="unit_length"):
        eqx.filter_jit(sc.transmissivity)(1.0, 0.0)
    with pytest.raises(eqx.EquinoxRuntimeError, match="absorption_coefficient"):
        sc.absorptivity(-1.0)
