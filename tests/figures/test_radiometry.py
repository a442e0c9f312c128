"""The Planck figure: its curves against a numpy Planck's law with SciPy's CODATA constants."""

import numpy as np
import pytest
from scipy import constants, optimize

from radiometria.figures import FIGURES, make_figures
from radiometria.figures._radiometry import planck_figure_data


@pytest.fixture(scope="module")
def data():
    return planck_figure_data(smoke=True)


def _planck_numpy(wavelength_nm, temperature):
    """2 h c^2 / (lambda^5 (exp(h c / (lambda k T)) - 1)), per nm [W sr^-1 m^-2 nm^-1]."""
    h, c, k = constants.h, constants.c, constants.k
    lam = np.asarray(wavelength_nm) * 1e-9
    return 2 * h * c**2 / lam**5 / np.expm1(h * c / (lam * k * temperature)) * 1e-9


def test_planck_figure_curves_equal_numpy_planck(data):
    wl, T = data["wavelengths_nm"], data["temperatures"]
    np.testing.assert_array_equal(T, [3000.0, 4000.0, 5000.0, 5778.0, 6000.0])
    assert data["radiance"].shape == (T.size, wl.size)
    np.testing.assert_allclose(data["radiance"], _planck_numpy(wl[None], T[:, None]), rtol=1e-9)
    np.testing.assert_allclose(
        data["locus_radiance"],
        _planck_numpy(data["locus_peak_nm"], data["locus_temperatures"]),
        rtol=1e-9,
    )


def test_planck_figure_peaks_are_wien_maxima(data):
    """Wien's law with SciPy's constant, and each marked peak is the maximum of the numpy
    Planck curve (found by bounded minimisation, independent of the x = 5(1 - e^-x) root)."""
    for key_t, key_peak in (("temperatures", "peaks_nm"), ("locus_temperatures", "locus_peak_nm")):
        np.testing.assert_allclose(data[key_peak], constants.Wien / data[key_t] * 1e9, rtol=1e-9)
    for t, peak, value in zip(
        data["temperatures"], data["peaks_nm"], data["peaks_radiance"], strict=True
    ):
        res = optimize.minimize_scalar(
            lambda x, t=t: -_planck_numpy(x, t), bounds=(200.0, 2000.0), method="bounded",
            options={"xatol": 1e-6},
        )  # fmt: skip
        assert peak == pytest.approx(res.x, rel=1e-6)
        assert value == pytest.approx(-res.fun, rel=1e-9)
        assert value == pytest.approx(_planck_numpy(peak, t), rel=1e-9)
    # Every plotted curve lies below its own peak marker.
    assert np.all(data["radiance"].max(axis=1) <= data["peaks_radiance"] * (1 + 1e-12))


def test_planck_figure_written(tmp_path):
    assert "fig_1_planck" in FIGURES
    paths = make_figures(tmp_path, ["fig_1_planck"], smoke=True)
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]
