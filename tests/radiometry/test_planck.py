"""Planck's, Stefan-Boltzmann's and Wien's laws (thesis section 1.5, eq. 1.22-1.24)."""

import math
from decimal import Decimal, getcontext

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from colour.colorimetry import planck_law
from jax.test_util import check_grads

from radiometria import constants as c
from radiometria.radiometry import (
    integrate_spectrum,
    planck,
    planck_exitance,
    planck_frequency,
    planck_peak_frequency,
    planck_peak_wavelength,
    spectral_density_per_nm_to_per_hz,
    stefan_boltzmann_exitance,
    wavelength_to_frequency,
)

# The promised domain: wavelengths 1 nm to 1 mm, temperatures 1 K to 1e6 K.
DOMAIN_NM = (1.0, 1e6)
DOMAIN_K = (1.0, 1e6)


def _planck_decimal(wavelength_nm: float, temperature: float) -> float:
    """Planck's law evaluated in 50-digit decimal arithmetic: an independent closed form."""
    getcontext().prec = 50
    h, cc, k = Decimal("6.62607015e-34"), Decimal(299792458), Decimal("1.380649e-23")
    lam = Decimal(repr(wavelength_nm)) * Decimal("1e-9")
    t = Decimal(repr(temperature))
    per_m = 2 * h * cc**2 / lam**5 / ((h * cc / (lam * k * t)).exp() - 1)
    return float(per_m * Decimal("1e-9"))


@pytest.mark.parametrize(
    ("wavelength_nm", "temperature"),
    [
        (550.0, 5000.0),
        (555.0, 6504.0),
        (380.0, 2856.0),
        (780.0, 1000.0),
        (10_000.0, 300.0),
        (1.0, 1e6),
        (1e6, 1.0),
        (1e6, 1e6),
        (100.0, 50.0),  # x = 2877, deep in the Wien tail (about 1e-1224 in float64: 0)
        (2.0, 1e4),  # x = 719: exp(x) overflows float64, the radiance (4e-294) does not
    ],
)
def test_planck_reference_values(wavelength_nm, temperature):
    expected = _planck_decimal(wavelength_nm, temperature)
    got = float(planck(wavelength_nm, temperature))
    assert got == pytest.approx(expected, rel=1e-13, abs=0.0)


def test_planck_matches_colour_science():
    wavelengths_nm = np.geomspace(100.0, 1e5, 97)  # x <= 288: colour overflows beyond 709
    temperatures = np.array([500.0, 1500.0, 2856.0, 5000.0, 6504.0, 20000.0])
    # colour's planck_law takes metres, returns per metre; given the exact constants, it agrees.
    expected = planck_law(wavelengths_nm * 1e-9, temperatures, c1=c.C1, c2=c.C2) * 1e-9
    got = planck(wavelengths_nm[:, None], temperatures[None, :])
    mask = expected > 1e-290  # both underflow in the far Wien tail
    np.testing.assert_allclose(np.asarray(got)[mask], expected[mask], rtol=1e-12)


def test_planck_matches_colour_science_default_constants():
    # colour's defaults are c1 = 3.741771e-16 W m^2 (CODATA 2000, 6 digits) and
    # c2 = 1.4388e-2 m K (ITS-90). The relative difference they make is, to first order,
    # |dc1/c1| + |dc2/c2| x / (1 - e^-x) with x = c2 / (lambda T).
    wavelengths_nm = np.arange(360.0, 831.0, 5.0)
    temperatures = np.array([2000.0, 2856.0, 4000.0, 6504.0, 10000.0])
    expected = planck_law(wavelengths_nm * 1e-9, temperatures) * 1e-9
    got = np.asarray(planck(wavelengths_nm[:, None], temperatures[None, :]))
    x = c.C2 / (wavelengths_nm[:, None] * 1e-9 * temperatures[None, :])
    bound = abs(3.741771e-16 / c.C1 - 1) + abs(1.4388e-2 / c.C2 - 1) * x / -np.expm1(-x)
    rel = np.abs(got / expected - 1)
    assert np.all(rel <= 1.01 * bound + 1e-12)
    assert rel.max() > 1e-6  # the constants do differ: the bound is not vacuous


@pytest.mark.parametrize("temperature", [1000.0, 2856.0, 5778.0, 1e4, 1e5])
def test_planck_stefan_boltzmann(temperature):
    # integral of M_lambda = pi L_lambda over all wavelengths = sigma T^4 (eq. 1.22-1.24);
    # x = c2 / (lambda T) from 200 (the e^-200 Wien tail) to 1e-3 (Rayleigh-Jeans tail 3e-10).
    wavelengths_nm = np.geomspace(
        c.C2 * 1e9 / temperature / 200, c.C2 * 1e9 / temperature / 1e-3, 40_001
    )
    total = integrate_spectrum(planck_exitance(wavelengths_nm, temperature), wavelengths_nm)
    expected = stefan_boltzmann_exitance(temperature)
    assert float(total) == pytest.approx(float(expected), rel=1e-6)
    assert float(expected) == pytest.approx(c.STEFAN_BOLTZMANN * temperature**4, rel=1e-15)


def test_stefan_boltzmann_thesis_constant():
    # The thesis prints sigma = 5.67032e-8 W m^-2 K^-4 (older CODATA): agreement to 1e-5.
    assert float(stefan_boltzmann_exitance(1.0)) == pytest.approx(5.67032e-8, rel=1e-5)


def test_planck_exitance_is_pi_radiance():
    wavelengths_nm = jnp.linspace(300.0, 900.0, 7)
    np.testing.assert_allclose(
        planck_exitance(wavelengths_nm, 4000.0),
        math.pi * planck(wavelengths_nm, 4000.0),
        rtol=1e-15,
    )


@pytest.mark.parametrize("temperature", [300.0, 2856.0, 5778.0, 1e5])
def test_planck_wien_peak_argmax(temperature):
    peak = float(planck_peak_wavelength(temperature))
    assert peak == pytest.approx(c.WIEN_DISPLACEMENT * 1e9 / temperature, rel=1e-15)
    grid = np.linspace(0.9 * peak, 1.1 * peak, 200_001)  # spacing 1e-6 of the peak
    argmax = grid[int(np.argmax(np.asarray(planck(grid, temperature))))]
    assert argmax == pytest.approx(peak, rel=2e-6)


@pytest.mark.parametrize("temperature", [300.0, 2856.0, 5778.0, 1e5])
def test_planck_wien_peak_gradient_zero(temperature):
    peak = planck_peak_wavelength(temperature)
    slope = jax.grad(planck)(peak, temperature)
    # Relative slope dlnL/dln(lambda) vanishes at the peak (it is 5 - x/(1 - e^-x) = 0).
    assert abs(float(slope * peak / planck(peak, temperature))) < 1e-12
    # ... and it changes sign: rising before, falling after.
    assert float(jax.grad(planck)(0.99 * peak, temperature)) > 0
    assert float(jax.grad(planck)(1.01 * peak, temperature)) < 0


@pytest.mark.parametrize("temperature", [300.0, 5778.0])
def test_planck_frequency_peak(temperature):
    peak = planck_peak_frequency(temperature)
    assert float(peak) == pytest.approx(5.878925757646825e10 * temperature, rel=1e-14)
    slope = jax.grad(planck_frequency)(peak, temperature)
    assert abs(float(slope * peak / planck_frequency(peak, temperature))) < 1e-12
    # The per-frequency peak is NOT at c / lambda_max (about 1.76 lambda_max).
    ratio = float(wavelength_to_frequency(planck_peak_wavelength(temperature)) / peak)
    assert ratio == pytest.approx(c.WIEN_X / 2.821439372122079, rel=1e-14)  # x_5 / x_3 = 1.7598


def test_planck_frequency_matches_per_wavelength():
    wavelengths_nm = np.geomspace(1.0, 1e6, 61)
    temperatures = np.array([1.0, 300.0, 5778.0, 1e6])
    per_hz = planck_frequency(
        wavelength_to_frequency(wavelengths_nm)[:, None], temperatures[None, :]
    )
    converted = spectral_density_per_nm_to_per_hz(
        planck(wavelengths_nm[:, None], temperatures[None, :]), wavelengths_nm[:, None]
    )
    mask = np.asarray(converted) > 1e-280
    np.testing.assert_allclose(np.asarray(per_hz)[mask], np.asarray(converted)[mask], rtol=1e-10)


def test_planck_frequency_reference_value():
    # L_nu = 2 h nu^3 / c^2 / expm1(h nu / k T), written directly in float64.
    nu, t = 5.4e14, 5000.0
    expected = (
        2 * c.PLANCK * nu**3 / c.SPEED_OF_LIGHT**2 / math.expm1(c.PLANCK * nu / (c.BOLTZMANN * t))
    )
    assert float(planck_frequency(nu, t)) == pytest.approx(expected, rel=1e-14)


# --- Stability over the whole domain, in float32 and float64 -----------------------------------


def _domain_grid(dtype, n=241):
    wavelengths_nm = np.geomspace(*DOMAIN_NM, n)
    temperatures = np.geomspace(*DOMAIN_K, n)
    w, t = np.meshgrid(wavelengths_nm, temperatures)
    return jnp.asarray(w.ravel(), dtype), jnp.asarray(t.ravel(), dtype)


@pytest.mark.parametrize("dtype", [jnp.float32, jnp.float64])
def test_planck_stable_over_domain(dtype):
    w, t = _domain_grid(dtype)
    radiance = planck(w, t)
    assert radiance.dtype == dtype
    assert bool(jnp.all(jnp.isfinite(radiance))) and bool(jnp.all(radiance >= 0))
    assert float(jnp.max(radiance)) > 1e15  # the 1 nm / 1e6 K corner is large and finite
    grads = jax.vmap(jax.grad(planck, argnums=(0, 1)))(w, t)
    for g in grads:
        assert g.dtype == dtype
        assert bool(jnp.all(jnp.isfinite(g)))
    # Accuracy against float64 on the same (rounded) inputs: the condition number of L in x is
    # about max(1, x), so the float32 error is a few ulp times that.
    w64, t64 = np.asarray(w, np.float64), np.asarray(t, np.float64)
    reference = np.asarray(planck(w64, t64))
    x = c.C2 * 1e9 / (w64 * t64)
    tiny = np.finfo(np.dtype(dtype)).tiny
    ok = reference > tiny * 1e6  # compare where float32/64 is not in its subnormal range
    eps = np.finfo(np.dtype(dtype)).eps
    rel = np.abs(np.asarray(radiance, np.float64)[ok] / reference[ok] - 1)
    assert np.all(rel <= 8 * eps * np.maximum(1.0, x[ok]))


@pytest.mark.parametrize("dtype", [jnp.float32, jnp.float64])
def test_planck_frequency_stable_over_domain(dtype):
    w, t = _domain_grid(dtype)
    nu = jnp.asarray(wavelength_to_frequency(np.asarray(w, np.float64)), dtype)
    radiance = planck_frequency(nu, t)
    assert radiance.dtype == dtype
    assert bool(jnp.all(jnp.isfinite(radiance))) and bool(jnp.all(radiance >= 0))
    for g in jax.vmap(jax.grad(planck_frequency, argnums=(0, 1)))(nu, t):
        assert bool(jnp.all(jnp.isfinite(g)))


@pytest.mark.parametrize("dtype", [jnp.float32, jnp.float64])
def test_planck_underflows_to_zero(dtype):
    # x = 1.4e7: exp(x) overflows, the radiance underflows; the answer is exactly 0, gradient 0.
    w, t = jnp.asarray(1.0, dtype), jnp.asarray(1.0, dtype)
    assert float(planck(w, t)) == 0.0
    assert [float(g) for g in jax.grad(planck, argnums=(0, 1))(w, t)] == [0.0, 0.0]


@pytest.mark.parametrize("dtype", [jnp.float32, jnp.float64])
def test_planck_near_branch_switch_continuous(dtype):
    # x_s (37 in float64, 18 in float32) is where the direct and the Wien forms meet: no jump.
    from radiometria.radiometry._planck import _X_SWITCH_F32, _X_SWITCH_F64

    switch = _X_SWITCH_F64 if dtype == jnp.float64 else _X_SWITCH_F32
    t = jnp.asarray(5000.0, dtype)
    x = jnp.asarray([switch - 0.001, switch, switch + 0.001], dtype)
    w = jnp.asarray(c.C2 * 1e9 / 5000.0, dtype) / x
    ref = np.array([_planck_decimal(float(wi), 5000.0) for wi in np.asarray(w, np.float64)])
    np.testing.assert_allclose(
        np.asarray(planck(w, t), np.float64), ref, rtol=200 * float(jnp.finfo(dtype).eps)
    )


@pytest.mark.parametrize("x", [19.5, 36.5, 37.0, 37.5, 80.0, 800.0])
def test_planck_kernel_gradient_at_branch_switch(x):
    # d/dx [1 / expm1(x)] = -e^x / expm1(x)^2, exactly also at the float64 switch x = 37.
    from radiometria.radiometry._planck import _prefactor_over_expm1

    fn = lambda x: _prefactor_over_expm1(jnp.asarray(1.0), jnp.asarray(0.0), x)
    expected = -math.exp(-x) / (-math.expm1(-x)) ** 2  # the same, written without overflow
    assert float(jax.grad(fn)(jnp.asarray(x))) == pytest.approx(expected, rel=1e-13)
    assert float(fn(jnp.asarray(x))) == pytest.approx(math.exp(-x) / -math.expm1(-x), rel=1e-14)


# --- Transformations ----------------------------------------------------------------------------


def test_planck_jit_matches_eager():
    w, t = _domain_grid(jnp.float64, n=31)
    np.testing.assert_array_equal(jax.jit(planck)(w, t), planck(w, t))
    np.testing.assert_array_equal(
        jax.jit(planck_frequency)(w * 1e9, t), planck_frequency(w * 1e9, t)
    )


def test_planck_vmap_matches_loop():
    w = jnp.linspace(300.0, 900.0, 5)
    t = jnp.linspace(1000.0, 9000.0, 5)
    looped = jnp.stack([planck(wi, ti) for wi, ti in zip(w, t, strict=True)])
    np.testing.assert_allclose(jax.vmap(planck)(w, t), looped, rtol=1e-15)


def test_planck_batch_shapes():
    w = jnp.linspace(300.0, 900.0, 4)
    t = jnp.linspace(1000.0, 3000.0, 3)[:, None]
    assert planck(w, t).shape == (3, 4)
    assert planck(550.0, t).shape == (3, 1)
    assert planck(w.reshape(2, 2, 1), 5000.0).shape == (2, 2, 1)
    assert planck_frequency(jnp.ones((2, 3)) * 5e14, 5000.0).shape == (2, 3)
    assert planck_peak_wavelength(t).shape == (3, 1)


@pytest.mark.parametrize(
    ("wavelength_nm", "temperature"), [(550.0, 5000.0), (10.0, 300.0), (1e5, 3.0), (2.0, 1e4)]
)
def test_planck_grad(wavelength_nm, temperature):
    check_grads(planck, (wavelength_nm, temperature), order=2, modes=("fwd", "rev"), rtol=1e-5)


def test_planck_frequency_grad():
    check_grads(planck_frequency, (5.4e14, 5000.0), order=2, modes=("fwd", "rev"), rtol=1e-5)


def test_planck_python_floats_are_weakly_typed():
    # Python floats follow the dtype of the array arguments (no promotion to float64).
    assert planck(jnp.asarray([550.0], jnp.float32), 5000.0).dtype == jnp.float32
    assert planck(550.0, jnp.asarray([5000.0], jnp.float32)).dtype == jnp.float32


# --- Bad input ----------------------------------------------------------------------------------


@pytest.mark.parametrize("fn", [planck, planck_frequency, planck_exitance])
@pytest.mark.parametrize(
    ("first", "temperature", "match"),
    [
        (0.0, 5000.0, "nm|Hz"),
        (-1.0, 5000.0, "nm|Hz"),
        (550.0, 0.0, "temperature"),
        (550.0, -3.0, "temperature"),
    ],
)
def test_planck_rejects_non_positive_under_jit(fn, first, temperature, match):
    args = (jnp.asarray([500.0, first]), jnp.asarray(temperature))
    with pytest.raises(eqx.EquinoxRuntimeError, match=match):
        eqx.filter_jit(fn)(*args)
    with pytest.raises(eqx.EquinoxRuntimeError, match=match):
        fn(*args)
    # Under a bare jax.jit equinox cannot re-raise its own type; the message still arrives.
    with pytest.raises(jax.errors.JaxRuntimeError, match=match):
        jax.jit(fn)(*args)


@pytest.mark.parametrize(
    "fn", [stefan_boltzmann_exitance, planck_peak_wavelength, planck_peak_frequency]
)
def test_temperature_functions_reject_non_positive(fn):
    with pytest.raises(eqx.EquinoxRuntimeError, match="temperature"):
        eqx.filter_jit(fn)(jnp.asarray([300.0, 0.0]))
    with pytest.raises(eqx.EquinoxRuntimeError, match="temperature"):
        fn(-1.0)


def test_planck_rejects_integer_arrays():
    with pytest.raises(TypeError, match="wavelength_nm"):
        planck(np.array([500, 600]), 5000.0)
    with pytest.raises(TypeError, match="temperature"):
        planck(550.0, jnp.array([5000, 6000]))
    with pytest.raises(TypeError, match="temperature"):
        stefan_boltzmann_exitance(np.arange(3))


def test_planck_nan_propagates():
    # NaN is not an out-of-domain error (NaN <= 0 is false): it propagates, documented.
    out = planck(jnp.asarray([jnp.nan, 550.0]), jnp.asarray([5000.0, jnp.nan]))
    assert bool(jnp.all(jnp.isnan(out)))
    assert bool(jnp.isnan(planck_frequency(jnp.nan, 5000.0)))
    assert bool(jnp.isnan(planck_peak_wavelength(jnp.nan)))
