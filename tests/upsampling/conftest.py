"""Shared fixtures of the upsampling tests: ColorChecker colours and one direct fit."""

import numpy as np
import pytest

import radiometria.upsampling as up


@pytest.fixture(scope="session")
def colorchecker():
    """(wavelengths (n,), reflectances (24, n), names, linear sRGB (24, 3) clipped to [0, 1])."""
    from radiometria.figures._upsampling import colorchecker_spectra

    wl, values, names = colorchecker_spectra()
    model = up.forward_model("sRGB")
    rgb = values @ model.weights_XYZ @ model.matrix_XYZ_to_RGB.T
    return wl, values, names, np.clip(rgb, 0.0, 1.0)


@pytest.fixture(scope="session")
def direct_fit(colorchecker):
    """fit_rgb on 30 colours: the 24 patches, black, white, a grey, and 3 table-node colours."""
    lut = up.get_lut()
    scale = np.asarray(lut.scale, np.float64)
    nodes = np.array([
        [scale[40], scale[40] * 10 / 63, scale[40] * 50 / 63],  # red largest (l = 0)
        [scale[20] * 33 / 63, scale[20], 0.0],  # green largest, x = 0
        [scale[60] * 5 / 63, scale[60] * 62 / 63, scale[60]],  # blue largest
    ])  # fmt: skip
    rgb = np.concatenate([colorchecker[3], [[0, 0, 0], [1, 1, 1], [0.3, 0.3, 0.3]], nodes])
    return rgb, up.fit_rgb(rgb, throw=False)
