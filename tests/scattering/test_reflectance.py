"""Reflectance quantities of thesis table 3.2: closed forms, consistency, error estimates."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.scattering as sc

KEY = jax.random.key(0)
R = jnp.array([0.2, 0.9])


def _dir(theta, phi=0.4):
    return jnp.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def _within(est, exact, k=6.0):
    m, se = np.asarray(est.mean), np.asarray(est.standard_error)
    assert np.all(np.abs(m - exact) <= k * se + 1e-12), (m, se, exact)


def test_lambertian_closed_forms():
    d = sc.DiffuseBxDF(R)
    for theta in [0.0, 0.7, 1.5]:
        # Cosine-weighted importance sampling of a Lambertian BRDF has zero variance.
        e = sc.directional_hemispherical_reflectance(d, _dir(theta), n_samples=64, key=KEY)
        np.testing.assert_allclose(e.mean, R, rtol=1e-12)
        np.testing.assert_allclose(e.standard_error, 0.0, atol=1e-12)
        e = sc.hemispherical_directional_reflectance(d, _dir(theta), n_samples=64, key=KEY)
        np.testing.assert_allclose(e.mean, R, rtol=1e-12)
    np.testing.assert_allclose(
        sc.bihemispherical_reflectance(d, n_samples=64, key=KEY).mean, R, rtol=1e-12
    )
    # A cone of half-angle g around the axis at polar angle a collects R sin^2(g) cos(a).
    for axis_theta, g in [(0.0, 0.3), (0.5, 0.6), (0.2, 1.2)]:
        cone = sc.Cone(_dir(axis_theta, 1.0), g)
        exact = R * np.sin(g) ** 2 * np.cos(axis_theta)
        np.testing.assert_allclose(
            cone.projected_solid_angle(), np.pi * np.sin(g) ** 2 * np.cos(axis_theta)
        )
        _within(
            sc.directional_conical_reflectance(d, _dir(0.4), cone, n_samples=50_000, key=KEY), exact
        )
        _within(sc.hemispherical_conical_reflectance(d, cone, n_samples=50_000, key=KEY), exact)
        _within(sc.biconical_reflectance(d, cone, cone, n_samples=50_000, key=KEY), exact)
        # Uniform incidence from any cone onto a Lambertian surface: all of R is reflected.
        _within(sc.conical_hemispherical_reflectance(d, cone, n_samples=50_000, key=KEY), R)


def test_hemisphere_cone_equals_hemispherical():
    b = sc.RoughConductorBxDF(0.4, 0.2, 3.0)
    half = sc.Cone(jnp.array([0.0, 0.0, 1.0]), np.pi / 2)
    u = jax.random.uniform(KEY, (40_000, 5))
    a = sc.directional_conical_reflectance(b, _dir(0.6), half, u=u[:, :3])
    h = sc.directional_hemispherical_reflectance(b, _dir(0.6), u=u[:, :3])
    np.testing.assert_allclose(a.mean, h.mean, rtol=1e-12)
    np.testing.assert_allclose(
        sc.biconical_reflectance(b, half, half, u=u).mean,
        sc.bihemispherical_reflectance(b, u=u).mean,
        rtol=2e-2,  # cone vs cosine sampling of the incident directions: same integral
    )


@pytest.mark.parametrize(
    "bxdf",
    [
        sc.RoughConductorBxDF(0.3, 0.2, 3.0),
        sc.OrenNayarBxDF(R, 0.5),
        sc.RoughDielectricBxDF(0.3, 1.5),
    ],
    ids=lambda b: type(b).__name__,
)
def test_reciprocity_directional_vs_hemispherical(bxdf):
    # For a reciprocal BRDF rho_dh(w) = rho_hd(w); the two estimators sample differently.
    for theta in [0.2, 1.1]:
        a = sc.directional_hemispherical_reflectance(
            bxdf, _dir(theta), n_samples=100_000, key=jax.random.key(1)
        )
        b = sc.hemispherical_directional_reflectance(
            bxdf, _dir(theta), n_samples=100_000, key=jax.random.key(2)
        )
        diff = np.abs(np.asarray(a.mean) - np.asarray(b.mean))
        assert np.all(diff <= 6 * np.hypot(a.standard_error, b.standard_error) + 1e-12)


def test_dielectric_reflectance_is_fresnel():
    # A smooth dielectric reflects F(theta) of the flux: the reflectance counts reflection only.
    b = sc.DielectricBxDF(1.5)
    for theta in [0.0, 0.9, 1.4]:
        e = sc.directional_hemispherical_reflectance(b, _dir(theta), n_samples=200_000, key=KEY)
        _within(e, float(sc.fresnel_dielectric(np.cos(theta), 1.5)))
    # Bi-hemispherical reflectance of glass: 2 * int F(mu) mu dmu (about 0.092 for eta = 1.5).
    mu = (np.arange(20000) + 0.5) / 20000
    exact = 2 * np.mean(np.asarray(sc.fresnel_dielectric(mu, 1.5)) * mu)
    _within(sc.bihemispherical_reflectance(b, n_samples=200_000, key=KEY), exact)


@pytest.mark.slow
def test_error_estimate_is_calibrated():
    # Over independent replicates, |estimate - truth| / se behaves like |N(0, 1)|.
    b = sc.OrenNayarBxDF(0.8, 0.3, model="fujii")
    truth = sc.hemispherical_directional_reflectance(
        b, _dir(0.8), n_samples=2_000_000, key=KEY
    ).mean[0]
    z = []
    for i in range(40):
        e = sc.hemispherical_directional_reflectance(
            b, _dir(0.8), n_samples=2000, key=jax.random.key(100 + i)
        )
        z.append(float((e.mean[0] - truth) / e.standard_error[0]))
    z = np.abs(np.array(z))
    assert 0.4 < np.mean(z) < 1.2  # E|N(0,1)| = 0.80


def test_reflectance_quasi_monte_carlo_and_batch():
    from radiometria.montecarlo import sobol

    d = sc.RoughConductorBxDF(0.3, 0.2, 3.0)
    u = sobol(4096, 3)
    e = sc.directional_hemispherical_reflectance(d, _dir(0.5), u=u)
    ref = sc.directional_hemispherical_reflectance(d, _dir(0.5), n_samples=200_000, key=KEY)
    _within(ref, float(e.mean[0]), k=8)
    # A batch of directions
    wo = jnp.stack([_dir(0.1), _dir(0.5), _dir(1.0)])
    e = sc.hemispherical_directional_reflectance(d, wo, n_samples=1000, key=KEY)
    assert e.mean.shape == (3, 1)


def test_reflectance_bad_input():
    d = sc.DiffuseBxDF(0.5)
    with pytest.raises(ValueError, match="key"):
        sc.bihemispherical_reflectance(d, n_samples=10)
    with pytest.raises(TypeError, match="bxdf"):
        sc.bihemispherical_reflectance("diffuse", n_samples=10, key=KEY)
    with pytest.raises(eqx.EquinoxRuntimeError, match="horizon"):
        sc.Cone(_dir(1.2), 0.5)
    with pytest.raises(ValueError, match="axis"):
        sc.Cone(jnp.ones(2), 0.5)


# --------------------------------------------------------------------------------------------
# The differential quantities of table 3.2: bidirectional, conical-directional and the
# (normalised) hemispherical-directional reflectance, d rho / d omega_o [sr^-1]


def test_differential_reflectances_lambertian_closed_forms():
    d = sc.DiffuseBxDF(R)
    for theta_o in [0.0, 0.7, 1.4]:
        wo = _dir(theta_o, 2.0)
        exact = R * np.cos(theta_o) / np.pi  # all equal; as reflectance factors all equal R
        np.testing.assert_allclose(sc.bidirectional_reflectance(d, wo, _dir(0.3)), exact)
        e = sc.normalised_hemispherical_directional_reflectance(d, wo, n_samples=64, key=KEY)
        np.testing.assert_allclose(e.mean, exact, rtol=1e-12)
        np.testing.assert_allclose(e.standard_error, 0.0, atol=1e-12)
        for axis_theta, g in [(0.0, 0.4), (0.5, 0.9)]:
            cone = sc.Cone(_dir(axis_theta, 1.0), g)
            e = sc.conical_directional_reflectance(d, cone, wo, n_samples=50_000, key=KEY)
            _within(e, exact)
    # Transmitted pairs do not count.
    np.testing.assert_array_equal(sc.bidirectional_reflectance(d, _dir(0.3), -_dir(0.3)), 0.0)
    # d rho / d omega_o integrates to the directional-hemispherical reflectance R.
    n = 200
    mu = (np.arange(n) + 0.5) / n
    phi = (np.arange(2 * n) + 0.5) * np.pi / n
    M, P = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1 - M**2)
    wo = jnp.asarray(np.stack([s * np.cos(P), s * np.sin(P), M], -1).reshape(-1, 3))
    b = sc.RoughConductorBxDF(0.5, 0.2, 3.0)
    dens = sc.bidirectional_reflectance(b, wo, _dir(0.5))
    integral = np.sum(np.asarray(dens), axis=0) * (1 / n) * (np.pi / n)
    ref = sc.directional_hemispherical_reflectance(b, _dir(0.5), n_samples=100_000, key=KEY)
    _within(ref, integral, k=6)


def test_differential_reflectances_mirror():
    eta, k = jnp.array([0.2, 1.1]), jnp.array([3.0, 0.5])
    m = sc.ConductorBxDF(eta, k)
    for theta_o in [0.2, 0.9]:
        wo = _dir(theta_o, 0.5)
        F = sc.fresnel_conductor(np.cos(theta_o), eta, k)
        e = sc.normalised_hemispherical_directional_reflectance(m, wo, n_samples=16, key=KEY)
        np.testing.assert_allclose(e.mean, F * np.cos(theta_o) / np.pi, rtol=1e-12)
        # A cone around the mirror direction of wo receives the reflection of all its light
        # that arrives along the mirror direction: |cos theta_o| F / Omega'.
        mirror = wo * jnp.array([-1.0, -1.0, 1.0])
        cone = sc.Cone(mirror, 0.1)
        e = sc.conical_directional_reflectance(m, cone, wo, n_samples=16, key=KEY)
        np.testing.assert_allclose(
            e.mean, np.cos(theta_o) * F / cone.projected_solid_angle(), rtol=1e-12
        )
        off = sc.Cone(_dir(0.3, 0.5 + np.pi / 2), 0.1)
        assert not bool(off.contains(mirror))
        e = sc.conical_directional_reflectance(m, off, wo, n_samples=16, key=KEY)
        np.testing.assert_array_equal(e.mean, 0.0)
        # A delta lobe has no bidirectional density.
        np.testing.assert_array_equal(sc.bidirectional_reflectance(m, wo, mirror), 0.0)


@pytest.mark.parametrize(
    "bxdf",
    [sc.RoughConductorBxDF(0.3, 0.2, 3.0), sc.OrenNayarBxDF(R, 0.5, model="fujii")],
    ids=lambda b: type(b).__name__,
)
def test_conical_directional_reciprocity(bxdf):
    # Nicodemus (1977): Omega' d rho(Omega; w)/d omega = |cos theta| rho(w; Omega) for a
    # reciprocal BRDF; the two estimators sample from opposite ends.
    cone = sc.Cone(_dir(0.4, 1.0), 0.5)
    for theta in [0.3, 0.9]:
        w = _dir(theta, 1.3)
        a = sc.conical_directional_reflectance(
            bxdf, cone, w, n_samples=100_000, key=jax.random.key(3)
        )
        b = sc.directional_conical_reflectance(
            bxdf, w, cone, n_samples=100_000, key=jax.random.key(4)
        )
        scale = float(cone.projected_solid_angle()) / np.cos(theta)
        diff = np.abs(np.asarray(a.mean) * scale - np.asarray(b.mean))
        tol = 6 * np.hypot(np.asarray(a.standard_error) * scale, b.standard_error) + 1e-12
        assert np.all(diff <= tol), (diff, tol)
    # The hemispherical form is the albedo (eq. 3.5) times |cos theta_o| / pi.
    u = jax.random.uniform(KEY, (20_000, 3))
    w = _dir(0.8)
    a = sc.normalised_hemispherical_directional_reflectance(bxdf, w, u=u)
    b = sc.hemispherical_directional_reflectance(bxdf, w, u=u)
    np.testing.assert_allclose(a.mean, b.mean * np.cos(0.8) / np.pi, rtol=1e-12)
    np.testing.assert_allclose(a.standard_error, b.standard_error * np.cos(0.8) / np.pi, rtol=1e-10)


def test_differential_reflectances_jit_batch_and_errors():
    b = sc.RoughConductorBxDF(0.3, 0.2, 3.0)
    wo = jnp.stack([_dir(0.1), _dir(0.5), _dir(1.0)])
    cone = sc.Cone(_dir(0.2), 0.6)
    u = jax.random.uniform(KEY, (500, 3))
    e = sc.conical_directional_reflectance(b, cone, wo, u=u)
    assert e.mean.shape == (3, 1)
    ej = eqx.filter_jit(lambda b, c, w, u: sc.conical_directional_reflectance(b, c, w, u=u))(
        b, cone, wo, u
    )
    np.testing.assert_allclose(ej.mean, e.mean, rtol=1e-12)
    e = sc.normalised_hemispherical_directional_reflectance(b, wo, u=u)
    assert e.mean.shape == (3, 1)
    assert sc.bidirectional_reflectance(b, wo, _dir(0.4)).shape == (3, 1)
    g = jax.grad(lambda a: sc.bidirectional_reflectance(sc.DiffuseBxDF(a), _dir(0.2), _dir(0.4))[0])
    np.testing.assert_allclose(g(0.5), np.cos(0.2) / np.pi, rtol=1e-12)
    with pytest.raises(TypeError, match="cone"):
        sc.conical_directional_reflectance(b, None, wo, u=u)
    with pytest.raises(TypeError, match="bxdf"):
        sc.bidirectional_reflectance("mirror", wo, wo)
