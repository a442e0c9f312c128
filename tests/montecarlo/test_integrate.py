"""`integrate` and `convergence_study`: unbiasedness, error estimates, convergence rates, errors."""

import math

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


@pytest.mark.parametrize("method", ["mc", "stratified", "lhs", "sobol", "halton", "lattice"])
def test_integrate_box_unbiased(method):
    n = 256
    ests = jvmap(
        lambda k: mc.integrate(
            smooth_2d, ((0.0, 1.0), (0.0, 1.0)), n, method=method, key=k, n_replicates=4
        )
    )(keys(14, 64))
    assert_unbiased(ests, EXACT_2D, check_variance=False)


@pytest.mark.parametrize("domain, exact", [("hemisphere", EXACT_HEMI), ("sphere", 4 * math.pi / 3)])
def test_integrate_directions(domain, exact):
    f = radiance_integrand if domain == "hemisphere" else (lambda w: w[:, 2] ** 2 + w[:, 0])
    est = mc.integrate(f, domain, 4096, method="sobol", key=jax.random.key(15), n_replicates=8)
    assert abs(float(est.mean) - exact) < T_MAX * float(est.standard_error) + 1e-9
    est = mc.integrate(f, domain, 20_000, method="mc", key=jax.random.key(16))
    assert abs(float(est.mean) - exact) < T_MAX * float(est.standard_error)


def test_integrate_scaled_box():
    est = mc.integrate(
        lambda x: x[:, 0] * x[:, 1],
        ((0.0, 2.0), (1.0, 4.0)),
        1024,
        method="sobol",
        key=jax.random.key(17),
    )
    assert float(est.mean) == pytest.approx(2.0 * 7.5, rel=1e-3)


def test_integrate_bad_input():
    with pytest.raises(ValueError, match="valid values"):
        mc.integrate(smooth_2d, "cube", 16, key=jax.random.key(0))
    with pytest.raises(ValueError, match="method"):
        mc.integrate(smooth_2d, "hemisphere", 16, method="qmc", key=jax.random.key(0))
    with pytest.raises(ValueError, match="n = s\\^d"):
        mc.integrate(
            smooth_2d, ((0.0, 1.0), (0.0, 1.0)), 10, method="stratified", key=jax.random.key(0)
        )
    with pytest.raises(ValueError, match="one value per sample"):
        mc.integrate(lambda x: jnp.sum(x), "unit_cube", 16, dim=2, key=jax.random.key(0))
    with pytest.raises(ValueError, match="`n` must be >= 1"):
        mc.integrate(smooth_2d, "unit_cube", 0, dim=2, key=jax.random.key(0))


def test_convergence_plain_mc_slope_is_minus_half():
    f, exact = mc.genz("gaussian", [1.0, 1.5, 0.8], [0.3, 0.6, 0.5])
    study = mc.convergence_study(
        f,
        exact,
        [2**k for k in range(6, 15)],
        method="mc",
        dim=3,
        key=jax.random.key(18),
        n_replicates=64,
    )
    assert -0.62 < float(study.slope) < -0.38, study


@pytest.mark.parametrize("kind, d", [("gaussian", 2), ("oscillatory", 3), ("product_peak", 4)])
def test_convergence_owen_sobol_slope_near_minus_three_halves(kind, d):
    rng = np.random.default_rng(d)
    f, exact = mc.genz(kind, rng.uniform(0.5, 1.5, d), rng.uniform(0.2, 0.8, d))
    study = mc.convergence_study(
        f,
        exact,
        [2**k for k in range(5, 14)],
        method="sobol",
        dim=d,
        key=jax.random.key(19),
        n_replicates=48,
    )
    # Owen 1997: RMSE = O(n^-3/2 (log n)^((d-1)/2)); the log factor flattens the fit a little.
    assert -1.75 < float(study.slope) < -1.2, study


def test_convergence_discontinuous_is_slower_for_sobol():
    f, exact = mc.genz("discontinuous", [1.0, 1.0], [0.4, 0.7])
    study = mc.convergence_study(
        f,
        exact,
        [2**k for k in range(5, 14)],
        method="sobol",
        dim=2,
        key=jax.random.key(20),
        n_replicates=48,
    )
    # An axis-aligned jump costs QMC its n^-3/2 rate (about n^-1 here, n^-3/4 if oblique).
    assert -1.3 < float(study.slope) < -0.65
