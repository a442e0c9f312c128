"""Blend and mask BxDFs (Mitsuba 3's `blendbsdf`, `mask`): the one-sample mixture's sampling
weights are unbiased for the hemispherical-directional reflectance (compared with an
independent uniform-sphere estimate of the integral of f cos), `sample_f` reports the mixture's
own `f` and `pdf` at non-delta samples, and the mixture pdf integrates to the components'
valid mass."""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.scattering as sc

N = 200_000


def _uniform_sphere(n, seed):
    z = np.random.default_rng(seed).random((n, 2))
    cz = 1.0 - 2.0 * z[:, 0]
    r = np.sqrt(1.0 - cz**2)
    ph = 2.0 * np.pi * z[:, 1]
    return jnp.asarray(np.stack([r * np.cos(ph), r * np.sin(ph), cz], -1))


def _mean_se(x):
    x = np.asarray(x)
    return x.mean(), x.std() / np.sqrt(x.size)


def _cases():
    d = sc.DiffuseBxDF(jnp.array([0.5]))
    c = sc.RoughConductorBxDF(0.5, jnp.array([1.5]), jnp.array([3.0]))
    return {
        "blend": (sc.BlendBxDF(d, c, 0.3), 0.0),
        "mask": (sc.MaskBxDF(c, 0.6), 0.4),  # delta pass-through carries 1 - opacity
    }


@pytest.mark.parametrize("name", ["blend", "mask"])
def test_mixture_sampling_is_unbiased_and_consistent(name):
    bxdf, delta_part = _cases()[name]
    th = 0.6
    wo = jnp.broadcast_to(jnp.array([np.sin(th), 0.0, np.cos(th)]), (N, 3))
    rng = np.random.default_rng(1)
    s = bxdf.sample_f(wo, jnp.asarray(rng.random(N)), jnp.asarray(rng.random((N, 2))))
    ok = s.pdf > 0
    w = np.where(ok, s.f[:, 0] * jnp.abs(s.wi[:, 2]) / jnp.where(ok, s.pdf, 1.0), 0.0)
    wi = _uniform_sphere(N, 2)
    ref = np.asarray(bxdf.f(wo, wi)[:, 0] * jnp.abs(wi[:, 2]) * 4.0 * np.pi)
    (m1, e1), (m2, e2) = _mean_se(w), _mean_se(ref)
    assert abs(m1 - (m2 + delta_part)) < 5.0 * np.hypot(e1, e2), (m1, m2 + delta_part, e1, e2)
    smooth = np.asarray(ok & ~s.is_delta)
    assert smooth.sum() > N // 3
    np.testing.assert_allclose(
        np.asarray(bxdf.pdf(wo, s.wi))[smooth], np.asarray(s.pdf)[smooth], rtol=1e-10
    )
    np.testing.assert_allclose(
        np.asarray(bxdf.f(wo, s.wi)[:, 0])[smooth], np.asarray(s.f[:, 0])[smooth], rtol=1e-10
    )
    # The pdf is a density over the sphere: its integral is the mass of the non-delta samples.
    mass, se = _mean_se(np.asarray(bxdf.pdf(wo, wi)) * 4.0 * np.pi)
    assert abs(mass - smooth.mean()) < 5.0 * np.hypot(se, np.sqrt(smooth.mean() / N))


def test_bad_weights_are_named():
    d = sc.DiffuseBxDF(jnp.array([0.5]))
    with pytest.raises(eqx.EquinoxRuntimeError, match="weight"):
        sc.BlendBxDF(d, d, 1.5)
    with pytest.raises(eqx.EquinoxRuntimeError, match="opacity"):
        sc.MaskBxDF(d, -0.1)
    with pytest.raises(TypeError, match="BxDF"):
        sc.BlendBxDF(d, "diffuse", 0.5)
