"""Chapter 9 figures: the Cornell box against Mitsuba 3, and the render convergence curve
against the 1/N law of independent sampling."""

import numpy as np
import pytest

from radiometria.figures import FIGURES, _render, make_figures
from radiometria.figures._render import cornell_box_data, render_convergence_data

from ..render._mitsuba import cornell_dict, render_mitsuba

SIZE, SPP = 16, 1024  # a tiny Cornell box, but enough samples for its mean to within ~1 %


@pytest.fixture(scope="module")
def cornell():
    return cornell_box_data(size=SIZE, spp=SPP)


@pytest.fixture(scope="module")
def convergence():
    return render_convergence_data(smoke=True, seeds=range(64))


@pytest.mark.slow
def test_cornell_box_figure_images(cornell):
    """Both images are finite and non-negative; the red wall is on the left and the green
    wall on the right (a mirrored or transposed image fails); the exposure maps the measured
    scene's mean Rec. 709 luminance to 0.18."""
    assert cornell["size"] == SIZE and cornell["spp"] == SPP
    for key in ("box", "measured"):
        img = cornell[key]
        assert img.shape == (SIZE, SIZE, 3) and np.all(np.isfinite(img)) and img.min() >= 0
        left, right = img[:, :3].mean(axis=(0, 1)), img[:, -3:].mean(axis=(0, 1))
        assert left[0] > 3 * left[1] and right[1] > right[0], key
    y = cornell["measured"] @ np.array([0.2126, 0.7152, 0.0722])
    assert cornell["exposure"] * y.mean() == pytest.approx(0.18, rel=1e-12)


@pytest.mark.slow
def test_cornell_box_figure_mean_matches_mitsuba(cornell):
    """Per-channel means of the RGB scene against Mitsuba 3 (`scalar_spectral`, 4096 spp).

    Tolerance: over seeds, the mean of a 16 x 16 image at 64 spp scatters by about 2 % (R, G)
    and 7 % (B, the dim channel); at 1024 spp that is 0.5 % and 1.8 %, so 3 % and 6 % are
    about 5 and 3 standard errors. The spectral upsampling of the reflectances is the same
    as Mitsuba's (Jakob & Hanika 2019) up to the table's resolution.
    """
    pytest.importorskip("mitsuba", reason="Mitsuba 3 is the optional reference renderer")
    reference = render_mitsuba(cornell_dict(SIZE, SIZE), 4096, seed=1).mean(axis=(0, 1))
    np.testing.assert_allclose(cornell["box"].mean(axis=(0, 1))[:2], reference[:2], rtol=0.03)
    assert cornell["box"].mean(axis=(0, 1))[2] == pytest.approx(reference[2], rel=0.06)


@pytest.mark.slow
def test_render_convergence_figure_slope(convergence):
    """Relative MSE against spp, 8 x 8 px, 1-8 spp, averaged over 64 seeds.

    Independent sampling: E[MSE(N)] = sigma^2 / N + (reference noise), a log-log slope of -1
    (the reference, Sobol at 128 spp, adds a floor under 1/16 of the 8 spp error, which
    flattens the slope by at most 0.03). The error is heavy-tailed (fireflies): slopes fitted
    to 16-seed means scatter by 0.18 between disjoint seed sets, so 64 seeds give about 0.09
    and the bound 0.3 is over 3 standard errors (these seeds give -0.97). At 1 spp the
    Owen-scrambled Sobol sampler has nothing to stratify across samples; at 8 spp it is
    clearly better.
    """
    counts = np.asarray(convergence["counts"], float)
    np.testing.assert_array_equal(counts, [1, 2, 4, 8])
    assert convergence["size"] == 8 and len(convergence["seeds"]) == 64
    ind, sob = convergence["errors"]["independent"], convergence["errors"]["sobol"]
    assert np.all(np.diff(ind) < 0) and np.all(np.diff(sob) < 0)
    slope = np.polyfit(np.log(counts), np.log(ind), 1)[0]
    assert abs(slope + 1.0) < 0.3, slope
    assert sob[-1] < 0.8 * ind[-1]  # 0.45-0.57 of it in disjoint 16-seed sets
    ref = convergence["reference"]
    assert ref.shape == (8, 8, 3) and np.all(np.isfinite(ref))


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "helper", "fixture"),
    [
        ("fig_9_cornell_box", "cornell_box_data", "cornell"),
        ("fig_9_render_convergence", "render_convergence_data", "convergence"),
    ],
)
def test_render_figure_drawn_from_its_data(tmp_path, monkeypatch, request, name, helper, fixture):
    """The figure draws the data its helper returns (the module's fixture, not recomputed)."""
    assert name in FIGURES
    data = request.getfixturevalue(fixture)
    calls = []
    monkeypatch.setattr(_render, helper, lambda **kw: calls.append(kw) or data)
    paths = make_figures(tmp_path, [name], smoke=True)
    assert calls == [{"smoke": True}]
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]
