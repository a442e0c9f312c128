"""The coefficient table: packaged accuracy, lookup semantics, errors (fit: test_fit_lut.py)."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.upsampling as up
from radiometria.upsampling._data import read_packaged


def _pbrt_lookup(scale, coeffs, rgb):
    """A plain-Python transcription of pbrt-v4's RGBToSpectrumTable::operator()."""
    res = scale.shape[0]
    r, g, b = (float(v) for v in rgb)
    if r == g == b:
        v = r
        c2 = np.inf if v >= 1 else -np.inf if v <= 0 else (v - 0.5) / np.sqrt(v * (1 - v))
        return np.array([0.0, 0.0, c2])
    maxc = (0 if r > b else 2) if r > g else (1 if g > b else 2)
    z = rgb[maxc]
    x = rgb[(maxc + 1) % 3] * (res - 1) / z
    y = rgb[(maxc + 2) % 3] * (res - 1) / z
    xi, yi = min(int(x), res - 2), min(int(y), res - 2)
    zi = max(0, min(res - 2, int(np.searchsorted(scale, z, side="left")) - 1))
    dx, dy = x - xi, y - yi
    dz = (z - scale[zi]) / (scale[zi + 1] - scale[zi])
    out = np.zeros(3)
    for i in range(3):
        co = lambda ox, oy, oz: coeffs[maxc, zi + oz, yi + oy, xi + ox, i]  # noqa: B023, E731
        lerp = lambda t, a, b: (1 - t) * a + t * b  # noqa: E731
        out[i] = lerp(
            dz,
            lerp(dy, lerp(dx, co(0, 0, 0), co(1, 0, 0)), lerp(dx, co(0, 1, 0), co(1, 1, 0))),
            lerp(dy, lerp(dx, co(0, 0, 1), co(1, 0, 1)), lerp(dx, co(0, 1, 1), co(1, 1, 1))),
        )
    return out


@pytest.fixture(scope="module")
def lut():
    return up.get_lut()


def test_packaged_table_is_the_fitters_and_converged():
    scale, coeffs, meta = read_packaged()  # checks the sha256
    assert coeffs.shape == (3, 64, 64, 64, 3) and coeffs.dtype == np.float32
    np.testing.assert_allclose(scale, up.brightness_scale(64), rtol=1e-6, atol=1e-12)
    s = meta["fit_summary"]
    assert s["not_converged"] == 0 and s["out_of_reach"] == 0
    assert s["residual_max"] <= s["tolerance"] <= 5e-3
    assert meta["fit"]["wavelength_step_nm"] == 1.0


def test_packaged_table_accuracy(lut):
    """The accuracy goal: CIEDE2000 round trip, 33^3 encoded grid and 1e5 random colours."""
    grid = up.roundtrip_grid_rgb(33)
    de_grid, _ = up.roundtrip_delta_E(lut, grid)
    rnd = up.roundtrip_random_rgb(100_000, seed=1)
    de_rnd, _ = up.roundtrip_delta_E(lut, rnd)
    assert de_grid.max() <= 1.0 and de_rnd.max() <= 1.0
    assert de_grid.mean() <= 0.03 and de_rnd.mean() <= 0.03
    # The dark saturated corner where pbrt-v4's table reaches 11.7.
    dark = np.array([[0.0, 0.0024, 0.0], [0.0024, 0.0, 0.0], [0.0, 0.0, 0.0024], [1e-4, 0, 3e-4]])
    de_dark, _ = up.roundtrip_delta_E(lut, dark)
    assert de_dark.max() <= 1.0


def test_lookup_matches_pbrt_transcription(lut):
    rng = np.random.default_rng(2)
    rgb = np.concatenate([
        rng.random((200, 3)),
        rng.random((50, 3)) ** 6,  # dark
        np.array([[0.5, 0.5, 0.2], [0.3, 0.1, 0.3], [0.1, 0.4, 0.4], [0.7, 0.7, 0.7], [1, 1, 1],
                  [0, 0, 0], [1, 0, 0], [0, 1e-3, 0], [1, 1, 0.999], [0.2, 0, 0.2]]),
    ])  # fmt: skip
    scale = np.asarray(lut.scale, np.float64)
    coeffs = np.asarray(lut.coeffs, np.float64)
    ref = np.stack([_pbrt_lookup(scale, coeffs, c) for c in rgb])
    got = np.asarray(lut.coefficients(rgb))
    np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-12)


def test_lookup_greys_white_black(lut):
    wl = np.linspace(360.0, 830.0, 95)
    v = np.array([0.0, 1e-6, 0.01, 0.18, 0.5, 0.9, 1.0])
    c = np.asarray(lut.coefficients(np.repeat(v[:, None], 3, axis=1)))
    assert np.all(c[:, :2] == 0.0)
    spec = np.asarray(up.SigmoidPolynomialSpectrum(c)(wl))
    np.testing.assert_allclose(spec, np.repeat(v[:, None], wl.size, axis=1), rtol=1e-12, atol=0)
    assert np.all(spec[0] == 0.0) and np.all(spec[-1] == 1.0)


def test_own_white_and_greys_roundtrip_exactly(lut):
    de, rgb_out = up.roundtrip_delta_E(lut, np.array([[1.0, 1.0, 1.0], [0.4, 0.4, 0.4]]))
    np.testing.assert_allclose(rgb_out, [[1.0, 1.0, 1.0], [0.4, 0.4, 0.4]], rtol=1e-12)
    assert de.max() < 1e-9


def test_lookup_grad_jit_vmap(lut):
    pts = jnp.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [0.3, 0.3, 0.3], [1.0, 0.0, 0.0],
                     [0.2, 0.5, 0.1], [0.9, 0.9, 0.2], [0.0, 1e-3, 0.0]])  # fmt: skip
    f = lambda x: jnp.sum(up.SigmoidPolynomialSpectrum(lut.coefficients(x))(550.0))  # noqa: E731
    g = jax.vmap(jax.grad(f))(pts)
    assert np.all(np.isfinite(np.asarray(g)))
    c = lut.coefficients(pts)
    np.testing.assert_array_equal(
        np.asarray(jax.jit(lambda x: lut.coefficients(x))(pts)), np.asarray(c)
    )
    np.testing.assert_array_equal(
        np.asarray(jax.vmap(lambda x: lut.coefficients(x))(pts)), np.asarray(c)
    )
    # The table itself is differentiable too (a pytree).
    gt = jax.grad(lambda t: jnp.sum(t.coefficients(pts[4:6])))(lut)
    assert np.isfinite(np.asarray(gt.coeffs)).all() and np.asarray(gt.coeffs).any()


def test_lookup_rejects_bad_rgb(lut):
    for bad in ([-0.1, 0.2, 0.3], [np.nan, 0.2, 0.3], [np.inf, 0, 0], [1.2, 0.2, 0.3]):
        with pytest.raises(ValueError, match="rgb"):
            lut.coefficients(np.array(bad))
    with pytest.raises(eqx.EquinoxRuntimeError, match="rgb"):
        eqx.filter_jit(lambda x: lut.coefficients(x))(jnp.array([-0.1, 0.2, 0.3]))


def test_lut_rejects_bad_shape():
    with pytest.raises(ValueError, match="shape"):
        up.RGBToSpectrumLUT(np.linspace(0, 1, 4), np.zeros((3, 4, 4, 3, 3)))
