"""Bidirectional figures (thesis ch. 9, issue 14): the hard scene's geometry; the
MIS-weighted strategy images sum to the full bdpt image of the same samples and, per path
length, agree with the unweighted ones in mean; both figures draw their helpers' data."""

import numpy as np
import pytest

from radiometria.figures import FIGURES, _bidirectional, make_figures
from radiometria.figures._bidirectional import (
    STRATEGY_DEPTH,
    glass_panel_scene,
    rel_mse,
    strategies_data,
)
from radiometria.render import load_scene


@pytest.fixture(scope="module")
def hard():
    # Synthetic data for the drawing test: the real data take four compiled integrators
    # (about 75 s on 2 cores), what `radiometria figures` and the demo run; the claims they
    # show are tested where they are cheaper (test_pssmlt, test_bdpt, the benchmark).
    rng = np.random.default_rng(0)
    names = ["path", "ptracer", "bdpt", "pssmlt"]
    return {
        "size": 8, "reference": rng.uniform(size=(8, 8, 3)), "ref_spp": 16,
        "images": {n: rng.uniform(size=(8, 8, 3)) for n in names},
        "spp": dict.fromkeys(names, 4), "seconds": dict.fromkeys(names, 0.1),
        "rel_mse": dict.fromkeys(names, 0.5),
    }  # fmt: skip


@pytest.fixture(scope="module")
def strategies():
    return strategies_data(smoke=True)


def test_rel_mse_definition():
    ref = np.array([[1.0, 0.0]])
    assert rel_mse(ref, ref) == 0.0
    np.testing.assert_allclose(rel_mse(ref + 0.1, ref), 0.5 * (0.01 / 1.01 + 0.01 / 0.01))


def test_glass_panel_scene(tmp_path):
    """The hard scene is the built-in Cornell box plus two triangles of thin glass under the
    light, covering it in x and z."""
    scene = load_scene(glass_panel_scene(tmp_path))
    box = load_scene("cornell-box")
    assert scene.faces.shape[0] == box.faces.shape[0] + 2
    panel = [m.type for m in scene.materials]
    assert panel.count("thindielectric") == 1
    glass = scene.vertices[scene.faces[-2:]].reshape(-1, 3)
    light = box.vertices[box.faces[box.face_emitter >= 0]].reshape(-1, 3)
    np.testing.assert_allclose(glass[:, 1], 0.97)
    assert glass[:, 0].min() < light[:, 0].min() and glass[:, 0].max() > light[:, 0].max()
    assert glass[:, 2].min() < light[:, 2].min() and glass[:, 2].max() > light[:, 2].max()


@pytest.mark.slow
def test_strategy_images_sum_to_the_bdpt_image(strategies):
    """The MIS weights of a path's strategies sum to 1 (Veach eq. 10.9), so the weighted
    strategy images of the same samples add up to the bdpt image (float32 sums); without one
    strategy they do not. Per path length k, the weighted row and each unweighted image that
    can sample the length's paths estimate the same image: their image means agree within
    30 % at these tiny sample counts (hitting the light, s = 0, is left out: too noisy)."""
    weighted, unweighted, full = (
        strategies["weighted"],
        strategies["unweighted"],
        strategies["full"],
    )
    total = sum(weighted.values())
    np.testing.assert_allclose(total, full, rtol=1e-4, atol=1e-5)
    assert not np.allclose(total - weighted[(1, 2)], full, rtol=1e-2, atol=1e-3)
    for k in range(1, STRATEGY_DEPTH + 1):
        row = sum(weighted[(s, k + 1 - s)] for s in range(k + 1))
        for s in range(1, k + 1):
            np.testing.assert_allclose(
                unweighted[(s, k + 1 - s)].mean(), row.mean(), rtol=0.3, err_msg=str((s, k))
            )


@pytest.mark.parametrize(
    ("name", "helper", "fixture"),
    [
        ("fig_9_bidirectional", "bidirectional_data", "hard"),
        ("fig_9_bdpt_strategies", "strategies_data", "strategies"),
    ],
)
@pytest.mark.slow
def test_bidirectional_figure_drawn_from_its_data(
    tmp_path, monkeypatch, request, name, helper, fixture
):
    """The figure draws the data its helper returns (the module's fixture, not recomputed)."""
    assert name in FIGURES
    data = request.getfixturevalue(fixture)
    calls = []
    monkeypatch.setattr(_bidirectional, helper, lambda **kw: calls.append(kw) or data)
    paths = make_figures(tmp_path, [name], smoke=True)
    assert calls == [{"smoke": True}]
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]
