"""Figures 2.1 and 2.2: the plotted CMFs, cone fundamentals, loci, gamuts and white points
against colour-science, CIE 170-2 and a numpy Planck's law with SciPy's constants."""

import numpy as np
import pytest
from scipy import constants

from radiometria.figures import FIGURES, make_figures
from radiometria.figures._colorimetry import chromaticity_figure_data, cmfs_figure_data

colour = pytest.importorskip("colour")


@pytest.fixture(scope="module")
def data():
    return cmfs_figure_data()


@pytest.mark.parametrize(
    ("key", "table"),
    [
        ("rgb", "Wright & Guild 1931 2 Degree RGB CMFs"),
        ("xyz", "CIE 1931 2 Degree Standard Observer"),
        ("lms", "Stockman & Sharpe 2 Degree Cone Fundamentals"),
    ],
)
def test_cmfs_figure_curves_equal_colour_science(data, key, table):
    wl, values = data[key]
    ref = colour.MSDS_CMFS[table]
    assert values.shape == (wl.size, 3)
    assert np.all(np.isin(wl, ref.wavelengths))
    np.testing.assert_allclose(values, ref[wl], rtol=1e-6, atol=1e-9)


def test_cmfs_figure_cones_give_the_cie_2006_observer(data):
    """CIE 170-2:2015: the CIE 2006 (2015) 2° CMFs are a fixed linear map of these LMS curves,
    and colour-science tabulates them separately (from CVRL), an independent check."""
    wl, lms = data["lms"]
    xyz_2006 = colour.MSDS_CMFS["CIE 2015 2 Degree Standard Observer"]
    keep = np.isin(wl, xyz_2006.wavelengths)
    M = np.array(
        [
            [1.94735469, -1.41445123, 0.36476327],
            [0.68990272, 0.34832189, 0.0],
            [0.0, 0.0, 1.93485343],
        ]
    )  # CIE 170-2:2015 (LMS to XYZ, 2°)
    np.testing.assert_allclose(lms[keep] @ M.T, xyz_2006[wl[keep]], atol=5e-6)


def test_cmfs_figure_cone_peaks(data):
    """Peaks of the energy-based 2° fundamentals: L 570 nm, M 543 nm, S 442 nm (CVRL)."""
    wl, lms = data["lms"]
    np.testing.assert_allclose(lms.max(axis=0), 1.0, atol=1e-4)
    np.testing.assert_array_equal(wl[np.argmax(lms, axis=0)], [570.0, 543.0, 442.0])


def test_cmfs_figure_written(tmp_path):
    assert "fig_2_1_cmfs" in FIGURES
    paths = make_figures(tmp_path, ["fig_2_1_cmfs"], smoke=True)
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]


# --- fig. 2.2: the chromaticity diagram ----------------------------------------------------

OBSERVER = "CIE 1931 2 Degree Standard Observer"


@pytest.fixture(scope="module")
def chromaticity():
    return chromaticity_figure_data(smoke=True)


def _planck_xy(temperatures):
    """xy of Planck's law (scipy.constants) summed against colour-science's CMFs, 360-830 nm."""
    wl = np.arange(360.0, 831.0)
    cmfs = colour.MSDS_CMFS[OBSERVER][wl]
    lam = wl[None] * 1e-9
    t = np.asarray(temperatures, float)[:, None]
    h, c, k = constants.h, constants.c, constants.k
    spd = 2 * h * c**2 / lam**5 / np.expm1(h * c / (lam * k * t))
    return colour.XYZ_to_xy(spd @ cmfs)


def test_chromaticity_figure_spectral_locus(chromaticity):
    wl = chromaticity["locus_wavelengths_nm"]
    np.testing.assert_array_equal(wl[[0, -1]], [360.0, 780.0])
    ref = colour.XYZ_to_xy(colour.MSDS_CMFS[OBSERVER][wl])
    np.testing.assert_allclose(chromaticity["locus"], ref, atol=1e-12)
    # The labelled points (locus[wl - 360]): 520 nm is the top of the horseshoe, 700 nm red.
    assert chromaticity["locus"][520 - 360, 1] == pytest.approx(0.8338, abs=1e-3)
    assert chromaticity["locus"][700 - 360, 0] == pytest.approx(0.7347, abs=1e-3)


def test_chromaticity_figure_planckian_locus_and_isotemperature_lines(chromaticity):
    T = chromaticity["planck_cct"]
    np.testing.assert_allclose(T[[0, -1]], [1000.0, 100000.0])
    np.testing.assert_allclose(chromaticity["planck_xy"], _planck_xy(T), atol=1e-9)
    uv = lambda xy: colour.xy_to_UCS_uv(xy)  # noqa: E731 (CIE 1960 UCS)
    for t, (duv, xy) in chromaticity["isotemperature"].items():
        np.testing.assert_allclose(duv, np.linspace(-0.02, 0.02, 11))
        p, ahead = uv(_planck_xy([t, t * 1.0001]))
        line = uv(xy)
        # The line passes through the locus at Duv = 0 and |Duv| is the distance in uv ...
        np.testing.assert_allclose(line[5], p, atol=1e-8)
        np.testing.assert_allclose(np.linalg.norm(line - p, axis=1), np.abs(duv), atol=1e-6)
        # ... along the normal of the locus (the tangent by a numpy finite difference), ...
        tangent = (ahead - p) / np.linalg.norm(ahead - p)
        np.testing.assert_allclose((line - p) @ tangent, 0.0, atol=1e-6)
        # ... with Duv > 0 above the locus (towards green, CIE 015:2018 section 9.4).
        assert line[-1, 1] > p[1] > line[0, 1]


def test_chromaticity_figure_gamuts_and_white_points(chromaticity):
    for name, primaries in chromaticity["gamuts"].items():
        np.testing.assert_allclose(primaries, colour.RGB_COLOURSPACES[name].primaries, atol=1e-12)
    assert list(chromaticity["gamuts"]) == ["sRGB", "Display P3", "ITU-R BT.2020"]
    cmfs = colour.MSDS_CMFS[OBSERVER]
    table = colour.CCS_ILLUMINANTS[OBSERVER]
    for name, xy in chromaticity["illuminants"].items():
        ref = colour.XYZ_to_xy(colour.sd_to_XYZ(colour.SDS_ILLUMINANTS[name], cmfs))
        np.testing.assert_allclose(xy, ref, atol=1e-5, err_msg=name)
        np.testing.assert_allclose(xy, table[name], atol=5e-5, err_msg=name)  # CIE 015 table


def test_chromaticity_figure_image(chromaticity):
    """The fill: transparent outside the locus, neutral at D65, red at sRGB's red primary."""
    img = chromaticity["image"]
    n = img.shape[0]
    assert img.shape == (n, n, 4) and np.all((img >= 0) & (img <= 1))

    def pixel(x, y):  # imshow(origin="lower", extent=(0, 0.8, 0, 0.9)): rows are y
        return img[round(y / 0.9 * (n - 1)), round(x / 0.8 * (n - 1))]

    assert pixel(0.3, 0.85)[3] == 0 and pixel(0.7, 0.1)[3] == 0 and pixel(0.05, 0.02)[3] == 0
    np.testing.assert_allclose(pixel(0.3127, 0.3290), [1, 1, 1, 1], atol=0.03)
    np.testing.assert_allclose(pixel(0.64, 0.33), [1, 0, 0, 1], atol=0.1)
    np.testing.assert_allclose(pixel(0.15, 0.06), [0, 0, 1, 1], atol=0.15)
