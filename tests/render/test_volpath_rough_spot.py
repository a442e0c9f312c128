"""volpath against Mitsuba 3 `scalar_spectral` `volpath` on a homogeneous medium behind a
rough dielectric boundary lit by a spot light (the issue's "rough dielectric boundary with a
spot light" case), judged with Mitsuba's z-test (`radiometria.montecarlo.pixel_z_test` on
Mitsuba `moment` references, `_mitsuba.py`) and the image mean within pooled standard errors,
with a 25 % denser medium as the negative control.

The spot light shines on a rough (GGX, alpha 0.9) dielectric cube filled with a scattering
medium, against a black background: the camera sees the spot's glossy reflection on the
interface and the medium's in-scattering. A delta light cannot be connected to a medium
vertex through a non-null boundary, so the medium is lit by next-event estimation at the
boundary's inner side (rough transmission towards the spot), the paths this case exists for.

The z-test runs on 2 x 2 pixel bins (8 x 8 bins; a bin's per-sample variance is the mean of
its pixels' over 4): those paths are heavy-tailed, and at CI sample counts the per-pixel test
fails Mitsuba against itself (99.5 % of pixel channels for two other seeds, 99.75 % needed)
while the binned one passes it (100 %).

Found with this scene: our `roughdielectric` used the height-correlated Smith
masking-shadowing where Mitsuba 3 uses the separable $G_1G_1$; with no medium at all the image
was 10 % brighter than Mitsuba's (+3.5 pooled standard errors), with the medium 14 %. The
`roughdielectric` and `roughconductor` plugins now use `masking="separable"` as Mitsuba does.
"""

import numpy as np
import pytest

from radiometria.montecarlo import pixel_z_test
from radiometria.render import render

from ._mitsuba import mitsuba_moments

pytest.importorskip("mitsuba")

SIZE = 16
SPP = 1024
REF_SPP = 4096

SCENE = """<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="22"/>
    <transform name="to_world"><lookat origin="0, 0.5, 5" target="0, 0, 0" up="0, 1, 0"/>
    </transform>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm"><integer name="width" value="{size}"/>
      <integer name="height" value="{size}"/><rfilter type="box"/></film>
  </sensor>
  <integrator type="volpath"><integer name="max_depth" value="8"/></integrator>
  <emitter type="spot"><transform name="to_world"><lookat origin="1.5, 3, 3" target="0, 0, 0"
    up="0, 1, 0"/></transform><rgb name="intensity" value="30, 30, 30"/>
    <float name="cutoff_angle" value="35"/><float name="beam_width" value="25"/></emitter>
  <medium type="homogeneous" id="m"><float name="sigma_t" value="{sigma_t}"/>
    <rgb name="albedo" value="0.9, 0.7, 0.5"/><phase type="hg"><float name="g" value="0.3"/>
    </phase></medium>
  <shape type="cube"><transform name="to_world"><scale value="0.75"/><rotate y="1" angle="35"/>
    <rotate x="1" angle="20"/></transform>
    <bsdf type="roughdielectric"><string name="distribution" value="ggx"/>
      <float name="alpha" value="0.9"/><float name="int_ior" value="1.33"/></bsdf>
    <ref name="interior" id="m"/></shape>
</scene>
"""


@pytest.fixture(scope="module")
def rough_spot(tmp_path_factory):
    """The scene file as a function of the medium's sigma_t, and Mitsuba's per-pixel mean and
    variance at sigma_t = 0.7"""
    tmp = tmp_path_factory.mktemp("rough_spot")

    def scene(sigma_t: float):
        path = tmp / f"rough_spot_{sigma_t}.xml"
        path.write_text(SCENE.format(size=SIZE, sigma_t=sigma_t))
        return path

    mean, var = mitsuba_moments(scene(0.7), REF_SPP, seed=1)
    return scene, mean, var


def _bin(a):
    """Means over 2 x 2 pixel blocks, `(H/2, W/2, 3)`."""
    h, w = a.shape[0] // 2, a.shape[1] // 2
    return a.reshape(h, 2, w, 2, -1).mean(axis=(1, 3))


def _judge(path, mean, var):
    img = np.asarray(render(path, spp=SPP, seed=0, return_xyz=True, progress=False), np.float64)
    n = mean.shape[0] * mean.shape[1]
    se = np.sqrt(var.sum(axis=(0, 1)) / n**2 * (1 / SPP + 1 / REF_SPP))
    mean_ok = bool(np.all(np.abs((img - mean).mean(axis=(0, 1))) < 4 * se))
    result = pixel_z_test(_bin(img), _bin(mean), _bin(var) / 4, SPP, REF_SPP)
    return result, mean_ok, img


def test_medium_behind_a_rough_dielectric_lit_by_a_spot_passes_against_mitsuba(rough_spot):
    scene, mean, var = rough_spot
    result, mean_ok, img = _judge(scene(0.7), mean, var)
    assert result.passed, result.message
    assert mean_ok, (img.mean(axis=(0, 1)), mean.mean(axis=(0, 1)))


def test_a_denser_medium_fails_against_mitsuba(rough_spot):
    scene, mean, var = rough_spot
    result, mean_ok, _ = _judge(scene(0.875), mean, var)
    assert not (result.passed and mean_ok)
