"""Figures 2.4, the round-trip error map and the ColorChecker: the plotted data against closed
forms and a colour-science round trip (its CMFs, D65, sRGB matrices, CIELAB and CIEDE2000)."""

import numpy as np
import pytest

from radiometria.figures import FIGURES, make_figures
from radiometria.figures._upsampling import (
    colorchecker_figure_data,
    roundtrip_error_data,
    sigmoid_figure_data,
)
from radiometria.upsampling import RGBAlbedoSpectrum, get_lut

colour = pytest.importorskip("colour")

WL = np.arange(360.0, 831.0)  # the 1 nm grid of the fit [nm]


def _srgb_matrices():
    """sRGB's RGB -> XYZ matrix derived from its primaries and white (colour-science's
    `normalised_primary_matrix`; its stored sRGB matrices are IEC 61966-2-1's rounded ones)."""
    cs = colour.RGB_COLOURSPACES["sRGB"]
    m = colour.normalised_primary_matrix(cs.primaries, cs.whitepoint)
    return m, np.linalg.inv(m)


def _colour_science_weights():
    """Reflectance -> XYZ weights on WL under D65 with colour-science's data: CIE 1931 2° CMFs,
    D65 (tabulated at 5 nm to 780 nm: interpolated linearly, held constant beyond), Y = 1 for
    the perfect reflector, then each sRGB channel divided by its sum (the fit's white balance,
    `radiometria.upsampling._forward`, module docstring)."""
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"][WL]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    s = np.interp(WL, d65.wavelengths, d65.values)
    w = cmfs * s[:, None]
    w /= w[:, 1].sum()
    to_xyz, to_rgb = _srgb_matrices()
    w_rgb = w @ to_rgb.T
    return (w_rgb / w_rgb.sum(axis=0)) @ to_xyz.T


def _colour_science_delta_E(rgb, spectra):
    """CIEDE2000 between linear sRGB colours and reflectance spectra on WL, by colour-science."""
    white = colour.RGB_COLOURSPACES["sRGB"].whitepoint
    xyz_in = rgb @ _srgb_matrices()[0].T
    xyz_out = spectra @ _colour_science_weights()
    lab_in, lab_out = (colour.XYZ_to_Lab(x, white) for x in (xyz_in, xyz_out))
    return colour.delta_E(lab_in, lab_out, method="CIE 2000")


# --- fig. 2.4: the sigmoid ----------------------------------------------------------------


def test_sigmoid_figure_equals_closed_form():
    data = sigmoid_figure_data()
    x, wl, c = data["x"], data["wavelengths_nm"], data["coeffs"]
    sigmoid = lambda t: 0.5 + t / (2 * np.sqrt(1 + t * t))  # noqa: E731 (eq. 2.26)
    np.testing.assert_allclose(data["s"], sigmoid(x), rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(c, [-0.000073447, 0.035354, -2.607])  # thesis fig. 2.4
    np.testing.assert_allclose(data["poly"], c[0] * wl**2 + c[1] * wl + c[2], rtol=1e-12)
    np.testing.assert_allclose(data["S"], sigmoid(np.polyval(c, wl)), rtol=1e-10, atol=1e-14)
    np.testing.assert_array_equal(wl[[0, -1]], [360.0, 830.0])
    # s(0) = 1/2, s is odd about (0, 1/2), and the curve spans (0, 1).
    np.testing.assert_allclose(data["s"] + data["s"][::-1], 1.0, atol=1e-14)
    assert data["s"][200] == 0.5 and 0 < data["S"].min() < data["S"].max() < 1


# --- round-trip error map -----------------------------------------------------------------


@pytest.fixture(scope="module")
def roundtrip():
    return roundtrip_error_data(smoke=True)


def test_roundtrip_figure_grid_is_inside_srgb(roundtrip):
    xy, rgb = roundtrip["xy"], roundtrip["rgb"]
    cs = colour.RGB_COLOURSPACES["sRGB"]
    np.testing.assert_allclose(roundtrip["primaries"], cs.primaries, atol=1e-12)
    # The colours have the plotted chromaticities (colour-science's RGB -> XYZ -> xy).
    np.testing.assert_allclose(colour.XYZ_to_xy(rgb @ _srgb_matrices()[0].T), xy, atol=1e-12)
    np.testing.assert_allclose(rgb.max(axis=1), 1.0, atol=1e-12)
    assert rgb.min() >= 0.0 and len(xy) > 200
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"][np.arange(360.0, 781.0)]
    np.testing.assert_allclose(roundtrip["locus"], colour.XYZ_to_xy(cmfs), atol=1e-12)


def test_roundtrip_figure_delta_E_equals_colour_science(roundtrip):
    """The plotted CIEDE2000 of each colour and each brightness, redone with colour-science on
    the table's spectrum (`RGBAlbedoSpectrum`); the summary statistics in the titles agree."""
    lut = get_lut("sRGB")
    assert [b for b, _ in roundtrip["results"]] == [1.0, 0.02]
    for b, de in roundtrip["results"]:
        rgb = roundtrip["rgb"] * b
        spectra = np.asarray(RGBAlbedoSpectrum(lut, rgb)(WL))
        ref = _colour_science_delta_E(rgb, spectra)
        # Agreement to 1e-13 observed; 1e-6 leaves room for BLAS/ordering differences and
        # is far below the plotted errors (mean 0.017 at brightness 1, 0.11 at 0.02).
        np.testing.assert_allclose(de, ref, atol=1e-6, err_msg=f"brightness {b}")
        assert de.mean() == pytest.approx(ref.mean(), abs=1e-6)
        assert de.max() == pytest.approx(ref.max(), abs=1e-6)


# --- ColorChecker --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def checker():
    return colorchecker_figure_data()


def test_colorchecker_figure_spectra_equal_colour_science(checker):
    ref = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    assert checker["names"] == list(ref.keys()) and len(checker["names"]) == 24
    wl = checker["wavelengths_nm"]
    np.testing.assert_array_equal(wl, WL)
    knots = np.isin(wl, np.arange(380.0, 781.0, 5.0))
    for k, name in enumerate(checker["names"]):
        np.testing.assert_allclose(checker["measured"][k, knots], ref[name].values, atol=1e-12)
        # Held constant outside the 380-780 nm table (CIE 015 practice).
        assert np.all(checker["measured"][k, wl < 380] == ref[name].values[0])
        assert np.all(checker["measured"][k, wl > 780] == ref[name].values[-1])


def test_colorchecker_figure_colours_equal_colour_science(checker):
    """Linear sRGB under D65 of the measured spectra, by colour-science's `sd_to_XYZ` (ASTM
    E308 on its own 5 nm data, an independent integration), and the encoded patch colours."""
    ref = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    xyz = np.stack([colour.sd_to_XYZ(ref[n], cmfs, d65) / 100 for n in checker["names"]])
    rgb = np.clip(xyz @ _srgb_matrices()[1].T, 0, 1)
    np.testing.assert_allclose(checker["rgb"], rgb, atol=3e-3)
    encoded = colour.cctf_encoding(checker["rgb"], function="sRGB")
    np.testing.assert_allclose(checker["encoded"], encoded, atol=1e-9)
    # The white patch is (nearly) neutral; the dark skin patch is reddish.
    white = checker["rgb"][checker["names"].index("white 9.5 (.05 D)")]
    assert np.ptp(white) < 0.03
    skin = checker["rgb"][0]
    assert skin[0] > skin[1] > skin[2]


def test_colorchecker_figure_upsampling_and_delta_E(checker):
    lut = get_lut("sRGB")
    np.testing.assert_allclose(
        checker["upsampled"], np.asarray(RGBAlbedoSpectrum(lut, checker["rgb"])(WL)), atol=1e-12
    )
    assert np.all((checker["upsampled"] > 0) & (checker["upsampled"] < 1))
    ref = _colour_science_delta_E(checker["rgb"], checker["upsampled"])
    np.testing.assert_allclose(checker["delta_E"], ref, atol=1e-6)
    assert checker["delta_E"].max() < 1.0  # the table reproduces every patch's colour


@pytest.mark.parametrize("name", ["fig_2_4_sigmoid", "fig_2_roundtrip_error"])
def test_upsampling_figure_written(tmp_path, name):
    assert name in FIGURES
    paths = make_figures(tmp_path, [name], smoke=True)
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]
