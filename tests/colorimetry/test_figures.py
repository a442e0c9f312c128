"""The colorimetry figures render (smoke sizes) and are written as PNG and PDF."""

import pytest

from radiometria.figures import FIGURES, make_figures


@pytest.mark.parametrize("name", ["fig_2_1_cmfs", "fig_2_2_chromaticity"])
def test_colorimetry_figure_smoke(tmp_path, name):
    assert name in FIGURES
    paths = make_figures(tmp_path, [name], smoke=True)
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]
    assert all(p.stat().st_size > 1000 for p in paths)
