"""`fit_lut`: argument errors, a small converged table, wide-gamut out-of-reach entries."""

import jax
import numpy as np
import pytest

import radiometria.upsampling as up


def test_fit_lut_rejects_bad_arguments():
    with pytest.raises(ValueError, match="resolution"):
        up.fit_lut("sRGB", 1)
    with pytest.raises(TypeError, match="resolution"):
        up.fit_lut("sRGB", 8.5)
    with pytest.raises(ValueError, match="colourspace"):
        up.fit_lut("not a space", 8)


@pytest.mark.slow
def test_fit_lut_small_table():
    """A res-10 sRGB table: every entry converges, nodes are exact fits, and the sharded code
    path (one device here) gives the same table."""
    fit = up.fit_lut("sRGB", 10)
    s = fit.summary()
    assert s["not_converged"] == 0 and s["out_of_reach"] == 0 and s["residual_max"] <= 5e-3
    assert np.asarray(fit.converged).all()
    sharded = up.fit_lut("sRGB", 10, devices=jax.devices()[:1])
    np.testing.assert_allclose(
        np.asarray(sharded.lut.coeffs), np.asarray(fit.lut.coeffs), rtol=1e-4, atol=1e-6
    )
    # Node colours round-trip (to the fit tolerance; float32 table, float64 evaluation).
    lut = fit.lut
    scale = np.asarray(lut.scale, np.float64)
    k, j, i = 6, 3, 8
    rgb = scale[k] * np.array([[1.0, i / 9, j / 9], [j / 9, 1.0, i / 9], [i / 9, j / 9, 1.0]])
    de, _ = up.roundtrip_delta_E(lut, rgb)
    assert de.max() < 0.01
    # A coarse table interpolates much worse than the res-64 one, but it is a sane table.
    de_grid, _ = up.roundtrip_delta_E(lut, up.roundtrip_grid_rgb(9))
    assert np.isfinite(de_grid).all() and de_grid.mean() < 1.5


@pytest.mark.slow
def test_fit_lut_wide_gamut_reports_out_of_reach():
    fit = up.fit_lut("ProPhoto RGB", 6, throw=False)
    s = fit.summary()
    assert s["converged"] + s["out_of_reach"] + s["not_converged"] == s["entries"]
    assert s["out_of_reach"] > 0  # ProPhoto's primaries lie outside the object-colour solid
    assert np.isfinite(np.asarray(fit.lut.coeffs)).all()
    assert fit.lut.colourspace == "ProPhoto RGB"
