"""The spectrum hierarchy: constant, piecewise-linear and blackbody spectra, and its members."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads
from scipy import integrate

import radiometria as rm
from radiometria import constants as c
from radiometria.radiometry import (
    AbstractSpectrum,
    BlackbodySpectrum,
    ConstantSpectrum,
    PiecewiseLinearSpectrum,
    integrate_spectrum,
    planck,
)

GRID = np.arange(360.0, 831.0, 1.0)  # nm, the renderer's 1 nm grid


def _table(seed=0, n=40, batch=()):
    """A random tabulated spectrum on an irregular grid inside 380-780 nm."""
    rng = np.random.default_rng(seed)
    wl = np.sort(rng.uniform(380.0, 780.0, n))
    return wl, rng.uniform(0.0, 1.0, batch + (n,))


# --- The hierarchy -----------------------------------------------------------------------


def test_abstract_spectrum_is_abstract():
    with pytest.raises(TypeError):
        AbstractSpectrum()


def test_abstract_spectrum_members():
    lut = rm.upsampling.get_lut("sRGB")
    rgb = jnp.array([0.2, 0.5, 0.8])
    members = [
        ConstantSpectrum(0.5),
        PiecewiseLinearSpectrum(*_table()),
        BlackbodySpectrum(5000.0),
        rm.upsampling.SigmoidPolynomialSpectrum(jnp.array([1e-4, -0.1, 20.0])),
        rm.upsampling.RGBAlbedoSpectrum(lut, rgb),
        rm.upsampling.RGBUnboundedSpectrum(lut, rgb),
        rm.upsampling.RGBIlluminantSpectrum(lut, rgb),
        rm.colorimetry.get_illuminant("D65"),
        rm.colorimetry.get_cmfs(),
    ]
    for spectrum in members:
        assert isinstance(spectrum, AbstractSpectrum), type(spectrum).__name__
        assert spectrum(550.0).dtype == jnp.float64
    # One public path: upsampling no longer has its own interface.
    assert not hasattr(rm.upsampling, "AbstractSpectrum")


def test_abstract_spectrum_batching_rule_shared():
    """Every batched member follows broadcast((*batch, 1), wavelength shape)."""
    lut = rm.upsampling.get_lut("sRGB")
    rgb = jnp.array([[0.2, 0.5, 0.8], [0.9, 0.1, 0.1]])
    wl, v = _table(batch=(2,))
    batched = [
        ConstantSpectrum(jnp.array([0.1, 0.2])),
        PiecewiseLinearSpectrum(wl, v),
        BlackbodySpectrum(jnp.array([3000.0, 6500.0])),
        rm.upsampling.RGBAlbedoSpectrum(lut, rgb),
        rm.upsampling.RGBIlluminantSpectrum(lut, rgb),
    ]
    for spectrum in batched:
        assert spectrum(550.0).shape == (2,)
        assert spectrum(jnp.asarray(GRID)).shape == (2, GRID.size)
        assert spectrum(jnp.ones((2, 4)) * 550.0).shape == (2, 4)
        assert spectrum(jnp.ones((3, 1, 4)) * 550.0).shape == (3, 2, 4)


# --- ConstantSpectrum --------------------------------------------------------------------


def test_constant_spectrum_values_and_shapes():
    s = ConstantSpectrum(0.25)
    assert s(550.0).shape == ()
    np.testing.assert_array_equal(s(jnp.asarray(GRID)), np.full(GRID.shape, 0.25))
    b = ConstantSpectrum(jnp.array([0.1, 0.2, 0.3]))
    np.testing.assert_array_equal(b(jnp.asarray(GRID)), np.repeat([[0.1], [0.2], [0.3]], 471, 1))
    np.testing.assert_array_equal(b(500.0), [0.1, 0.2, 0.3])


def test_constant_spectrum_dtype_follows_inputs():
    assert ConstantSpectrum(0.5)(jnp.ones(3, jnp.float32)).dtype == jnp.float32
    assert ConstantSpectrum(jnp.float32(0.5))(jnp.ones(3)).dtype == jnp.float64


def test_constant_spectrum_grad():
    n = GRID.size
    g = jax.grad(lambda v: ConstantSpectrum(v)(jnp.asarray(GRID)).sum())(0.3)
    assert g == n
    check_grads(lambda v: ConstantSpectrum(v)(jnp.asarray(GRID)), (jnp.array([0.2, 0.4]),), 2)


def test_constant_spectrum_rejects_bad_input():
    with pytest.raises(TypeError, match="value"):
        ConstantSpectrum(np.array([1, 2]))
    with pytest.raises(ValueError, match="wavelength_nm"):
        ConstantSpectrum(jnp.ones(3))(jnp.ones((2, 4)))


# --- PiecewiseLinearSpectrum --------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_piecewise_linear_spectrum_matches_np_interp_exactly(seed):
    """Bit-identical to the renderer's `np.interp(grid, wl, v, left=0.0, right=0.0)`."""
    wl, v = _table(seed)
    rng = np.random.default_rng(seed + 10)
    x = np.concatenate([GRID, wl, rng.uniform(300.0, 850.0, 5000), [wl[0], wl[-1]]])
    expected = np.interp(x, wl, v, left=0.0, right=0.0)
    got = np.asarray(PiecewiseLinearSpectrum(wl, v)(jnp.asarray(x)))
    np.testing.assert_array_equal(got, expected)
    assert got[-2] == v[0] and got[-1] == v[-1]


def test_piecewise_linear_spectrum_cornell_box_data():
    """The measured Cornell box light (Cornell Program of Computer Graphics data, as in the
    renderer's `cornell_box_measured.json`): linear in 400-700 nm, zero outside."""
    wl = np.array([400.0, 500.0, 600.0, 700.0])
    v = np.array([0.0, 8.0, 15.6, 18.4])
    expected = np.interp(GRID, wl, v, left=0.0, right=0.0)
    np.testing.assert_array_equal(PiecewiseLinearSpectrum(wl, v)(jnp.asarray(GRID)), expected)


def test_piecewise_linear_spectrum_zero_outside():
    wl, v = _table()
    s = PiecewiseLinearSpectrum(wl, v + 1.0)
    outside = jnp.array([1.0, wl[0] - 1e-9, wl[-1] + 1e-9, 2000.0])
    np.testing.assert_array_equal(s(outside), np.zeros(4))


def test_piecewise_linear_spectrum_batch_matches_loop():
    wl, v = _table(batch=(3, 2))
    s = PiecewiseLinearSpectrum(wl, v)
    out = s(jnp.asarray(GRID))
    assert out.shape == (3, 2, GRID.size)
    for i in range(3):
        for k in range(2):
            np.testing.assert_array_equal(out[i, k], np.interp(GRID, wl, v[i, k], 0.0, 0.0))
    # Each spectrum at its own wavelengths, and a scalar wavelength.
    x = np.random.default_rng(3).uniform(370.0, 790.0, (3, 2, 7))
    got = s(jnp.asarray(x))
    for i in range(3):
        for k in range(2):
            np.testing.assert_array_equal(got[i, k], np.interp(x[i, k], wl, v[i, k], 0.0, 0.0))
    np.testing.assert_array_equal(s(550.0), np.asarray(s(jnp.array([550.0])))[..., 0])


def test_piecewise_linear_spectrum_jit_matches_eager():
    """Under jit XLA may fuse the multiply-add into an FMA: equal to within one rounding."""
    wl, v = _table(batch=(2,))
    s = PiecewiseLinearSpectrum(wl, v)
    eager = s(jnp.asarray(GRID))
    jitted = jax.jit(lambda sp, x: sp(x))(s, jnp.asarray(GRID))
    np.testing.assert_allclose(jitted, eager, rtol=0.0, atol=4 * np.finfo(float).eps)


def test_piecewise_linear_spectrum_vmap_matches_batch():
    wl, v = _table(batch=(4,))
    batched = PiecewiseLinearSpectrum(wl, v)(jnp.asarray(GRID))
    mapped = jax.vmap(lambda row: PiecewiseLinearSpectrum(wl, row)(jnp.asarray(GRID)))(v)
    np.testing.assert_allclose(mapped, batched, rtol=0.0, atol=4 * np.finfo(float).eps)


def test_piecewise_linear_spectrum_grad():
    wl, v = _table()
    s = PiecewiseLinearSpectrum(wl, v)
    # d S / d lambda is the slope of the segment (away from the knots).
    x = jnp.asarray(0.5 * (wl[:-1] + wl[1:]))
    dsdx = jax.vmap(jax.grad(s))(x)
    np.testing.assert_allclose(dsdx, np.diff(v) / np.diff(wl), rtol=1e-12)
    check_grads(lambda vals: PiecewiseLinearSpectrum(wl, vals)(x), (jnp.asarray(v),), 2)
    check_grads(lambda grid: PiecewiseLinearSpectrum(grid, v)(x), (jnp.asarray(wl),), 1)


@pytest.mark.parametrize("dtype", [jnp.float32, jnp.float64])
def test_piecewise_linear_spectrum_dtypes(dtype):
    wl, v = _table()
    s = PiecewiseLinearSpectrum(jnp.asarray(wl, dtype), jnp.asarray(v, dtype))
    out = s(jnp.asarray(GRID, dtype))
    assert out.dtype == dtype
    # Reference: np.interp in float64 on the same (rounded) table.
    wl, v = np.asarray(s.wavelengths_nm, np.float64), np.asarray(s.values, np.float64)
    rtol = 1e-5 if dtype == jnp.float32 else 1e-14
    np.testing.assert_allclose(out, np.interp(GRID, wl, v, 0.0, 0.0), rtol=rtol, atol=rtol)
    # A float32 table at float64 wavelengths is evaluated in float64.
    assert s(jnp.asarray(GRID)).dtype == jnp.float64


def test_piecewise_linear_spectrum_rejects_bad_grid():
    with pytest.raises(ValueError, match="wavelengths_nm"):
        PiecewiseLinearSpectrum(np.array([400.0, 500.0, 500.0]), np.ones(3))
    with pytest.raises(ValueError, match="wavelengths_nm"):
        PiecewiseLinearSpectrum(np.array([400.0, np.nan, 600.0]), np.ones(3))
    with pytest.raises(ValueError, match="wavelengths_nm"):
        PiecewiseLinearSpectrum(np.array([500.0]), np.ones(1))
    with pytest.raises(ValueError, match="wavelengths_nm"):
        PiecewiseLinearSpectrum(np.ones((2, 3)), np.ones(3))
    with pytest.raises(ValueError, match="values"):
        PiecewiseLinearSpectrum(np.array([400.0, 500.0, 600.0]), np.ones((3, 2)))
    with pytest.raises(TypeError, match="wavelengths_nm"):
        PiecewiseLinearSpectrum(np.array([400, 500]), np.ones(2))
    with pytest.raises(TypeError, match="wavelength_nm"):
        PiecewiseLinearSpectrum(np.array([400.0, 500.0]), np.ones(2))(np.array([450, 460]))


def test_piecewise_linear_spectrum_rejects_bad_grid_under_jit():
    @eqx.filter_jit
    def evaluate(wl):
        return PiecewiseLinearSpectrum(wl, jnp.ones(3))(jnp.asarray(GRID))

    assert evaluate(jnp.array([400.0, 500.0, 600.0])).shape == GRID.shape
    with pytest.raises(eqx.EquinoxRuntimeError, match="wavelengths_nm"):
        evaluate(jnp.array([400.0, 600.0, 500.0]))


# --- BlackbodySpectrum -------------------------------------------------------------------


def test_blackbody_spectrum_equals_planck():
    np.testing.assert_array_equal(
        BlackbodySpectrum(5000.0)(jnp.asarray(GRID)), planck(GRID, 5000.0)
    )
    assert BlackbodySpectrum(2856.0)(555.0) == planck(555.0, 2856.0)
    t = jnp.array([1000.0, 3000.0, 6504.0])
    out = BlackbodySpectrum(t)(jnp.asarray(GRID))
    for i in range(3):
        np.testing.assert_array_equal(out[i], planck(GRID, t[i]))
    np.testing.assert_array_equal(BlackbodySpectrum(t)(550.0), planck(550.0, t))


def test_blackbody_spectrum_scale():
    t, s = jnp.array([3000.0, 6000.0]), jnp.array([0.5, 2.0])
    out = BlackbodySpectrum(t, s)(jnp.asarray(GRID))
    np.testing.assert_array_equal(out, s[:, None] * planck(GRID, t[:, None]))
    # A scalar temperature and a batch of scales.
    out = BlackbodySpectrum(4000.0, s)(jnp.asarray(GRID))
    assert out.shape == (2, GRID.size)
    np.testing.assert_array_equal(out[1], 2.0 * planck(GRID, 4000.0))


@pytest.mark.parametrize("temperature", [300.0, 2856.0, 6504.0, 20000.0])
def test_blackbody_spectrum_stefan_boltzmann(temperature):
    """integral of L_lambda over all wavelengths = sigma T^4 / pi (thesis eq. 1.22, 1.24)."""
    s = BlackbodySpectrum(temperature)
    expected = c.STEFAN_BOLTZMANN * temperature**4 / math.pi
    peak = c.WIEN_DISPLACEMENT * c.NM_PER_M / temperature  # nm
    # SciPy's adaptive quadrature, split at the peak, out to infinity.
    f = lambda lam: float(s(lam))  # noqa: E731
    lo, _ = integrate.quad(f, 1e-3 * peak, peak, epsrel=1e-12, limit=200)
    hi, _ = integrate.quad(f, peak, np.inf, epsrel=1e-12, limit=200)
    assert lo + hi == pytest.approx(expected, rel=1e-9)
    # And the trapezoid rule on a wide, fine log grid.
    grid = jnp.geomspace(0.05 * peak, 2000.0 * peak, 200_001)
    assert float(integrate_spectrum(s(grid), grid)) == pytest.approx(expected, rel=1e-6)


def test_blackbody_spectrum_grad_temperature():
    grid = jnp.geomspace(50.0, 1e6, 100_001)

    def radiance(t):
        return integrate_spectrum(BlackbodySpectrum(t)(grid), grid)

    t = 3000.0
    g = jax.grad(radiance)(t)
    h = 1e-3 * t
    fd = (radiance(t + h) - radiance(t - h)) / (2 * h)
    assert float(g) == pytest.approx(float(fd), rel=1e-6)
    # d/dT (sigma T^4 / pi) = 4 sigma T^3 / pi
    assert float(g) == pytest.approx(4 * c.STEFAN_BOLTZMANN * t**3 / math.pi, rel=1e-5)
    check_grads(
        lambda t, s: BlackbodySpectrum(t, s)(jnp.asarray(GRID[::50])),
        (jnp.array([3000.0, 5000.0]), jnp.array([1.0, 0.5])),
        1,
        rtol=1e-6,
    )


def test_blackbody_spectrum_jit_vmap():
    t = jnp.array([2000.0, 4000.0, 8000.0])
    batched = BlackbodySpectrum(t)(jnp.asarray(GRID))
    jitted = jax.jit(lambda sp: sp(jnp.asarray(GRID)))(BlackbodySpectrum(t))
    mapped = jax.vmap(lambda ti: BlackbodySpectrum(ti)(jnp.asarray(GRID)))(t)
    np.testing.assert_allclose(jitted, batched, rtol=1e-14)
    np.testing.assert_allclose(mapped, batched, rtol=1e-14)
    # vmap over a batched spectrum object (a pytree).
    mapped = jax.vmap(lambda sp: sp(jnp.asarray(GRID)))(BlackbodySpectrum(t, jnp.ones(3)))
    np.testing.assert_allclose(mapped, batched, rtol=1e-14)


def test_blackbody_spectrum_rejects_bad_input():
    with pytest.raises(ValueError, match="temperature"):
        BlackbodySpectrum(0.0)
    with pytest.raises(ValueError, match="temperature"):
        BlackbodySpectrum(jnp.array([3000.0, -1.0]))
    with pytest.raises(ValueError, match="scale"):
        BlackbodySpectrum(jnp.ones(3) * 3000.0, jnp.ones(2))
    with pytest.raises(TypeError, match="temperature"):
        BlackbodySpectrum(np.array([3000, 4000]))
    with pytest.raises(eqx.EquinoxRuntimeError, match="temperature"):
        eqx.filter_jit(lambda t: BlackbodySpectrum(t)(550.0))(jnp.array(-5.0))
    with pytest.raises(eqx.EquinoxRuntimeError, match="wavelength_nm"):
        BlackbodySpectrum(3000.0)(jnp.array([-1.0, 500.0]))
