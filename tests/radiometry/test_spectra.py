"""Sampled spectra: trapezoid integration and linear resampling on nm grids."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads

from radiometria.radiometry import integrate_spectrum, resample_spectrum

RNG = np.random.default_rng(0)
IRREGULAR_NM = np.sort(RNG.uniform(360.0, 830.0, 57))


def test_integrate_spectrum_matches_numpy_trapezoid():
    values = RNG.normal(size=(3, 4, IRREGULAR_NM.size))
    np.testing.assert_allclose(
        integrate_spectrum(values, IRREGULAR_NM),
        np.trapezoid(values, IRREGULAR_NM, axis=-1),
        rtol=1e-13,
    )


@pytest.mark.parametrize("axis", [0, 1, -1, -2])
def test_integrate_spectrum_axis(axis):
    values = RNG.normal(size=(5, 6, 7))
    n = values.shape[axis]
    grid = np.cumsum(RNG.uniform(0.5, 2.0, n)) + 400.0
    np.testing.assert_allclose(
        integrate_spectrum(values, grid, axis=axis),
        np.trapezoid(values, grid, axis=axis),
        rtol=1e-13,
    )


def test_integrate_spectrum_per_spectrum_grids():
    grids = np.sort(RNG.uniform(400.0, 700.0, (4, 9)), axis=-1)
    values = RNG.normal(size=(4, 9))
    expected = [np.trapezoid(v, g) for v, g in zip(values, grids, strict=True)]
    np.testing.assert_allclose(integrate_spectrum(values, grids), expected, rtol=1e-13)


def test_integrate_spectrum_exact_for_linear_functions():
    # The trapezoid rule integrates piecewise-linear functions exactly, on any grid.
    values = 2.0 * IRREGULAR_NM - 300.0
    lo, hi = IRREGULAR_NM[0], IRREGULAR_NM[-1]
    expected = (hi**2 - lo**2) - 300.0 * (hi - lo)
    assert float(integrate_spectrum(values, IRREGULAR_NM)) == pytest.approx(expected, rel=1e-13)


def test_integrate_spectrum_jit_vmap_grad():
    values = jnp.asarray(RNG.normal(size=(3, IRREGULAR_NM.size)))
    grid = jnp.asarray(IRREGULAR_NM)
    eager = integrate_spectrum(values, grid)
    np.testing.assert_allclose(jax.jit(integrate_spectrum)(values, grid), eager, rtol=1e-14)
    np.testing.assert_allclose(
        jax.vmap(integrate_spectrum, in_axes=(0, None))(values, grid), eager, rtol=1e-14
    )
    check_grads(integrate_spectrum, (values, grid), order=1, modes=("rev",))


def test_integrate_spectrum_rejects_bad_input():
    values = np.ones(5)
    with pytest.raises(ValueError, match="must match"):
        integrate_spectrum(values, np.linspace(400.0, 500.0, 6))
    with pytest.raises(ValueError, match="shape"):
        integrate_spectrum(np.ones((2, 5)), np.ones((3, 5)))
    with pytest.raises(ValueError, match="at least 2"):
        integrate_spectrum(np.ones(1), np.ones(1))
    with pytest.raises(ValueError, match="at least one dimension"):
        integrate_spectrum(1.0, np.ones(1))
    with pytest.raises(ValueError, match="axis"):
        integrate_spectrum(values, np.linspace(400.0, 500.0, 5), axis=1)
    with pytest.raises(TypeError, match="values"):
        integrate_spectrum(np.arange(5), np.linspace(400.0, 500.0, 5))
    with pytest.raises(TypeError, match="wavelengths_nm"):
        integrate_spectrum(values, np.arange(400, 405))


@pytest.mark.parametrize(
    "grid",
    [[400.0, 410.0, 405.0, 420.0], [400.0, 410.0, 410.0, 420.0], [420.0, 410.0, 405.0, 400.0]],
)
def test_integrate_spectrum_rejects_non_increasing_grid(grid):
    with pytest.raises(eqx.EquinoxRuntimeError, match="strictly increasing"):
        integrate_spectrum(np.ones(4), np.asarray(grid))
    with pytest.raises(eqx.EquinoxRuntimeError, match="strictly increasing"):
        eqx.filter_jit(integrate_spectrum)(jnp.ones(4), jnp.asarray(grid))


def test_integrate_spectrum_nan_propagates():
    values = np.ones(5)
    values[2] = np.nan
    assert np.isnan(float(integrate_spectrum(values, np.linspace(400.0, 500.0, 5))))


# --- resample_spectrum --------------------------------------------------------------------------


def test_resample_spectrum_matches_numpy_interp():
    values = RNG.normal(size=IRREGULAR_NM.size)
    new = np.linspace(370.0, 820.0, 200)
    np.testing.assert_allclose(
        resample_spectrum(values, IRREGULAR_NM, new),
        np.interp(new, IRREGULAR_NM, values),
        rtol=1e-13,
        atol=1e-15,
    )


def test_resample_spectrum_exact_at_samples_and_roundtrip():
    values = RNG.normal(size=(2, IRREGULAR_NM.size))
    np.testing.assert_array_equal(resample_spectrum(values, IRREGULAR_NM, IRREGULAR_NM), values)
    # Resampling onto a finer grid that contains the old one, and back, is the identity.
    fine = np.unique(
        np.concatenate([IRREGULAR_NM, np.linspace(IRREGULAR_NM[0], IRREGULAR_NM[-1], 300)])
    )
    there = resample_spectrum(values, IRREGULAR_NM, fine)
    np.testing.assert_allclose(
        resample_spectrum(there, fine, IRREGULAR_NM), values, rtol=1e-13, atol=1e-15
    )


def test_resample_spectrum_extrapolation_policies():
    grid = np.array([400.0, 500.0, 600.0])
    values = np.array([1.0, 2.0, 4.0])
    new = np.array([300.0, 400.0, 450.0, 600.0, 700.0])
    np.testing.assert_array_equal(resample_spectrum(values, grid, new), [0.0, 1.0, 1.5, 4.0, 0.0])
    np.testing.assert_array_equal(
        resample_spectrum(values, grid, new, extrapolation="constant"), [1.0, 1.0, 1.5, 4.0, 4.0]
    )
    with pytest.raises(ValueError, match="extrapolation"):
        resample_spectrum(values, grid, new, extrapolation="linear")


def test_resample_spectrum_shapes_and_axis():
    grid = np.linspace(400.0, 700.0, 7)
    values = RNG.normal(size=(3, 7, 2))
    new = np.array([[410.0, 420.0, 430.0], [440.0, 450.0, 460.0]])
    out = resample_spectrum(values, grid, new, axis=1)
    assert out.shape == (3, 2, 3, 2)
    expected = np.stack(
        [
            np.stack([np.interp(new, grid, values[i, :, j]) for j in range(2)], axis=-1)
            for i in range(3)
        ]
    )
    np.testing.assert_allclose(out, expected, rtol=1e-13)
    assert resample_spectrum(values[0, :, 0], grid, 455.0).shape == ()


def test_resample_spectrum_jit_vmap_grad():
    grid = jnp.linspace(400.0, 700.0, 7)
    values = jnp.asarray(RNG.normal(size=(4, 7)))
    new = jnp.asarray([405.0, 512.5, 699.0])
    fn = lambda v, g, x: resample_spectrum(v, g, x)
    eager = fn(values, grid, new)
    np.testing.assert_allclose(jax.jit(fn)(values, grid, new), eager, rtol=1e-15)
    np.testing.assert_allclose(
        jax.vmap(fn, in_axes=(0, None, None))(values, grid, new), eager, rtol=1e-15
    )
    check_grads(fn, (values, grid, new), order=1, modes=("fwd", "rev"))


def test_resample_spectrum_bad_input_and_nan():
    grid = np.array([400.0, 500.0, 600.0])
    with pytest.raises(ValueError, match="must match"):
        resample_spectrum(np.ones(4), grid, grid)
    with pytest.raises(ValueError, match="1-D"):
        resample_spectrum(np.ones((2, 3)), np.ones((2, 3)), grid)
    with pytest.raises(eqx.EquinoxRuntimeError, match="strictly increasing"):
        resample_spectrum(np.ones(3), grid[::-1], grid)
    out = resample_spectrum(np.ones(3), grid, np.array([np.nan, 450.0]))
    assert np.isnan(float(out[0])) and float(out[1]) == 1.0


def test_resample_spectrum_gradient_at_end_samples():
    # At the end samples the one-sided (inside) slope is used, in full.
    grid = jnp.asarray([400.0, 500.0, 600.0])
    values = jnp.asarray([1.0, 2.0, 4.0])
    slope = jax.grad(lambda x: resample_spectrum(values, grid, x))
    assert float(slope(jnp.asarray(600.0))) == pytest.approx(0.02, rel=1e-14)
    assert float(slope(jnp.asarray(400.0))) == pytest.approx(0.01, rel=1e-14)
    assert float(slope(jnp.asarray(650.0))) == 0.0
