"""`BeckmannDistribution`: normalisation and Smith's Lambda by Gauss-Legendre quadrature, D
and G1 against Mitsuba 3's `MicrofacetDistribution`, visible-normal sampling by chi-square
and its slope inversion against the closed-form CDF."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.special import erf

import radiometria.scattering as sc
from radiometria.montecarlo import chi2_test
from radiometria.scattering._microfacet import _beckmann_sample11

ALPHAS = [(0.1, 0.1), (0.5, 0.5), (0.3, 0.8), (1.0, 0.2)]


def _dir(theta, phi):
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def _hemisphere_quad(fn):
    """Integral of fn(directions (n, 3)) -> (n,) over the upper hemisphere: composite
    Gauss-Legendre in theta (finer near the pole, where narrow lobes live), midpoint rule in
    the periodic phi."""
    x, wx = np.polynomial.legendre.leggauss(160)
    edges = [0.0, 0.1, 0.25, 0.5, 1.0, np.pi / 2]
    th = np.concatenate(
        [(b - a) / 2 * x + (a + b) / 2 for a, b in zip(edges[:-1], edges[1:], strict=True)]
    )
    wt = np.concatenate([(b - a) / 2 * wx for a, b in zip(edges[:-1], edges[1:], strict=True)])
    n_phi = 256
    ph = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    t, p = np.meshgrid(th, ph, indexing="ij")
    dirs = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    vals = np.asarray(fn(jnp.asarray(dirs.reshape(-1, 3)))).reshape(t.shape)
    return float(np.sum(vals * np.sin(t) * wt[:, None]) * 2 * np.pi / n_phi)


def _walter_D(m, ax, ay):
    """Walter et al. 2007 eq. 25 in polar form, generalised to two roughnesses."""
    theta = np.arccos(m[2])
    phi = np.arctan2(m[1], m[0])
    t2 = np.tan(theta) ** 2 * (np.cos(phi) ** 2 / ax**2 + np.sin(phi) ** 2 / ay**2)
    return np.exp(-t2) / (np.pi * ax * ay * np.cos(theta) ** 4)


@pytest.mark.parametrize(("ax", "ay"), ALPHAS)
def test_D_closed_form_and_projected_area(ax, ay):
    d = sc.BeckmannDistribution(ax, ay)
    rng = np.random.default_rng(0)
    ms = np.array([_dir(t, p) for t, p in rng.uniform([0, 0], [1.4, 2 * np.pi], (20, 2))])
    np.testing.assert_allclose(d.D(jnp.asarray(ms)), [_walter_D(m, ax, ay) for m in ms], rtol=1e-10)
    assert float(d.D(jnp.array([0.6, 0.0, -0.8]))) == 0.0  # no normals below the surface
    # the projected microfacet area is the macro-surface's: int D cos = 1
    area = _hemisphere_quad(lambda m: d.D(m) * m[:, 2])
    assert area == pytest.approx(1.0, abs=2e-5)


@pytest.mark.parametrize(("ax", "ay"), ALPHAS[1:])
@pytest.mark.parametrize("theta", [0.0, 0.7, 1.3])
def test_lambda_is_the_projected_area_of_the_visible_facets(ax, ay, theta):
    """Smith: int D(m) max(0, w.m) dm = cos(theta) (1 + Lambda(w)) (Heitz 2014, eq. 17)."""
    d = sc.BeckmannDistribution(ax, ay)
    w = _dir(theta, 0.4)
    visible = _hemisphere_quad(lambda m: d.D(m) * jnp.maximum(0.0, m @ jnp.asarray(w)))
    lam = float(d.lambda_(jnp.asarray(w)))
    assert visible == pytest.approx(w[2] * (1 + lam), rel=1e-5)
    assert float(d.G1(jnp.asarray(w))) == pytest.approx(1 / (1 + lam), rel=1e-12)
    # D_visible is a density: it integrates to 1
    dv = _hemisphere_quad(lambda m: d.D_visible(jnp.broadcast_to(jnp.asarray(w), m.shape), m))
    assert dv == pytest.approx(1.0, abs=2e-5)
    # grazing and normal incidence
    assert float(d.lambda_(jnp.array([1.0, 0.0, 0.0]))) == np.inf
    assert float(d.lambda_(jnp.array([0.0, 0.0, 1.0]))) == 0.0


def test_D_and_G1_match_mitsuba():
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    rng = np.random.default_rng(1)
    for ax, ay in ALPHAS:
        ref = mi.MicrofacetDistribution(mi.MicrofacetType.Beckmann, ax, ay)
        ours = sc.BeckmannDistribution(ax, ay)
        for t, p, tv, pv in rng.uniform([0, 0, 0, 0], [1.3, 6.28, 1.5, 6.28], (10, 4)):
            m, v = _dir(t, p), _dir(tv, pv)
            d_ref = ref.eval(mi.Vector3f(*m))
            np.testing.assert_allclose(float(ours.D(jnp.asarray(m))), d_ref, rtol=2e-5, atol=1e-9)
            # Mitsuba's G1 is Walter et al.'s rational fit of the exact one (error < 0.4 %)
            g_ref = ref.smith_g1(mi.Vector3f(*v), mi.Vector3f(*m)) if v @ m > 0 else 0.0
            if v @ m > 0:
                assert float(ours.G1(jnp.asarray(v))) == pytest.approx(g_ref, abs=4e-3)


@pytest.mark.parametrize(("ax", "ay"), [(0.25, 0.25), (0.3, 0.8), (1.0, 0.2)])
@pytest.mark.parametrize(("theta", "phi"), [(0.9, 0.7), (2.2, 4.0)])
def test_visible_normal_sampling_chi2(ax, ay, theta, phi):
    """sample_wm draws D_visible (directions below the surface are mirrored). Narrow lobes sit
    in the top rows of the (cos theta, phi) grid: 120 rows resolve them (17 rows do not: the
    expected counts of the cells around the pole come out wrong, not the samples)."""
    d = sc.BeckmannDistribution(ax, ay)
    w = jnp.asarray(_dir(theta, phi))
    res = chi2_test(
        lambda u: d.sample_wm(jnp.broadcast_to(w, (u.shape[0], 3)), u),
        lambda m: d.pdf(jnp.broadcast_to(w, m.shape), m),
        domain="sphere",
        n_samples=40_000,
        key=jax.random.key(7),
        u_dim=2,
        resolution=(120, 40),
        quadrature=16,
        n_tests=6,
    )
    assert res.passed, res.message


def test_bad_roughness_is_refused():
    with pytest.raises(Exception, match="Beckmann roughness"):
        sc.BeckmannDistribution(jnp.asarray(1.5)).D(jnp.array([0.0, 0.0, 1.0]))


def test_visible_slope_inversion_solves_the_cdf_at_extreme_angles_and_variates():
    """The x-slope of a visible normal solves C(erf(x)) = u (Heitz & d'Eon 2014's marginal
    CDF, evaluated here with SciPy's erf) to 1e-5 with the few Newton steps the sampler takes,
    from grazing (cos 1e-4) to near-normal incidence and for u within 1e-6 of 0 and 1."""
    rng = np.random.default_rng(5)
    cos_t = np.concatenate([rng.uniform(1e-4, 0.05, 4000), rng.uniform(0.05, 0.9998, 4000)])
    u0 = np.concatenate([rng.random(6000), rng.uniform(1e-6, 1e-4, 1000),
                         rng.uniform(1 - 1e-4, 1 - 1e-6, 1000)])  # fmt: skip
    x, _ = _beckmann_sample11(jnp.asarray(cos_t), jnp.asarray(u0), jnp.asarray(u0))
    x = np.asarray(x)
    sin_t = np.sqrt(1 - cos_t**2)
    tan_t, cot_t = sin_t / cos_t, cos_t / sin_t
    norm = 1 + erf(cot_t) + tan_t * np.exp(-(cot_t**2)) / np.sqrt(np.pi)
    cdf = (1 + erf(x) + tan_t * np.exp(-(x**2)) / np.sqrt(np.pi)) / norm
    assert np.max(np.abs(cdf - u0)) < 1e-5
