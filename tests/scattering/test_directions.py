"""Reflection, refraction, frames and spherical coordinates."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.scattering as sc


def _unit(n, seed=0):
    v = np.random.default_rng(seed).normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def test_reflect_law_of_reflection():
    wi = _unit(100)
    n = _unit(100, 1)
    wr = np.asarray(sc.reflect(wi, n))
    # theta_r = theta_i, coplanar, unit length (thesis eq. 3.7-3.8)
    np.testing.assert_allclose(np.sum(wr * n, 1), np.sum(wi * n, 1), atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(wr, axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(np.sum(np.cross(wi, wr) * n, 1), 0.0, atol=1e-13)
    # phi_r = phi_i + pi in the local frame
    w = _unit(50, 2)
    wr = np.asarray(sc.reflect(w, jnp.array([0.0, 0.0, 1.0])))
    np.testing.assert_allclose(wr, w * np.array([-1, -1, 1]), atol=1e-15)


@pytest.mark.parametrize("eta", [1.5, 1 / 1.5, 1.33, 1.0])
def test_refract_snell_law(eta):
    wi = _unit(400, 3)
    n = np.array([0.0, 0.0, 1.0])
    wt, valid = sc.refract(wi, n, eta)
    wt, valid = np.asarray(wt), np.asarray(valid)
    cos_i = wi[:, 2]
    eta_i = np.where(cos_i > 0, 1.0, eta)
    eta_t = np.where(cos_i > 0, eta, 1.0)
    sin_i = np.sqrt(1 - cos_i**2)
    sin_t = np.sqrt(np.maximum(0, 1 - wt[:, 2] ** 2))
    expect_valid = (eta_i / eta_t * sin_i) < 1
    np.testing.assert_array_equal(valid, expect_valid)
    v = valid
    np.testing.assert_allclose(eta_i[v] * sin_i[v], eta_t[v] * sin_t[v], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(wt, axis=1), 1.0, atol=1e-12)
    # Transmitted ray on the other side, in the plane of incidence, azimuth turned by pi.
    assert np.all(wt[v, 2] * cos_i[v] <= 0)
    np.testing.assert_allclose(np.cross(wi, wt)[v, 2], 0.0, atol=1e-12)
    assert np.all(np.sum(wt[v, :2] * wi[v, :2], 1) <= 1e-12)
    # Under TIR the mirror direction is returned.
    np.testing.assert_allclose(wt[~v], wi[~v] * np.array([-1, -1, 1]), atol=1e-14)


def test_refract_matches_thesis_eq_3_12():
    wi = _unit(100, 4)
    wi[:, 2] = np.abs(wi[:, 2])
    eta = 1.5
    n = np.array([0.0, 0.0, 1.0])
    c = wi @ n
    # thesis eq. 3.12 with eta_i / eta_t = 1 / eta
    wt_ref = (1 / eta) * ((c - np.sqrt(eta**2 - 1 + c**2))[:, None] * n - wi)
    np.testing.assert_allclose(sc.refract(wi, n, eta)[0], wt_ref, atol=1e-14)


def test_refract_roundtrip_and_spectral_eta():
    wi = _unit(20, 5)
    wi[:, 2] = np.abs(wi[:, 2]) + 0.1
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    n = jnp.array([0.0, 0.0, 1.0])
    wt, ok = sc.refract(wi, n, 1.5)
    back, ok2 = sc.refract(wt, n, 1.5)
    assert bool(jnp.all(ok & ok2))
    np.testing.assert_allclose(back, wi, atol=1e-13)
    # Per-wavelength eta (..., n_lambda) with directions (..., 1, 3)
    wt4, ok4 = sc.refract(wi[:, None, :], n, jnp.array([1.4, 1.5, 1.6, 1.7]))
    assert wt4.shape == (20, 4, 3) and ok4.shape == (20, 4)


def test_refract_gradient_finite_at_normal_incidence_and_tir_edge():
    n = jnp.array([0.0, 0.0, 1.0])
    theta_c = np.arcsin(1 / 1.5)

    def g(theta):
        wi = jnp.stack([jnp.sin(theta), 0.0 * theta, -jnp.cos(theta)])
        wt, _ = sc.refract(wi, n, 1.5)
        return jnp.sum(wt)

    for theta in [0.0, theta_c, theta_c + 1e-12, 1.2]:
        assert np.isfinite(jax.grad(g)(theta))


def test_coordinate_system_is_orthonormal_right_handed():
    n = np.concatenate([_unit(500, 6), [[0, 0, 1.0], [0, 0, -1.0], [1.0, 0, 0]]])
    s, t = sc.coordinate_system(n)
    s, t = np.asarray(s), np.asarray(t)
    for a in (s, t):
        np.testing.assert_allclose(np.linalg.norm(a, axis=1), 1, atol=1e-13)
    np.testing.assert_allclose(np.sum(s * t, 1), 0, atol=1e-13)
    np.testing.assert_allclose(np.sum(s * n, 1), 0, atol=1e-13)
    np.testing.assert_allclose(np.cross(s, t), n, atol=1e-13)


def test_frame_roundtrip():
    n = _unit(50, 7)
    v = _unit(50, 8)
    fr = sc.Frame.from_z(n)
    loc = sc.to_local(fr, v)
    np.testing.assert_allclose(loc[:, 2], np.sum(v * n, 1), atol=1e-14)
    np.testing.assert_allclose(sc.to_world(fr, loc), v, atol=1e-14)
    np.testing.assert_allclose(sc.to_world((fr.s, fr.t, fr.n), loc), v, atol=1e-14)
    # One frame, many vectors.
    fr1 = sc.Frame.from_z(jnp.array([0.0, 0.0, 1.0]))
    np.testing.assert_allclose(sc.to_local(fr1, v), v, atol=1e-15)
    with pytest.raises(TypeError, match="frame"):
        sc.to_local("frame", v)


def test_spherical_helpers():
    theta = np.linspace(0, np.pi, 13)
    phi = np.linspace(0, 2 * np.pi, 13, endpoint=False)
    w = sc.spherical_direction(np.sin(theta), np.cos(theta), phi)
    np.testing.assert_allclose(sc.spherical_theta(w), theta, atol=1e-12)
    np.testing.assert_allclose(sc.spherical_phi(w)[1:-1], phi[1:-1], atol=1e-12)
    np.testing.assert_allclose(sc.cos_theta(w), np.cos(theta), atol=1e-15)
    np.testing.assert_allclose(sc.sin_theta(w), np.sin(theta), atol=1e-12)
    np.testing.assert_allclose(sc.cos_phi(w)[1:-1], np.cos(phi[1:-1]), atol=1e-12)
    np.testing.assert_allclose(sc.sin_phi(w)[1:-1], np.sin(phi[1:-1]), atol=1e-12)
    assert float(sc.cos_phi(jnp.array([0.0, 0.0, 1.0]))) == 1.0
    np.testing.assert_allclose(sc.tan2_theta(w[1:5]), np.tan(theta[1:5]) ** 2, rtol=1e-10)
    assert bool(sc.same_hemisphere(jnp.array([0, 0, 1.0]), jnp.array([0.3, 0, 0.1])))
    assert not bool(sc.same_hemisphere(jnp.array([0, 0, 1.0]), jnp.array([0.3, 0, -0.1])))
    assert np.all(np.isfinite(jax.grad(lambda x: sc.sin_theta(jnp.array([x, 0.0, 1.0])))(0.0)))


def test_face_forward_and_normalize():
    n = jnp.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(sc.face_forward(n, jnp.array([0.0, 0.3, -1.0])), -n)
    np.testing.assert_allclose(sc.normalize(jnp.array([3.0, 0.0, 4.0])), [0.6, 0.0, 0.8])
    np.testing.assert_allclose(sc.normalize(jnp.zeros(3)), 0.0)


def test_directions_reject_bad_shapes():
    with pytest.raises(ValueError, match="wi"):
        sc.reflect(jnp.ones(2), jnp.ones(3))
    with pytest.raises(ValueError, match="n"):
        sc.refract(jnp.ones(3), jnp.ones((2, 4)), 1.5)


def test_directions_jit_vmap_match_eager():
    wi = _unit(16, 9)
    n = _unit(16, 10)
    eager = sc.refract(wi, n, 1.3)
    jitted = jax.jit(sc.refract)(wi, n, 1.3)
    vm = jax.vmap(sc.refract, in_axes=(0, 0, None))(wi, n, 1.3)
    for a, b, c in zip(eager, jitted, vm, strict=True):
        np.testing.assert_allclose(a, b, atol=1e-14)
        np.testing.assert_allclose(a, c, atol=1e-14)
