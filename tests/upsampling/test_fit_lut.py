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
    assert s["not_converged"] == 0 and s["out_of_reach"] == 0
    assert s["residual_max_converged"] <= 5e-3
    assert np.asarray(fit.converged | fit.tail_free).all()
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
def test_fit_lut_tail_stage():
    """Stage (4) against the same fit without it: only entries whose spectrum had an infrared
    tail change, and each now reproduces its colour within TAIL_TOLERANCE (CIELAB computed by
    colour-science from the spectrum's XYZ) with tail ratio <= TAIL_RATIO."""
    import colour

    from radiometria.upsampling._tails import TAIL_RATIO, TAIL_TOLERANCE

    fit = up.fit_lut("sRGB", 10)
    plain = up.fit_lut("sRGB", 10, infrared_tails=False)
    assert plain.settings["infrared_tails"] == "off"
    report = fit.settings["infrared_tails"]
    new, old = np.asarray(fit.lut.coeffs, np.float64), np.asarray(plain.lut.coeffs, np.float64)
    changed = np.any(new != old, axis=-1)
    tail_free = np.array(fit.tail_free)
    assert report["replaced"] > 0 and np.array_equal(changed, tail_free)
    # Row 0 (black) holds a copy of row 1 (`fit_lut`'s explicit ends): check the nodes k >= 1.
    np.testing.assert_array_equal(new[:, 0], new[:, 1])
    tail_free[:, 0] = False
    assert report["entries_with_tail"] == report["replaced"] + report["kept"]
    model = up.forward_model("sRGB")
    wl = np.asarray(model.wavelengths_nm)
    scale = np.asarray(fit.lut.scale, np.float64)
    l_, k_, j_, i_ = np.nonzero(tail_free)
    rgb = np.zeros((l_.size, 3))
    rows = np.arange(l_.size)
    rgb[rows, l_] = scale[k_]
    rgb[rows, (l_ + 1) % 3] = i_ / 9 * scale[k_]
    rgb[rows, (l_ + 2) % 3] = j_ / 9 * scale[k_]
    spectra = np.asarray(up.sigmoid_polynomial_jakob2019(new[tail_free], wl))
    white = colour.XYZ_to_xy(model.white_XYZ)
    lab = colour.XYZ_to_Lab(spectra @ model.weights_XYZ, white)
    lab_t = colour.XYZ_to_Lab(rgb @ model.matrix_RGB_to_XYZ.T, white)
    de = colour.delta_E(lab, lab_t, method="CIE 1976")
    assert de.max() <= TAIL_TOLERANCE * (1 + 1e-3)
    np.testing.assert_allclose(de, np.asarray(fit.residual)[tail_free], rtol=1e-3, atol=1e-6)
    q = spectra[:, wl > 730].max(1) / spectra[:, wl <= 730].max(1)
    assert q.max() <= TAIL_RATIO * 1.01
    old_sp = np.asarray(up.sigmoid_polynomial_jakob2019(old[tail_free], wl))
    # (q is defined on the continuous interval; this 1 nm grid can only see it a hair lower)
    assert np.all(old_sp[:, wl > 730].max(1) / old_sp[:, wl <= 730].max(1) > 0.99 * TAIL_RATIO)


@pytest.mark.slow
def test_fit_lut_wide_gamut_reports_out_of_reach():
    fit = up.fit_lut("ProPhoto RGB", 6, throw=False)
    s = fit.summary()
    total = s["converged"] + s["out_of_reach"] + s["not_converged"] + s["tail_free"]
    assert total == s["entries"]
    assert s["out_of_reach"] > 0  # ProPhoto's primaries lie outside the object-colour solid
    assert np.isfinite(np.asarray(fit.lut.coeffs)).all()
    assert fit.lut.colourspace == "ProPhoto RGB"
