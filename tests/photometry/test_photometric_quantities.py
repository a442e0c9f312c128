"""Photometric quantities (thesis eq. 2.1-2.5) against colour-science and physical facts."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from colour import SDS_LIGHT_SOURCES, SpectralDistribution, luminous_efficiency, luminous_flux
from colour.colorimetry import SDS_LEFS_SCOTOPIC

from radiometria import constants as c, photometry as ph
from radiometria.radiometry import planck

V_SCOTOPIC = SDS_LEFS_SCOTOPIC["CIE 1951 Scotopic Standard Observer"]
NAMED = [
    ph.luminous_energy,
    ph.luminous_flux,
    ph.illuminance,
    ph.luminous_exitance,
    ph.luminous_intensity,
    ph.luminance,
]


def _sources():
    # Measured sources on 5 nm grids (all on whole nanometres, so V is not interpolated), and a
    # blackbody on a 1 nm grid wider than V's table.
    yield "Neodimium Incandescent", SDS_LIGHT_SOURCES["Neodimium Incandescent"]
    yield "F32T8/TL841 (Triphosphor)", SDS_LIGHT_SOURCES["F32T8/TL841 (Triphosphor)"]
    wl = np.arange(300.0, 901.0)
    yield "blackbody 3000 K", SpectralDistribution(np.asarray(planck(wl, 3000.0)), wl)


@pytest.mark.parametrize(
    ("name", "sd"), list(_sources()), ids=lambda x: x if isinstance(x, str) else ""
)
def test_luminous_flux_matches_colour_science(name, sd):
    photopic = ph.luminous_flux(sd.values, sd.wavelengths)
    assert float(photopic) == pytest.approx(luminous_flux(sd, K_m=c.K_M), rel=1e-12)
    scotopic = ph.luminous_flux(sd.values, sd.wavelengths, vision="scotopic")
    assert float(scotopic) == pytest.approx(
        luminous_flux(sd, V_SCOTOPIC, K_m=c.K_M_SCOTOPIC), rel=1e-12
    )


@pytest.mark.parametrize(
    ("name", "sd"), list(_sources()), ids=lambda x: x if isinstance(x, str) else ""
)
def test_luminous_efficacy_matches_colour_science(name, sd):
    efficiency = ph.luminous_efficiency(sd.values, sd.wavelengths)
    assert float(efficiency) == pytest.approx(luminous_efficiency(sd), rel=1e-12)
    # colour's luminous_efficacy multiplies by its K_m = 683 lm/W; ours by K_M = 683.002.
    efficacy = ph.luminous_efficacy(sd.values, sd.wavelengths)
    assert float(efficacy) == pytest.approx(c.K_M * luminous_efficiency(sd), rel=1e-12)
    scotopic = ph.luminous_efficiency(sd.values, sd.wavelengths, vision="scotopic")
    assert float(scotopic) == pytest.approx(luminous_efficiency(sd, V_SCOTOPIC), rel=1e-12)


@pytest.mark.parametrize(
    ("vision", "peak", "efficacy"),
    [("photopic", 555.0, c.K_M), ("scotopic", 507.0, c.K_M_SCOTOPIC)],
)
def test_luminous_flux_of_one_watt_at_the_peak(vision, peak, efficacy):
    # A triangle of 1 W (area 1) on [peak - 1, peak + 1] nm: the trapezoid sees V(peak) = 1.
    wl = np.array([peak - 1.0, peak, peak + 1.0])
    assert float(ph.luminous_flux(np.array([0.0, 1.0, 0.0]), wl, vision=vision)) == pytest.approx(
        efficacy, rel=1e-15
    )
    assert float(
        ph.luminous_efficacy(np.array([0.0, 1.0, 0.0]), wl, vision=vision)
    ) == pytest.approx(efficacy, rel=1e-15)


def test_luminous_efficacy_of_blackbodies():
    # Counting all radiation (1 nm to 1 mm): numerator checked against colour-science on a
    # 1 nm grid over V's support, denominator against Stefan-Boltzmann (sigma T^4 / pi).
    wl = np.geomspace(1.0, 1e6, 200_001)
    temperatures = np.array([2856.0, 4000.0, 5000.0, 6600.0, 7000.0, 10000.0])
    efficacy = np.asarray(ph.luminous_efficacy(planck(wl, temperatures[:, None]), wl))
    wl_1nm = np.arange(360.0, 831.0)
    for t, k in zip(temperatures, efficacy, strict=True):
        luminance = luminous_flux(
            SpectralDistribution(np.asarray(planck(wl_1nm, t)), wl_1nm), K_m=c.K_M
        )
        assert k == pytest.approx(luminance / (c.STEFAN_BOLTZMANN * t**4 / np.pi), rel=1e-4)
    # Textbook values: 54.7 lm/W at 4000 K; the maximum, about 95 lm/W, near 6600-7000 K.
    assert efficacy[1] == pytest.approx(54.7, abs=0.05)
    assert efficacy[3] == pytest.approx(95.4, abs=0.05)
    assert efficacy[3] > max(efficacy[2], efficacy[4], efficacy[5])


def test_named_quantities_are_luminous_quantity():
    sd = SDS_LIGHT_SOURCES["Neodimium Incandescent"]
    expected = ph.luminous_quantity(sd.values, sd.wavelengths)
    for fn in NAMED:
        assert float(fn(sd.values, sd.wavelengths)) == float(expected), fn.__name__
        assert fn.__name__ in repr(fn) and "[" in fn.__doc__ and "Thesis eq. (2." in fn.__doc__


def test_luminance_batch_axis_and_per_spectrum_grids():
    sd = SDS_LIGHT_SOURCES["Neodimium Incandescent"]
    values = np.stack([sd.values, 2.0 * sd.values, 0.5 * sd.values])
    single = float(ph.luminance(sd.values, sd.wavelengths))
    np.testing.assert_allclose(
        ph.luminance(values, sd.wavelengths), [single, 2 * single, 0.5 * single], rtol=1e-14
    )
    np.testing.assert_allclose(
        ph.luminance(values.T, sd.wavelengths, axis=0),
        [single, 2 * single, 0.5 * single],
        rtol=1e-14,
    )
    grids = np.broadcast_to(sd.wavelengths, values.shape)
    np.testing.assert_allclose(
        ph.luminance(values, grids), [single, 2 * single, 0.5 * single], rtol=1e-14
    )


def test_luminance_jit_vmap_grad():
    wl = jnp.linspace(380.0, 780.0, 81)
    values = planck(wl, jnp.asarray([3000.0, 5000.0])[:, None])
    eager = ph.luminance(values, wl)
    np.testing.assert_allclose(jax.jit(ph.luminance)(values, wl), eager, rtol=1e-14)
    np.testing.assert_allclose(
        jax.vmap(ph.luminance, in_axes=(0, None))(values, wl), eager, rtol=1e-14
    )
    # d luminance / d T of a blackbody: finite and positive; linear in the spectrum.
    dl_dt = jax.grad(lambda t: ph.luminance(planck(wl, t), wl))(4000.0)
    assert np.isfinite(float(dl_dt)) and float(dl_dt) > 0
    grad_values = jax.grad(lambda v: ph.luminance(v, wl))(values[0])
    step = np.diff(np.asarray(wl))
    weights = np.zeros(81)
    weights[:-1] += step / 2
    weights[1:] += step / 2
    v = np.asarray(ph.luminous_efficiency_function(wl))
    np.testing.assert_allclose(grad_values, c.K_M * v * weights, rtol=1e-12, atol=1e-300)


def test_luminance_float32():
    wl = jnp.linspace(380.0, 780.0, 81, dtype=jnp.float32)
    values = planck(wl, 5000.0)
    out = ph.luminance(values, wl)
    assert out.dtype == jnp.float32
    assert float(out) == pytest.approx(
        float(ph.luminance(np.asarray(values, np.float64), np.asarray(wl, np.float64))), rel=1e-5
    )


def test_photometric_quantities_reject_bad_input():
    wl = np.linspace(400.0, 700.0, 4)
    with pytest.raises(ValueError, match="vision"):
        ph.luminous_flux(np.ones(4), wl, vision="mesopic")
    with pytest.raises(ValueError, match="must match"):
        ph.luminance(np.ones(5), wl)
    with pytest.raises(TypeError, match="spectral_values"):
        ph.illuminance(np.arange(4), wl)
    with pytest.raises(eqx.EquinoxRuntimeError, match="strictly increasing"):
        ph.luminance(np.ones(4), wl[::-1])
    with pytest.raises(eqx.EquinoxRuntimeError, match="undefined"):
        ph.luminous_efficacy(np.zeros(4), wl)


def test_photometric_quantities_nan_propagates():
    wl = np.linspace(400.0, 700.0, 4)
    assert np.isnan(float(ph.luminance(np.array([1.0, np.nan, 1.0, 1.0]), wl)))
