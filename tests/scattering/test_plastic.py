"""Plastic, rough plastic, thin dielectric, blend and mask BxDFs: pointwise against Mitsuba 3
(`scalar_rgb`, in the test), sampling against the pdf (chi-square), closed forms."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.scattering as sc

from .test_bxdfs import _defective_chi2, _dir

mi = pytest.importorskip("mitsuba")
dr = pytest.importorskip("drjit")


def _dirs(n, seed):
    v = np.random.default_rng(seed).normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = np.abs(v[:, 2])
    return v.astype(np.float32).astype(np.float64)


def _mitsuba_eval_pdf(params, wo, wi):
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict(params)
    ctx, ev, pd = mi.BSDFContext(), [], []
    for a, b in zip(wo, wi, strict=True):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(*map(float, a))
        si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
        w = mi.Vector3f(*map(float, b))
        ev.append(float(bsdf.eval(ctx, si, w)[0]))
        pd.append(float(bsdf.pdf(ctx, si, w)))
    return np.array(ev), np.array(pd)


GREY = {"type": "rgb", "value": [0.3, 0.3, 0.3]}


@pytest.mark.parametrize("nonlinear", [False, True])
def test_plastic_matches_mitsuba(nonlinear):
    wo, wi = _dirs(100, 0), _dirs(100, 1)
    params = {"type": "plastic", "diffuse_reflectance": GREY, "int_ior": 1.6, "ext_ior": 1.0,
              "nonlinear": nonlinear}  # fmt: skip
    ev, pd = _mitsuba_eval_pdf(params, wo, wi)
    ours = sc.PlasticBxDF(0.3, 1.6, nonlinear=nonlinear)
    np.testing.assert_allclose(np.asarray(ours.f(wo, wi))[:, 0] * wi[:, 2], ev, rtol=2e-5)
    np.testing.assert_allclose(ours.pdf(wo, wi), pd, rtol=2e-5)


@pytest.mark.parametrize(
    ("distribution", "alpha", "rtol"), [("ggx", 0.3, 2e-5), ("beckmann", 0.3, 1e-2)]
)
def test_rough_plastic_matches_mitsuba(distribution, alpha, rtol):
    # Beckmann: Mitsuba's G1 is Walter's rational fit (error < 0.5 %), ours the exact erf form.
    wo, wi = _dirs(100, 2), _dirs(100, 3)
    params = {"type": "roughplastic", "distribution": distribution, "alpha": alpha,
              "diffuse_reflectance": GREY, "int_ior": 1.5, "ext_ior": 1.0}  # fmt: skip
    ev, pd = _mitsuba_eval_pdf(params, wo, wi)
    ours = sc.RoughPlasticBxDF(0.3, alpha, 1.5, distribution=distribution)
    np.testing.assert_allclose(np.asarray(ours.f(wo, wi))[:, 0] * wi[:, 2], ev, rtol=rtol)
    np.testing.assert_allclose(ours.pdf(wo, wi), pd, rtol=rtol)


def test_fresnel_diffuse_reflectance_matches_mitsuba_and_quadrature():
    mi.set_variant("scalar_rgb")
    for eta in [0.6, 1 / 1.5, 1.33, 1.5, 2.4]:
        assert (
            abs(float(sc.fresnel_diffuse_reflectance(eta)) - mi.fresnel_diffuse_reflectance(eta))
            < 1e-5
        )
        mu = (np.arange(20000) + 0.5) / 20000
        exact = 2 * np.mean(np.asarray(sc.fresnel_dielectric(mu, eta)) * mu)
        assert abs(float(sc.fresnel_diffuse_reflectance(eta)) - exact) < 0.01 * exact


def test_thin_slab_reflectance_series():
    # R' = R + T^2 R / (1 - R^2) is the sum R + T R T + T R^3 T + ... of the internal bounces.
    cos = np.linspace(0.05, 1.0, 7)
    r = np.asarray(sc.fresnel_dielectric(cos, 1.5))
    series = r + sum((1 - r) ** 2 * r ** (2 * k + 1) for k in range(200))
    np.testing.assert_allclose(sc.thin_slab_reflectance(cos, 1.5), series, rtol=1e-12)
    # Sample weights: the mirror gets R'/P(reflect) = 1, the straight-through 1 likewise.
    b = sc.ThinDielectricBxDF(jnp.full((4,), 1.5))
    wo = jnp.broadcast_to(_dir(0.7), (2000, 3))
    s = b.sample_f(wo, jax.random.uniform(jax.random.key(0), (2000,)), jnp.zeros((2000, 2)))
    np.testing.assert_allclose(s.weight(), 1.0, rtol=1e-12)
    frac = float(jnp.mean(~s.is_transmission))
    r7 = float(sc.thin_slab_reflectance(np.cos(0.7), 1.5))
    assert abs(frac - r7) < 5 * np.sqrt(r7 * (1 - r7) / 2000)


@pytest.mark.parametrize("theta", [0.4, 1.2])
def test_rough_plastic_sampling_chi2(theta):
    bxdf = sc.RoughPlasticBxDF(0.5, 0.3, 1.5, distribution="ggx")
    res = _defective_chi2(bxdf, _dir(theta), key=jax.random.key(5), n_tests=2, n_samples=20_000)
    assert res.passed, res


def test_plastic_sample_weights_match_f_and_pdf():
    bxdf = sc.PlasticBxDF(0.5, 1.5)
    wo = jnp.broadcast_to(_dir(0.9), (4000, 3))
    u = jax.random.uniform(jax.random.key(3), (4000, 3))
    s = bxdf.sample_f(wo, u[:, 0], u[:, 1:])
    ok = ~s.is_delta & (s.pdf > 0)
    np.testing.assert_allclose(np.asarray(s.f)[ok], np.asarray(bxdf.f(wo, s.wi))[ok], rtol=1e-9)
    np.testing.assert_allclose(np.asarray(s.pdf)[ok], np.asarray(bxdf.pdf(wo, s.wi))[ok], rtol=1e-9)


def test_nonlinear_flag_per_row_equals_one_bxdf_per_flag():
    """A batch whose rows mix `nonlinear` True and False (the scene's plastics share one
    BxDF) evaluates each row as the BxDF built with that row's flag alone."""
    wo, wi = jnp.asarray(_dir(0.4, 0.3))[None], jnp.asarray(_dir(0.9, 2.0))[None]
    wo, wi = jnp.repeat(wo, 2, 0), jnp.repeat(wi, 2, 0)
    rho, eta = jnp.full((2, 4), 0.6), jnp.full((2,), 1.5)  # eta: one per row
    flags = jnp.asarray([True, False])
    for make in (
        lambda nl: sc.PlasticBxDF(rho, eta, nonlinear=nl),
        lambda nl: sc.RoughPlasticBxDF(rho, 0.3, 1.5, nonlinear=nl),
    ):
        mixed = np.asarray(make(flags).f(wo, wi))
        for row, flag in enumerate((True, False)):
            np.testing.assert_allclose(mixed[row], np.asarray(make(flag).f(wo, wi))[row])
        assert not np.allclose(mixed[0], mixed[1])  # the flag matters at this albedo
