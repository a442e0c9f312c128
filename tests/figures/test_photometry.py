"""The luminous efficiency figure: V(lambda), V'(lambda) against colour-science's tables."""

import numpy as np
import pytest

from radiometria.figures import FIGURES, make_figures
from radiometria.figures._photometry import luminous_efficiency_data

colour = pytest.importorskip("colour")


@pytest.fixture(scope="module")
def data():
    return luminous_efficiency_data()


@pytest.mark.parametrize(
    ("vision", "table", "source", "efficacy", "span"),
    [
        ("photopic", "CIE 1924 Photopic Standard Observer", "SDS_LEFS_PHOTOPIC", 683.0, (360, 830)),
        ("scotopic", "CIE 1951 Scotopic Standard Observer", "SDS_LEFS_SCOTOPIC", 1700, (380, 780)),
    ],
)  # fmt: skip
def test_luminous_efficiency_figure_equals_colour_science(
    data, vision, table, source, efficacy, span
):
    d = data[vision]
    ref = getattr(colour.colorimetry, source)[table]
    wl = d["wavelengths_nm"]
    np.testing.assert_array_equal(wl, np.arange(span[0], span[1] + 1.0))
    np.testing.assert_allclose(d["values"], ref[wl], rtol=1e-9, atol=1e-12)
    # K_m = 683.002 and K'_m = 1700.06 lm/W (CIE 015:2018); colour-science rounds them.
    assert d["efficacy"] == pytest.approx(efficacy, rel=1e-4)
    np.testing.assert_allclose(d["efficacy_curve"], d["efficacy"] * ref[wl], rtol=1e-9)


def test_luminous_efficiency_figure_peaks(data):
    """V peaks at 555 nm, V' at 507 nm (CIE 015:2018); the efficacy curves peak at K_m."""
    assert data["photopic"]["peak_nm"] == 555.0
    assert data["scotopic"]["peak_nm"] == 507.0
    for d in data.values():
        assert d["values"].max() == pytest.approx(1.0, abs=1e-6)
        assert d["efficacy_curve"].max() == pytest.approx(d["efficacy"], rel=1e-6)
    # At 555 nm the photopic efficacy is 683 lm/W; the scotopic curve is higher at 507 nm.
    p, s = data["photopic"], data["scotopic"]
    assert p["efficacy_curve"][p["wavelengths_nm"] == 555.0][0] == pytest.approx(683.0, rel=1e-4)
    assert s["efficacy"] / p["efficacy"] == pytest.approx(1700.0 / 683.0, rel=1e-4)


def test_luminous_efficiency_figure_written(tmp_path):
    assert "fig_2_luminous_efficiency" in FIGURES
    paths = make_figures(tmp_path, ["fig_2_luminous_efficiency"], smoke=True)
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]
