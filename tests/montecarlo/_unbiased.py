"""Shared by the estimator and integration tests: t-tests over replicates, test integrands."""

import math

import jax
import jax.numpy as jnp
import numpy as np

import radiometria.montecarlo as mc

R = 200  # replicates per t-test
T_MAX = 5.0  # |t| < 5: false-failure probability below 1e-6 per test


def radiance_integrand(w):
    # cos(theta) L(w) with L = 1 + 0.5 w_x + w_z^2 on the +z hemisphere: exact 3 pi / 2.
    return w[:, 2] * (1.0 + 0.5 * w[:, 0] + w[:, 2] ** 2)


EXACT_HEMI = 1.5 * math.pi


def assert_unbiased(estimates: mc.Estimate, exact: float, *, check_variance: bool = True):
    means = np.asarray(estimates.mean)
    t = (means.mean() - exact) / (means.std(ddof=1) / math.sqrt(len(means)))
    assert abs(t) < T_MAX, f"t = {t:.2f}: mean {means.mean()} vs exact {exact}"
    if check_variance:
        # The reported variance matches the spread of the replicates (within sampling error).
        ratio = np.mean(np.asarray(estimates.variance)) / means.var(ddof=1)
        assert 0.6 < ratio < 1.6, f"reported/empirical variance = {ratio:.3f}"


def jvmap(fn):
    """`jit(vmap(fn))`: one compilation instead of one per operation of an eager vmap."""
    return jax.jit(jax.vmap(fn))


def keys(seed=0, r=R):
    return jax.random.split(jax.random.key(seed), r)


def smooth_2d(x):
    return jnp.exp(x[:, 0]) * x[:, 1]


EXACT_2D = (math.e - 1) / 2
