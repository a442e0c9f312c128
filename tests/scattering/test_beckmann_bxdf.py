"""Rough BxDFs with the Beckmann distribution (Mitsuba 3's default for `roughconductor` and
`roughdielectric`): f and pdf against Mitsuba 3's BSDFs, sampling against the pdf (chi-square),
sample_f consistent with f and pdf, energy (white furnace) and the distribution choice."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.scattering as sc
from tests.scattering.test_bxdfs import _defective_chi2, _dir, _random_dirs

mi = pytest.importorskip("mitsuba")
dr = pytest.importorskip("drjit")

from tests.scattering.test_mitsuba import _dirs, _mi_eval_pdf  # noqa: E402

# Mitsuba's Beckmann G1 is Walter et al.'s rational fit of the exact Smith G1 that
# `BeckmannDistribution` evaluates (error < 0.4 % each, so < 0.8 % for G1(wo) G1(wi)).
RTOL = 8e-3


def _close(ours, ref):
    ours, ref = np.asarray(ours, float), np.asarray(ref, float)
    atol = 1e-5 * max(1.0, float(np.max(np.abs(ref))))
    np.testing.assert_allclose(ours, ref, rtol=RTOL, atol=atol)


@pytest.fixture(scope="module")
def _scalar_rgb():
    mi.set_variant("scalar_rgb")


def test_distribution_field_and_choice():
    assert isinstance(
        sc.RoughConductorBxDF(0.3, 0.2, 3.0).distribution, sc.TrowbridgeReitzDistribution
    )
    b = sc.RoughConductorBxDF(0.3, 0.2, 3.0, distribution="beckmann")
    assert isinstance(b.distribution, sc.BeckmannDistribution)
    d = sc.RoughDielectricBxDF(0.3, 1.5, distribution="beckmann")
    assert isinstance(d.distribution, sc.BeckmannDistribution)
    with pytest.raises(ValueError, match="phong.*'ggx', 'beckmann'"):
        sc.RoughConductorBxDF(0.3, 0.2, 3.0, distribution="phong")
    with pytest.raises(TypeError, match="distribution"):
        sc.RoughDielectricBxDF(0.3, 1.5, distribution=sc.BeckmannDistribution(0.3))


@pytest.mark.parametrize("alpha", [0.1, 0.45])
def test_beckmann_rough_conductor_matches_mitsuba(_scalar_rgb, alpha):
    wo, wi = _dirs(200, 12, "upper"), _dirs(200, 13, "upper")
    wi[:100] = wo[:100] * np.array([-1, -1, 1]) + 0.5 * alpha * _dirs(100, 14)
    wi[:100] /= np.linalg.norm(wi[:100], axis=1, keepdims=True)
    wi[:100, 2] = np.abs(wi[:100, 2])
    wi = wi.astype(np.float32).astype(float)
    bsdf = mi.load_dict({"type": "roughconductor", "alpha": alpha, "eta": 0.2, "k": 3.0})
    assert "beckmann" in str(bsdf)  # Mitsuba's default distribution
    ev, pd = _mi_eval_pdf(bsdf, wo, wi)
    ours = sc.RoughConductorBxDF(alpha, 0.2, 3.0, masking="separable", distribution="beckmann")
    _close(np.asarray(ours.f(wo, wi))[:, 0] * np.abs(wi[:, 2]), ev)
    _close(ours.pdf(wo, wi), pd)
    # Anisotropic roughness.
    bsdf = mi.load_dict(
        {"type": "roughconductor", "alpha_u": 0.1, "alpha_v": alpha, "eta": 1.3, "k": 2.0}
    )
    ev, pd = _mi_eval_pdf(bsdf, wo, wi)
    ours = sc.RoughConductorBxDF(0.1, 1.3, 2.0, alpha, masking="separable", distribution="beckmann")
    _close(np.asarray(ours.f(wo, wi))[:, 0] * np.abs(wi[:, 2]), ev)
    _close(ours.pdf(wo, wi), pd)


@pytest.mark.parametrize("side", ["outside", "inside"])
def test_beckmann_rough_dielectric_matches_mitsuba(_scalar_rgb, side):
    wo = _dirs(300, 15, "upper" if side == "outside" else "lower")
    wi = _dirs(300, 16)
    bsdf = mi.load_dict({"type": "roughdielectric", "alpha": 0.3, "int_ior": 1.5, "ext_ior": 1.0})
    ev, pd = _mi_eval_pdf(bsdf, wo, wi)
    ours = sc.RoughDielectricBxDF(0.3, 1.5, masking="separable", distribution="beckmann")
    _close(np.asarray(ours.f(wo, wi))[:, 0] * np.abs(wi[:, 2]), ev)
    _close(ours.pdf(wo, wi), pd)


CHI2_CASES = [
    ("conductor", 0.2, sc.RoughConductorBxDF(0.3, 0.2, 3.0, distribution="beckmann")),
    ("conductor_aniso", 1.2, sc.RoughConductorBxDF(0.1, 1.3, 2.0, 0.5, distribution="beckmann")),
    ("dielectric_out", 0.9, sc.RoughDielectricBxDF(0.3, 1.5, distribution="beckmann")),
    ("dielectric_in", np.pi - 0.4, sc.RoughDielectricBxDF(0.2, 1.5, distribution="beckmann")),
]


def _maybe_slow(case):
    """The isotropic conductor and the outside dielectric run with the slow tests only."""
    slow = case[0] in ("conductor", "dielectric_out")
    return pytest.param(*case, id=case[0], marks=[pytest.mark.slow] if slow else [])


@pytest.mark.parametrize("name,theta,bxdf", [_maybe_slow(c) for c in CHI2_CASES])
def test_beckmann_bxdf_sampling_chi2(name, theta, bxdf):
    res = _defective_chi2(
        bxdf, _dir(theta), key=jax.random.key(31), n_tests=len(CHI2_CASES), n_samples=30_000
    )
    assert res.passed, res.message


@pytest.mark.parametrize(
    "bxdf",
    [
        sc.RoughConductorBxDF(
            0.3, jnp.array([0.2, 1.1]), jnp.array([3.0, 2.0]), distribution="beckmann"
        ),
        sc.RoughDielectricBxDF(0.4, 1.5, masking="separable", distribution="beckmann"),
    ],
    ids=["conductor", "dielectric"],
)
def test_beckmann_sample_consistent_with_f_and_pdf(bxdf):
    k1, k2 = jax.random.split(jax.random.key(32))
    wo = _random_dirs(k1, 1000)
    u = jax.random.uniform(k2, (1000, 3))
    s = jax.jit(lambda wo, u: bxdf.sample_f(wo, u[:, 0], u[:, 1:]))(wo, u)
    ok = np.asarray(s.pdf > 0)
    assert ok.mean() > 0.5
    np.testing.assert_allclose(s.f[ok], bxdf.f(wo, s.wi)[ok], rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(s.pdf[ok], bxdf.pdf(wo, s.wi)[ok], rtol=1e-7, atol=1e-12)
    np.testing.assert_array_equal(s.f[~ok], 0.0)
    assert np.all(np.isfinite(np.asarray(s.weight())))


@eqx.filter_jit
def _albedos(bxdf, wo, u):
    """Mean and standard error of the importance-transport sample weight, per direction."""
    s = jax.vmap(lambda w: bxdf.sample_f(w, u[:, 0], u[:, 1:], mode="importance"))(wo)
    w = s.weight()[..., 0]
    return w.mean(-1), w.std(-1) / np.sqrt(u.shape[0])


def test_beckmann_white_furnace():
    """Single scattering loses energy only to masking: the albedo of a unit-Fresnel conductor
    is at most 1, near 1 for a smooth-ish surface at normal incidence, and a dielectric's
    reflection + transmission (importance transport) is at most 1, from either side."""
    u = jax.random.uniform(jax.random.key(33), (10_000, 3))
    wo = jnp.stack([_dir(0.0), _dir(1.2), -_dir(0.0), -_dir(1.2)])
    for alpha, low in [(0.05, 0.995), (0.6, 0.8)]:
        b = sc.RoughConductorBxDF(alpha, 1.0, 1e4, distribution="beckmann")
        m, se = map(np.asarray, _albedos(b, wo[:2], u))
        assert np.all(m <= 1 + 6 * se), (alpha, m, se)
        assert m[0] > low, (alpha, m)
    m, se = map(
        np.asarray, _albedos(sc.RoughDielectricBxDF(0.3, 1.5, distribution="beckmann"), wo, u)
    )
    assert np.all((m > 0.85) & (m <= 1 + 6 * se)), (m, se)
