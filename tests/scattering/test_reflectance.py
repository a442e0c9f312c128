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
