"""Estimators: unbiasedness by t-tests over independent replicates, variance estimates, errors."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.montecarlo as mc
from tests.montecarlo._unbiased import (
    EXACT_2D,
    EXACT_HEMI,
    T_MAX,
    assert_unbiased,
    jvmap,
    keys,
    radiance_integrand,
    smooth_2d,
)


def test_estimate_mean_and_confidence_interval():
    x = jax.random.normal(jax.random.key(0), (10_000,)) * 2.0 + 3.0
    est = mc.estimate_mean(x)
    assert est.n == 10_000
    assert est.standard_error == pytest.approx(2.0 / 100, rel=0.05)
    lo, hi = est.confidence_interval(0.95)
    assert lo < 3.0 < hi
    assert float(hi - lo) == pytest.approx(2 * 1.959964 * float(est.standard_error), rel=1e-6)
    # Coverage of the 95% interval over replicates.
    ests = jvmap(lambda k: mc.estimate_mean(jax.random.normal(k, (200,))))(keys(1, 400))
    lo, hi = ests.confidence_interval(0.95)
    cover = np.mean((np.asarray(lo) < 0) & (np.asarray(hi) > 0))
    assert 0.91 < cover < 0.98


def test_importance_sampling_unbiased_and_cosine_beats_uniform():
    def est(k, sample, pdf):
        return mc.importance_sampling(radiance_integrand, sample, pdf, 256, u_dim=2, key=k)

    cos = jvmap(
        lambda k: est(k, mc.sample_cosine_hemisphere, lambda w: mc.cosine_hemisphere_pdf(w[:, 2]))
    )(keys())
    uni = jvmap(lambda k: est(k, mc.sample_uniform_hemisphere, mc.uniform_hemisphere_pdf))(keys())
    assert_unbiased(cos, EXACT_HEMI)
    assert_unbiased(uni, EXACT_HEMI)
    assert np.var(cos.mean) < 0.5 * np.var(uni.mean)


def test_importance_sampling_accepts_qmc_variates():
    u = mc.sobol(1024, 2, scramble="owen", key=jax.random.key(3))
    est = mc.importance_sampling(
        radiance_integrand,
        mc.sample_cosine_hemisphere,
        lambda w: mc.cosine_hemisphere_pdf(w[:, 2]),
        u_dim=2,
        u=u,
    )
    assert est.mean == pytest.approx(EXACT_HEMI, rel=2e-3)
    with pytest.raises(ValueError, match="either `key` or `u`"):
        mc.importance_sampling(
            radiance_integrand,
            mc.sample_cosine_hemisphere,
            mc.uniform_hemisphere_pdf,
            u_dim=2,
            u=u,
            key=jax.random.key(0),
        )
    with pytest.raises(eqx.EquinoxRuntimeError, match="u"):
        mc.antithetic(lambda u: u[:, 0], None, u_dim=1, u=jnp.full((4, 1), 1.5))
    with pytest.raises(ValueError, match="shape"):
        mc.importance_sampling(
            radiance_integrand, mc.sample_cosine_hemisphere, mc.uniform_hemisphere_pdf, u_dim=3, u=u
        )


STRATEGIES = [
    (mc.sample_uniform_hemisphere, mc.uniform_hemisphere_pdf, 64),
    (mc.sample_cosine_hemisphere, lambda w: mc.cosine_hemisphere_pdf(w[:, 2]), 192),
]


@pytest.mark.parametrize("heuristic", ["balance", "power"])
def test_mis_estimate_unbiased(heuristic):
    ests = jvmap(
        lambda k: mc.mis_estimate(
            radiance_integrand, STRATEGIES, u_dim=2, key=k, heuristic=heuristic
        )
    )(keys(4))
    assert_unbiased(ests, EXACT_HEMI)


@pytest.mark.parametrize("heuristic", ["balance", "power"])
def test_one_sample_mis_unbiased(heuristic):
    strategies = [s[:2] for s in STRATEGIES]
    ests = jvmap(
        lambda k: mc.one_sample_mis(
            radiance_integrand,
            strategies,
            jnp.array([0.3, 0.7]),
            256,
            u_dim=2,
            key=k,
            heuristic=heuristic,
        )
    )(keys(5))
    assert_unbiased(ests, EXACT_HEMI)


def test_stratified_estimate_unbiased_with_less_variance():
    strat = jvmap(lambda k: mc.stratified_estimate(smooth_2d, (8, 8), 4, key=k))(keys(6))
    assert_unbiased(strat, EXACT_2D)
    plain = jvmap(lambda k: mc.estimate_mean(smooth_2d(jax.random.uniform(k, (256, 2)))))(keys(7))
    assert np.var(strat.mean) < 0.05 * np.var(plain.mean)


def test_control_variate_unbiased_and_reduces_variance():
    def est(k):
        u = jax.random.uniform(k, (256,))
        return mc.control_variate(jnp.exp(u), u, 0.5)

    ests = jvmap(est)(keys(8))
    assert_unbiased(ests, math.e - 1)
    plain_var = (0.5 * (math.e**2 - 1) - (math.e - 1) ** 2) / 256
    assert np.var(ests.mean) < 0.1 * plain_var  # rho^2 = 0.98 for exp(U) vs U
    with pytest.raises(ValueError, match="share a shape"):
        mc.control_variate(jnp.ones(5), jnp.ones(4), 0.5)


def test_antithetic_unbiased_and_reduces_variance():
    ests = jvmap(lambda k: mc.antithetic(lambda u: jnp.exp(u[:, 0]), 128, u_dim=1, key=k))(keys(9))
    assert_unbiased(ests, math.e - 1)
    plain_var = (0.5 * (math.e**2 - 1) - (math.e - 1) ** 2) / 256
    assert np.var(ests.mean) < 0.1 * plain_var


def test_russian_roulette_unbiased():
    u = jax.random.uniform(jax.random.key(10), (400_000,))
    v = mc.russian_roulette(2.5, 0.3, u)
    est = mc.estimate_mean(v)
    assert abs(float(est.mean) - 2.5) < T_MAX * float(est.standard_error)
    assert set(np.unique(np.asarray(v)).round(6)) <= {0.0, round(2.5 / 0.3, 6)}


def test_roulette_and_split_unbiased():
    w = jnp.array([0.05, 0.4, 1.0, 2.3, 7.6])
    u = jax.random.uniform(jax.random.key(11), (200_000, 1))
    copies, new_w = mc.roulette_and_split(w[None, :], 1.0, u)
    total = np.asarray(copies).astype(float) * np.asarray(new_w)
    mean = total.mean(0)
    se = total.std(0) / math.sqrt(total.shape[0])
    assert np.all(np.abs(mean - np.asarray(w)) < T_MAX * se + 1e-12)
    assert np.all(np.asarray(copies)[:, 3] >= 2) and np.all(np.asarray(copies)[:, 3] <= 3)


def test_weighted_importance_sampling_eq_2_34_consistent():
    # Pixel reconstruction (thesis eq. 2.34): uniform offsets in [-1, 1]^2, tent filter weights,
    # r(x, y) = 1 + x + y^2. Exact: int f r / int f = 1 + 1/6.
    def est(k):
        x = jax.random.uniform(k, (1024, 2), minval=-1.0, maxval=1.0)
        wts = mc.tent_pdf(x[:, 0], 1.0) * mc.tent_pdf(x[:, 1], 1.0)
        return mc.weighted_importance_sampling(1 + x[:, 0] + x[:, 1] ** 2, wts)

    ests = jvmap(est)(keys(12))
    assert_unbiased(ests, 1 + 1 / 6)  # bias O(1/n) is far below the t-test's resolution here
    with pytest.raises(eqx.EquinoxRuntimeError, match="sum to 0"):
        mc.weighted_importance_sampling(jnp.ones(3), jnp.zeros(3))
    with pytest.raises(ValueError, match="weights"):
        mc.weighted_importance_sampling(jnp.ones(3), jnp.ones(4))


@pytest.mark.parametrize("weighted", [False, True])
def test_filter_importance_sampling_eq_2_35(weighted):
    def sample(u):
        return jnp.stack([mc.sample_tent(u[:, 0], 1.0), mc.sample_tent(u[:, 1], 1.0)], axis=-1)

    def filt(x):
        return mc.tent_pdf(x[:, 0], 1.0) * mc.tent_pdf(x[:, 1], 1.0)

    ests = jvmap(
        lambda k: mc.filter_importance_sampling(
            lambda x: 1 + x[:, 0] + x[:, 1] ** 2, filt, sample, filt, 512, key=k, weighted=weighted
        )
    )(keys(13))
    assert_unbiased(ests, 1 + 1 / 6)


def test_genz_exact_values_against_quadrature():
    # Tensor Gauss-Legendre quadrature in 2D is exact to ~1e-12 for the smooth families.
    xg, wg = np.polynomial.legendre.leggauss(60)
    xg, wg = (xg + 1) / 2, wg / 2
    X = np.stack(np.meshgrid(xg, xg, indexing="ij"), -1).reshape(-1, 2)
    W = np.outer(wg, wg).reshape(-1)
    for kind in ["oscillatory", "product_peak", "corner_peak", "gaussian"]:
        f, exact = mc.genz(kind, [1.3, 0.7], [0.25, 0.6])
        assert float(np.sum(W * np.asarray(f(jnp.asarray(X))))) == pytest.approx(exact, rel=1e-10)
