"""Fresnel equations: closed forms, energy conservation, Brewster, complex form, edge cases."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.scattering as sc

COS = np.linspace(-1.0, 1.0, 401)
ETAS = [1.0 / 1.5, 1.0, 1.33, 1.5, 2.4]


def _complex_reference(cos_i, eta, k):
    """Independent NumPy evaluation of the general complex Fresnel form (Born & Wolf 14.2)."""
    n = eta + 1j * k
    mu = np.abs(cos_i).astype(complex)
    cos_t = np.sqrt(1 - (1 - mu**2) / n**2)
    rs = (mu - n * cos_t) / (mu + n * cos_t)
    rp = (n * mu - cos_t) / (n * mu + cos_t)
    return np.abs(rs) ** 2, np.abs(rp) ** 2


@pytest.mark.parametrize("eta", [1.5, 1.33, 2.4])
def test_fresnel_dielectric_normal_incidence_closed_form(eta):
    f0 = ((eta - 1) / (eta + 1)) ** 2
    np.testing.assert_allclose(sc.fresnel_dielectric(1.0, eta), f0, rtol=1e-14)
    # From inside, the relative index inverts and F(normal) is the same.
    np.testing.assert_allclose(sc.fresnel_dielectric(-1.0, eta), f0, rtol=1e-14)
    np.testing.assert_allclose(sc.fresnel_schlick_f0(eta), f0, rtol=1e-14)


@pytest.mark.parametrize("eta", ETAS)
def test_fresnel_energy_conservation(eta):
    # R + T = 1 per polarisation, with T computed from the t amplitudes and eta cos_t / cos_i.
    cos_i = COS[np.abs(COS) > 1e-3]
    r_s, r_p, t_s, t_p = sc.fresnel_dielectric_amplitudes(cos_i, eta)
    eta_eff = np.where(cos_i < 0, 1 / eta, eta)
    sin2_t = (1 - cos_i**2) / eta_eff**2
    cos_t = np.sqrt(np.maximum(0, 1 - sin2_t))
    factor = eta_eff * cos_t / np.abs(cos_i)
    T_s = factor * np.asarray(t_s) ** 2
    T_p = factor * np.asarray(t_p) ** 2
    np.testing.assert_allclose(np.asarray(r_s) ** 2 + T_s, 1.0, atol=1e-13)
    np.testing.assert_allclose(np.asarray(r_p) ** 2 + T_p, 1.0, atol=1e-13)
    R = sc.fresnel_dielectric(cos_i, eta)
    T = sc.fresnel_dielectric_transmittance(cos_i, eta, radiance=False)
    np.testing.assert_allclose(R + T, 1.0, atol=1e-14)
    np.testing.assert_allclose(T, 0.5 * (T_s + T_p), atol=1e-13)
    # Radiance transmittance carries (eta_t/eta_i)^2 (thesis eq. 3.15-3.16).
    T_rad = sc.fresnel_dielectric_transmittance(cos_i, eta)
    np.testing.assert_allclose(T_rad, eta_eff**2 * (1 - R), atol=1e-13)


@pytest.mark.parametrize("eta", [1.33, 1.5, 2.4, 1 / 1.5])
def test_fresnel_brewster_angle(eta):
    theta_b = np.arctan(eta)
    R_s, R_p = sc.fresnel_dielectric_polarized(np.cos(theta_b), eta)
    assert abs(float(R_p)) < 1e-28
    assert float(R_s) > 0.01


def test_fresnel_dielectric_total_internal_reflection():
    eta = 1.5
    theta_c = np.arcsin(1 / eta)
    cos_beyond = -np.cos(np.linspace(theta_c + 1e-9, np.pi / 2, 50))  # inside, beyond critical
    np.testing.assert_array_equal(sc.fresnel_dielectric(cos_beyond, eta), 1.0)
    np.testing.assert_array_equal(sc.fresnel_dielectric_transmittance(cos_beyond, eta), 0.0)
    # The same interface described from the other side: eta -> 1/eta, cos -> -cos.
    np.testing.assert_array_equal(sc.fresnel_dielectric(-cos_beyond, 1 / eta), 1.0)
    below = np.cos(np.linspace(0.0, theta_c - 1e-6, 50))
    assert np.all(np.asarray(sc.fresnel_dielectric(-below, eta)) < 1)


def test_fresnel_dielectric_grazing_and_index_matched():
    np.testing.assert_allclose(sc.fresnel_dielectric(0.0, 1.5), 1.0)
    np.testing.assert_allclose(sc.fresnel_dielectric(COS, 1.0), 0.0, atol=1e-15)


@pytest.mark.parametrize("eta,k", [(0.2, 3.0), (1.5, 0.0), (0.5, 0.0), (1.1, 7.0), (2.5, 0.3)])
def test_fresnel_conductor_matches_complex_form(eta, k):
    mu = np.linspace(0.0, 1.0, 301)
    R_s, R_p = sc.fresnel_conductor_polarized(mu, eta, k)
    ref_s, ref_p = _complex_reference(mu, eta, k)
    np.testing.assert_allclose(R_s, ref_s, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(R_p, ref_p, rtol=1e-10, atol=1e-13)
    c_s, c_p = sc.fresnel_complex(mu, eta, k)
    np.testing.assert_allclose(np.abs(c_s) ** 2, ref_s, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(np.abs(c_p) ** 2, ref_p, rtol=1e-10, atol=1e-13)


def test_fresnel_conductor_normal_incidence_closed_form():
    eta = np.array([0.2, 0.15, 1.3])
    k = np.array([3.6, 3.4, 7.5])
    F = sc.fresnel_conductor(1.0, eta, k)
    np.testing.assert_allclose(F, ((eta - 1) ** 2 + k**2) / ((eta + 1) ** 2 + k**2), rtol=1e-14)


@pytest.mark.parametrize("eta", [1.5, 1.33, 0.8])
def test_fresnel_conductor_with_zero_k_equals_dielectric(eta):
    mu = np.linspace(0.0, 1.0, 201)
    np.testing.assert_allclose(
        sc.fresnel_conductor(mu, eta, 0.0), sc.fresnel_dielectric(mu, eta), atol=1e-13
    )
    R_s, R_p = sc.fresnel_conductor_polarized(mu, eta, 0.0)
    D_s, D_p = sc.fresnel_dielectric_polarized(mu, eta)
    np.testing.assert_allclose(R_s, D_s, atol=1e-13)
    np.testing.assert_allclose(R_p, D_p, atol=1e-13)


def test_fresnel_schlick_endpoints_and_accuracy():
    f0 = sc.fresnel_schlick_f0(1.5)
    np.testing.assert_allclose(sc.fresnel_schlick(1.0, f0), f0)
    np.testing.assert_allclose(sc.fresnel_schlick(0.0, f0), 1.0)
    mu = np.linspace(0.05, 1, 50)
    err = np.abs(
        np.asarray(sc.fresnel_schlick(mu, f0)) - np.asarray(sc.fresnel_dielectric(mu, 1.5))
    )
    assert err.max() < 0.04
    # Spectral f0 broadcasts.
    assert sc.fresnel_schlick(mu[:, None], jnp.array([0.04, 0.9])).shape == (50, 2)


def test_fresnel_spectral_broadcasting():
    cos = jnp.linspace(0.1, 1.0, 7)[:, None]
    eta = jnp.array([0.2, 0.5, 1.1, 1.3])
    k = jnp.array([3.0, 2.0, 1.0, 0.5])
    assert sc.fresnel_conductor(cos, eta, k).shape == (7, 4)
    assert sc.fresnel_dielectric(cos, eta).shape == (7, 4)
    assert sc.fresnel_dielectric_transmittance(cos, eta).shape == (7, 4)


def test_fresnel_jit_and_vmap_match_eager():
    mu = jnp.linspace(-1, 1, 33)
    for fn, args in [
        (sc.fresnel_dielectric, (mu, 1.5)),
        (sc.fresnel_conductor, (jnp.abs(mu), 0.2, 3.0)),
        (sc.fresnel_dielectric_transmittance, (mu, 1.5)),
    ]:
        eager = fn(*args)
        np.testing.assert_allclose(jax.jit(fn)(*args), eager, rtol=1e-14)
        np.testing.assert_allclose(
            jax.vmap(fn, in_axes=(0,) + (None,) * (len(args) - 1))(*args), eager, rtol=1e-14
        )


@pytest.mark.parametrize(
    "cos_i", [1.0, 1.0 - 1e-12, 0.0, 1e-9, -np.cos(np.arcsin(1 / 1.5)), -0.5, -0.9]
)
def test_fresnel_dielectric_gradients_finite(cos_i):
    g = jax.grad(lambda c, e: sc.fresnel_dielectric(c, e), argnums=(0, 1))(cos_i, 1.5)
    assert all(np.isfinite(np.asarray(x)) for x in g)
    g = jax.grad(lambda c, e: sc.fresnel_dielectric_transmittance(c, e), argnums=(0, 1))(cos_i, 1.5)
    assert all(np.isfinite(np.asarray(x)) for x in g)


@pytest.mark.parametrize("cos_i", [1.0, 0.0, 1e-9, 0.5])
@pytest.mark.parametrize("eta,k", [(0.2, 3.0), (1.5, 0.0), (0.5, 0.0), (1.0, 0.0)])
def test_fresnel_conductor_gradients_finite(cos_i, eta, k):
    g = jax.grad(lambda c, e, kk: sc.fresnel_conductor(c, e, kk), argnums=(0, 1, 2))(cos_i, eta, k)
    assert all(np.isfinite(np.asarray(x)) for x in g), g


def test_fresnel_gradient_matches_finite_differences():
    from jax.test_util import check_grads

    check_grads(lambda c: sc.fresnel_dielectric(c, 1.5), (0.6,), order=1, modes=["rev"])
    check_grads(
        lambda c, e, k: sc.fresnel_conductor(c, e, k), (0.6, 0.3, 2.5), order=1, modes=["rev"]
    )


def test_fresnel_rejects_bad_optical_constants():
    with pytest.raises(eqx.EquinoxRuntimeError, match="eta"):
        sc.fresnel_dielectric(0.5, -1.5)
    with pytest.raises(eqx.EquinoxRuntimeError, match="eta"):
        eqx.filter_jit(sc.fresnel_dielectric)(0.5, 0.0)
    with pytest.raises(eqx.EquinoxRuntimeError, match="`k`"):
        eqx.filter_jit(sc.fresnel_conductor)(0.5, 0.2, -1.0)
    with pytest.raises(ValueError, match="cos_theta_i"):
        sc.fresnel_conductor(jnp.ones(3), jnp.ones(4), 1.0)
    with pytest.raises(ValueError, match="eta"):
        sc.fresnel_dielectric(jnp.ones(3), jnp.ones(4))
    with pytest.raises(TypeError, match="cos_theta_i"):
        sc.fresnel_dielectric(np.array([1, 0]), 1.5)


def test_fresnel_float32():
    mu = jnp.linspace(0, 1, 11, dtype=jnp.float32)
    F = sc.fresnel_conductor(mu, jnp.float32(0.2), jnp.float32(3.0))
    assert F.dtype == jnp.float32
    np.testing.assert_allclose(F, sc.fresnel_conductor(np.asarray(mu, float), 0.2, 3.0), rtol=1e-5)
    assert sc.fresnel_dielectric(mu, jnp.float32(1.5)).dtype == jnp.float32
