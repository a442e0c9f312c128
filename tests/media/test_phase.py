"""Phase functions: normalisation, mean cosine, chi-square sampling, reciprocity, pbrt's
convention, and jit/vmap/grad."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads
from scipy import integrate

import radiometria.media as md
from radiometria.montecarlo import chi2_test

WO = jnp.array([0.48, -0.6, 0.64])  # unit, off every axis
HG_GS = [-0.9, -0.3, 0.0, 0.5, 0.95]
CASES = (
    [("isotropic", md.IsotropicPhaseFunction(), 0.0)]
    + [(f"hg{g}", md.HenyeyGreenstein(g), g) for g in HG_GS]
    + [("rayleigh", md.RayleighPhaseFunction(), 0.0)]
)
IDS = [c[0] for c in CASES]


def _wi(mu, phi=0.7):
    """The direction at scattering-angle cosine mu (cos theta = -wo . wi) and azimuth phi."""
    fwd = -np.asarray(WO)
    s = np.cross(fwd, [1.0, 0.0, 0.0])
    s /= np.linalg.norm(s)
    t = np.cross(fwd, s)
    st = math.sqrt(max(0.0, 1 - mu * mu))
    return jnp.asarray(st * math.cos(phi) * s + st * math.sin(phi) * t + mu * fwd)


def _p_of_mu(phase):
    f = jax.jit(lambda w: phase.p(WO, w))
    return lambda mu, phi=0.7: float(f(_wi(mu, phi)))


@pytest.mark.parametrize("name,phase,g", CASES, ids=IDS)
def test_phase_normalised_over_sphere(name, phase, g):
    p = _p_of_mu(phase)
    # Azimuthal symmetry about the forward direction, checked, then 2 pi int p dmu.
    assert abs(p(0.3, 0.1) - p(0.3, 2.9)) < 1e-12
    val, _ = integrate.quad(p, -1.0, 1.0, epsabs=1e-12, epsrel=1e-12, limit=200)
    assert abs(2 * math.pi * val - 1.0) < 1e-9


@pytest.mark.parametrize("name,phase,g", CASES, ids=IDS)
def test_phase_mean_cosine_by_quadrature(name, phase, g):
    p = _p_of_mu(phase)
    val, _ = integrate.quad(lambda mu: mu * p(mu), -1.0, 1.0, epsabs=1e-12, limit=200)
    assert abs(2 * math.pi * val - g) < 1e-9
    np.testing.assert_allclose(phase.mean_cosine(), g, atol=1e-15)


@pytest.mark.slow
@pytest.mark.parametrize("name,phase,g", CASES, ids=IDS)
def test_phase_sample_p_chi2(name, phase, g):
    res = chi2_test(
        jax.jit(lambda u: phase.sample_p(WO, u).wi),
        jax.jit(lambda w: phase.pdf(WO, w)),
        domain="sphere",
        n_samples=100_000,
        u_dim=2,
        key=jax.random.key(7),
        quadrature=24,
        n_tests=len(CASES),
    )
    assert res.passed, res.message


@pytest.mark.parametrize("name,phase,g", CASES, ids=IDS)
def test_phase_sample_value_pdf_consistent(name, phase, g):
    u = jax.random.uniform(jax.random.key(3), (1000, 2))
    s = phase.sample_p(WO, u)
    np.testing.assert_allclose(jnp.linalg.norm(s.wi, axis=-1), 1.0, atol=1e-12)
    np.testing.assert_allclose(s.value, phase.p(WO, s.wi), rtol=1e-9)
    np.testing.assert_allclose(s.pdf, phase.pdf(WO, s.wi), rtol=1e-9)


@pytest.mark.parametrize("name,phase,g", CASES, ids=IDS)
def test_phase_reciprocity(name, phase, g):
    k1, k2 = jax.random.split(jax.random.key(4))
    a = jax.random.normal(k1, (500, 3))
    b = jax.random.normal(k2, (500, 3))
    a = a / jnp.linalg.norm(a, axis=-1, keepdims=True)
    b = b / jnp.linalg.norm(b, axis=-1, keepdims=True)
    np.testing.assert_allclose(phase.p(a, b), phase.p(b, a), rtol=1e-14)


@pytest.mark.parametrize("g", [-0.99, -0.5, 0.002, 0.4, 0.99])
def test_henyey_greenstein_matches_pbrt(g):
    """pbrt-v4 `HenyeyGreenstein(Dot(wo, wi), g)` and `SampleHenyeyGreenstein`'s cosTheta
    (measured from wo) on the same variates."""
    hg = md.HenyeyGreenstein(g)
    u = jax.random.uniform(jax.random.key(5), (2000, 2))
    s = hg.sample_p(WO, u)
    cos_wo = np.asarray(s.wi @ WO)
    u0 = np.asarray(u[:, 0])
    sqr = (1 - g * g) / (1 + g - 2 * g * u0)
    pbrt_cos = -(1 + g * g - sqr * sqr) / (2 * g)
    np.testing.assert_allclose(cos_wo, pbrt_cos, atol=1e-9)
    denom = 1 + g * g + 2 * g * cos_wo
    pbrt_p = (1 - g * g) / (4 * math.pi * denom * np.sqrt(denom))
    np.testing.assert_allclose(s.value, pbrt_p, rtol=1e-10)


def test_henyey_greenstein_zero_is_isotropic():
    u = jax.random.uniform(jax.random.key(6), (100, 2))
    a = md.HenyeyGreenstein(0.0).sample_p(WO, u)
    b = md.IsotropicPhaseFunction().sample_p(WO, u)
    np.testing.assert_allclose(a.pdf, b.pdf, rtol=1e-15)
    np.testing.assert_allclose(a.wi, b.wi, atol=1e-15)


def test_rayleigh_inverse_cdf():
    u = jnp.linspace(0.0, 0.999999, 1001)
    s = md.RayleighPhaseFunction().sample_p(WO, jnp.stack([u, 0.3 + 0 * u], -1))
    mu = -np.asarray(s.wi @ WO)
    np.testing.assert_allclose((mu**3 + 3 * mu + 4) / 8, u, atol=1e-12)


@pytest.mark.parametrize("g", [1.0, -1.0, 1.5, float("nan")])
def test_henyey_greenstein_rejects_g_outside(g):
    with pytest.raises(ValueError, match="`g`"):
        md.HenyeyGreenstein(g)


def test_henyey_greenstein_rejects_g_outside_under_jit():
    import equinox as eqx

    with pytest.raises(eqx.EquinoxRuntimeError, match="`g`"):
        eqx.filter_jit(lambda g: md.HenyeyGreenstein(g).g)(1.2)


@pytest.mark.slow
def test_henyey_greenstein_grad_in_g():
    wi = _wi(0.4)
    check_grads(lambda g: md.HenyeyGreenstein(g).p(WO, wi), (0.3,), order=1)
    u = jnp.array([[0.2, 0.6], [0.9, 0.1], [0.5, 0.5]])
    check_grads(lambda g: md.HenyeyGreenstein(g).sample_p(WO, u).wi, (0.3,), order=1)
    check_grads(lambda g: md.HenyeyGreenstein(g).sample_p(WO, u).pdf, (-0.6,), order=1)


@pytest.mark.slow
def test_phase_jit_and_vmap():
    gs = jnp.array([-0.5, 0.1, 0.8])
    u = jnp.array([0.3, 0.7])

    def one(g):
        return md.HenyeyGreenstein(g).sample_p(WO, u).wi

    batched = jax.vmap(one)(gs)
    loop = jnp.stack([one(g) for g in gs])
    np.testing.assert_allclose(batched, loop, rtol=1e-14)
    np.testing.assert_allclose(jax.jit(one)(0.8), one(0.8), rtol=1e-14)
    # A batch of g broadcast against a batch of directions.
    hg = md.HenyeyGreenstein(gs)
    wi = jnp.stack([_wi(0.2), _wi(-0.4), _wi(0.9)])
    np.testing.assert_allclose(
        hg.p(jnp.broadcast_to(WO, (3, 3)), wi),
        [md.HenyeyGreenstein(g).p(WO, w) for g, w in zip(gs, wi, strict=True)],
        rtol=1e-14,
    )


@pytest.mark.parametrize("phase", [md.IsotropicPhaseFunction(), md.RayleighPhaseFunction()])
def test_phase_float32(phase):
    u = jax.random.uniform(jax.random.key(8), (64, 2), dtype=jnp.float32)
    s = phase.sample_p(WO.astype(jnp.float32), u)
    assert s.wi.dtype == jnp.float32
    np.testing.assert_allclose(jnp.linalg.norm(s.wi, axis=-1), 1.0, atol=1e-5)
