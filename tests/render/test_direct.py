"""The `direct` integrator's sample counts (Mitsuba's `emitter_samples`, `bsdf_samples`,
`shading_samples`): a closed form, Mitsuba 3 pixel by pixel, and bad parameters."""

import re

import numpy as np
import pytest

import radiometria.render as rr
from radiometria.montecarlo import pixel_z_test
from radiometria.render import Direct, SceneError


def _cornell_direct(tmp_path, size, params: str):
    from ._mitsuba import cornell_box_xml

    xml = re.sub(
        r'<integrator type="path">.*?</integrator>',
        f'<integrator type="direct">{params}</integrator>',
        cornell_box_xml(size, size),
        flags=re.S,
    )
    path = tmp_path / "direct.xml"
    path.write_text(xml)
    return path


@pytest.mark.slow
@pytest.mark.parametrize(
    ("emitter", "bsdf"), [(2, 3), (0, 2)], ids=["2 light + 3 bsdf", "bsdf only"]
)
def test_direct_sample_counts_match_mitsuba(tmp_path, emitter, bsdf):
    """Our `direct` with Mitsuba's sample counts against Mitsuba's own (`moment` integrator
    for the per-pixel variance) on the Cornell box, pixel by pixel and in the image mean; a
    10 % brighter image fails the mean."""
    pytest.importorskip("mitsuba")
    from ._mitsuba import mitsuba_moments

    params = (
        f'<integer name="emitter_samples" value="{emitter}"/>'
        f'<integer name="bsdf_samples" value="{bsdf}"/>'
    )
    path = _cornell_direct(tmp_path, 16, params)
    integrator = rr.scene_integrator(rr.load_scene(path))
    assert integrator == Direct(emitter_samples=emitter, bsdf_samples=bsdf)
    mean, var = mitsuba_moments(path, 4096, seed=1)
    ours = rr.render(path, integrator=integrator, spp=1024, return_xyz=True, progress=False)
    ours = np.asarray(ours, np.float64)
    res = pixel_z_test(ours, mean, var, 1024, 4096)
    assert res.passed, res.message
    # The image mean of Y, with the standard error from Mitsuba's per-pixel variances, has
    # the power that single noisy pixels lack: a 10 % brighter image fails it.
    se = np.sqrt(np.sum(var[..., 1]) * (1 / 1024 + 1 / 4096)) / var[..., 1].size
    z = (ours[..., 1].mean() - mean[..., 1].mean()) / se
    assert abs(z) < 4.0, z
    assert (1.1 * ours[..., 1].mean() - mean[..., 1].mean()) / se > 4.0


def test_direct_parameters(tmp_path):
    assert Direct.from_properties({}) == Direct()
    assert Direct.from_properties({"shading_samples": 3}) == Direct(
        emitter_samples=3, bsdf_samples=3
    )
    assert Direct(emitter_samples=2, bsdf_samples=0).sample_dimensions() == 8
    assert Direct().sample_dimensions() == 8  # the two-segment path layout
    with pytest.raises(ValueError, match="shading_samples or emitter_samples"):
        Direct.from_properties({"shading_samples": 2, "bsdf_samples": 1})
    with pytest.raises(ValueError, match=r"`bsdf_samples` must be an int >= 0, got -1"):
        Direct(bsdf_samples=-1)
    with pytest.raises(ValueError, match="must not both be 0"):
        Direct.from_properties({"emitter_samples": 0, "bsdf_samples": 0})
    path = _cornell_direct(tmp_path, 8, '<integer name="emitter_samples" value="-2"/>')
    with pytest.raises((SceneError, ValueError), match="emitter_samples"):
        rr.scene_integrator(rr.load_scene(path))
