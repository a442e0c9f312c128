"""The floor-1 array helpers (`radiometria._math`) against NumPy and JAX's own functions."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from radiometria._math import interp_columns, interp_table, interp_uniform_columns, uniform_grid


def _table(rng, n=37, columns=3):
    xp = np.sort(rng.uniform(360.0, 830.0, n))
    xp[5] = xp[4]  # a repeated knot: jnp.interp's zero-width guard
    return xp, rng.normal(size=(n, columns))


def test_interp_columns_equals_numpy_and_jnp_interp_per_column():
    """Every column is `np.interp` of that column (inside, at the knots, outside, with and
    without `left`/`right`), and `jnp.interp` to rounding."""
    rng = np.random.default_rng(3)
    xp, fp = _table(rng)
    x = np.concatenate([rng.uniform(300.0, 900.0, (40,)), xp, [xp[0], xp[-1], 200.0, 1000.0]])
    x = x.reshape(3, -1)
    for left, right in ((None, None), (0.0, 0.0), (-2.0, 5.0)):
        got = np.asarray(
            interp_columns(jnp.asarray(x), jnp.asarray(xp), jnp.asarray(fp), left, right)
        )
        assert got.shape == (*x.shape, fp.shape[1])
        for c in range(fp.shape[1]):
            want = np.interp(x, xp, fp[:, c], left=left, right=right)
            np.testing.assert_allclose(got[..., c], want, rtol=1e-13, atol=1e-13)
            same = jnp.interp(x, xp, fp[:, c], left=left, right=right)
            np.testing.assert_allclose(got[..., c], np.asarray(same), rtol=4e-16, atol=4e-16)


def test_interp_columns_one_column_table_and_scalar_query():
    rng = np.random.default_rng(4)
    xp, fp = _table(rng, columns=1)
    got = interp_columns(500.0, jnp.asarray(xp), jnp.asarray(fp[:, 0]))
    assert got.shape == ()
    np.testing.assert_allclose(float(got), np.interp(500.0, xp, fp[:, 0]), rtol=1e-13)


def test_interp_columns_gradients_equal_jnp_interp():
    """d/dx and d/dfp, including at a knot, at a repeated knot and outside the table."""
    rng = np.random.default_rng(5)
    xp, fp = _table(rng, columns=2)
    x = jnp.asarray([400.0, xp[7], xp[4], 350.0, 850.0])

    def ours(x, fp):
        return jnp.sum(interp_columns(x, jnp.asarray(xp), fp, left=0.0, right=0.0) ** 2)

    def theirs(x, fp):
        cols = [jnp.interp(x, jnp.asarray(xp), fp[:, c], left=0.0, right=0.0) for c in range(2)]
        return sum(jnp.sum(v**2) for v in cols)

    g_ours = jax.jit(jax.grad(ours, argnums=(0, 1)))(x, jnp.asarray(fp))
    g_theirs = jax.grad(theirs, argnums=(0, 1))(x, jnp.asarray(fp))
    for a, b in zip(g_ours, g_theirs, strict=True):
        assert np.all(np.isfinite(np.asarray(a)))
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-12, atol=1e-14)


def test_interp_columns_refuses_mismatched_tables():
    with pytest.raises(ValueError, match=r"`fp` \(n, \.\.\.\) with the same n"):
        interp_columns(jnp.ones(3), jnp.arange(5.0), jnp.ones((4, 3)))
    with pytest.raises(ValueError, match="at least 2 samples"):
        interp_columns(jnp.ones(3), jnp.arange(1.0), jnp.ones((1,)))


def test_interp_uniform_columns_equals_interp_columns():
    """Evenly spaced knots: same values as the searched lookup inside, at and between knots,
    at the ends and outside, with and without `left`/`right`; gradients in x and fp too."""
    rng = np.random.default_rng(6)
    xp = 360.0 + 5.0 * np.arange(95)
    assert uniform_grid(xp) == (360.0, 5.0)
    fp = jnp.asarray(rng.random((95, 3)))
    x = jnp.asarray(np.concatenate([rng.uniform(340, 850, 200), xp[[0, 7, 94]], [362.5]]))
    for left, right in [(None, None), (0.0, 0.0), (-1.0, 2.0)]:
        got = interp_uniform_columns(x, 360.0, 5.0, fp, left=left, right=right)
        want = interp_columns(x, jnp.asarray(xp), fp, left=left, right=right)
        np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-13, atol=1e-14)

    def loss(f, x, fp):
        return jnp.sum(f(x, fp) ** 2)

    inside = x[(x > 360.0) & (x < xp[-1])]
    ours = jax.grad(loss, argnums=(1, 2))(
        lambda x, fp: interp_uniform_columns(x, 360.0, 5.0, fp), inside, fp
    )
    ref = jax.grad(loss, argnums=(1, 2))(lambda x, fp: interp_columns(x, xp, fp), inside, fp)
    for a, b in zip(ours, ref, strict=True):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-12, atol=1e-13)


@pytest.mark.parametrize("even", [True, False])
def test_interp_table_is_np_interp_with_or_without_a_grid(even):
    rng = np.random.default_rng(7)
    xp = 360.0 + 5.0 * np.arange(20) if even else np.sort(rng.uniform(360.0, 460.0, 20))
    grid = uniform_grid(xp)
    assert (grid is not None) == even
    fp = rng.random(20)
    x = rng.uniform(340.0, 480.0, 300)
    got = interp_table(jnp.asarray(x), jnp.asarray(xp), jnp.asarray(fp), grid, 0.0, 0.0)
    want = np.interp(x, xp, fp, left=0.0, right=0.0)
    np.testing.assert_allclose(np.asarray(got), want, rtol=1e-13, atol=1e-14)


def test_uniform_grid_refuses_uneven_knots():
    assert uniform_grid([1.0, 2.0, 3.5]) is None
    assert uniform_grid([1.0]) is None
    assert uniform_grid([3.0, 2.0, 1.0]) is None
    start, step = uniform_grid(np.linspace(360.0, 830.0, 471))
    assert (start, step) == (360.0, 1.0)


@pytest.mark.parametrize("n", [1, 255, 256, 1000, 65536])
@pytest.mark.parametrize("fraction", [0.0, 0.4, 1.0])
def test_compact_indices_is_jnp_nonzero_with_a_size(n, fraction):
    """The live-path compaction gives `jnp.nonzero(mask, size=, fill_value=)`'s indices for
    sizes below, at and above the number of True entries, under `jit`."""
    from radiometria._math import compact_indices

    mask = np.random.default_rng(n).uniform(size=n) < fraction
    for size in {1, max(1, int(mask.sum()) // 2), n, n + 300}:
        want = np.asarray(jnp.nonzero(jnp.asarray(mask), size=size, fill_value=n)[0])
        got = jax.jit(compact_indices, static_argnums=(1, 2))(jnp.asarray(mask), size, n)
        assert got.dtype == jnp.int32
        np.testing.assert_array_equal(np.asarray(got), want)


def test_fast_inverse_trigonometry_within_float32_ulps_of_numpy():
    """`atan2_fast`, `acos_fast` and `asin_fast` against float64 NumPy: within 4 float32 ulps
    of the answer (plus the square root's rounding for acos and asin) on random and hostile
    inputs (signed zeros, the axes, the octant boundaries); float64 inputs take JAX's own."""
    from radiometria._math import acos_fast, asin_fast, atan2_fast

    rng = np.random.default_rng(11)
    y = np.concatenate([rng.normal(size=50000), [0.0, -0.0, 0.0, -0.0, 1.0, -1.0, 0.0, 1e-30, 3.0]])
    x = np.concatenate([rng.normal(size=50000), [0.0, 0.0, -0.0, -0.0, 0.0, -0.0, -1.0, 1.0, 3.0]])
    y32, x32 = y.astype(np.float32), x.astype(np.float32)
    want = np.arctan2(y32.astype(np.float64), x32.astype(np.float64))
    got = np.asarray(jax.jit(atan2_fast)(jnp.asarray(y32), jnp.asarray(x32)))
    assert got.dtype == np.float32
    ulp = np.spacing(np.abs(want).astype(np.float32)).astype(np.float64)
    assert np.all(np.abs(got - want) <= 4 * np.maximum(ulp, 1e-45)), np.max(
        np.abs(got - want) / ulp
    )
    np.testing.assert_array_equal(np.signbit(got), np.signbit(want))
    c = np.concatenate([rng.uniform(-1, 1, 50000), [-1.0, -0.5, 0.0, -0.0, 0.5, 1.0]]).astype(
        np.float32
    )
    for fast, ref in ((acos_fast, np.arccos), (asin_fast, np.arcsin)):
        got = np.asarray(jax.jit(fast)(jnp.asarray(c)))
        np.testing.assert_allclose(got, ref(c.astype(np.float64)), rtol=0, atol=1e-6)
        np.testing.assert_allclose(  # float64: JAX's own functions
            np.asarray(fast(jnp.asarray(c, jnp.float64))), ref(c.astype(np.float64)), rtol=1e-14
        )
    np.testing.assert_allclose(
        np.asarray(atan2_fast(jnp.asarray(y), jnp.asarray(x))), np.arctan2(y, x), rtol=1e-14
    )


def test_sincos_pi_within_float32_rounding_of_numpy_and_exact_at_quarter_turns():
    """`sincos_pi` against float64 NumPy on [-3, 3] (float32: 2e-7 absolute, about 2 ulps of
    1; exactly 0 and +-1 at multiples of a half, where the reduction leaves r = 0), its
    gradient against pi cos(pi x), and float64 inputs taking JAX's own sin and cos."""
    from radiometria._math import sincos_pi

    x = np.concatenate([np.linspace(-3.0, 3.0, 60001), np.arange(-6, 7) / 2.0]).astype(np.float32)
    s, c = jax.jit(sincos_pi)(jnp.asarray(x))
    assert s.dtype == c.dtype == jnp.float32
    want_s, want_c = np.sin(np.pi * x.astype(np.float64)), np.cos(np.pi * x.astype(np.float64))
    np.testing.assert_allclose(np.asarray(s), want_s, rtol=0, atol=2e-7)
    np.testing.assert_allclose(np.asarray(c), want_c, rtol=0, atol=2e-7)
    halves = x[-13:]
    np.testing.assert_array_equal(np.asarray(s)[-13:], np.round(np.sin(np.pi * halves)))
    np.testing.assert_array_equal(np.asarray(c)[-13:], np.round(np.cos(np.pi * halves)))
    grad = jax.vmap(jax.grad(lambda t: sincos_pi(t)[0]))(jnp.asarray(x[:2000:97]))
    np.testing.assert_allclose(np.asarray(grad), np.pi * want_c[:2000:97], rtol=0, atol=2e-6)
    s64, c64 = sincos_pi(jnp.asarray(x, jnp.float64))
    np.testing.assert_allclose(np.asarray(s64), want_s, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.asarray(c64), want_c, rtol=0, atol=1e-15)
