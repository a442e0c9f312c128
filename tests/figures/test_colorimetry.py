"""Figure 2.1: the plotted CMFs and cone fundamentals against colour-science and CIE 170-2."""

import numpy as np
import pytest

from radiometria.figures import FIGURES, make_figures
from radiometria.figures._colorimetry import cmfs_figure_data

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
