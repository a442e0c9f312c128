"""Spot lights with a `texture` (issue 12): Mitsuba's projected image.

The emitted intensity towards points is compared with Mitsuba 3's own `spot` emitter
(`sample_direction`, `scalar_spectral`, at four wavelengths, coloured texels), and a scene
with a coloured texture with the per-pixel z-test against Mitsuba 3 `scalar_spectral`, with a
negative control (the image mirrored) that must fail.
"""

import numpy as np
import pytest
from PIL import Image

from radiometria.render import SceneError, load_scene
from radiometria.render._lights._spot import SpotLight
from radiometria.render._textures import TextureSpec, read_texture_image

from ._mitsuba import delta_light_values, projected_image_scene

mi = pytest.importorskip("mitsuba")
dr = pytest.importorskip("drjit")


def _images(tmp_path):
    rng = np.random.default_rng(0)
    grey = rng.integers(0, 256, (6, 5), dtype=np.uint8)
    Image.fromarray(grey).save(tmp_path / "grey.png")
    colour = np.kron(rng.integers(0, 2, (4, 4, 3)) * 200 + 30, np.ones((2, 2, 1)))
    Image.fromarray(colour.astype(np.uint8)).save(tmp_path / "colour.png")
    Image.fromarray(colour[:, ::-1].astype(np.uint8)).save(tmp_path / "mirrored.png")


def test_textured_spot_intensity_matches_mitsubas_spot(tmp_path):
    """Against the spot of a Mitsuba XML file: the texture's albedo spectra, no D65 (an
    intensity given as a `<spectrum value>` is flat in both)."""
    _images(tmp_path)
    mi.set_variant("scalar_spectral")
    to_world = mi.ScalarTransform4f().look_at(origin=[0.3, -0.2, 0.5], target=[0.5, 0.4, 3.0],
                                              up=[0.2, 1.0, 0.0])  # fmt: skip
    m = np.asarray(to_world.matrix, np.float64)
    matrix = " ".join(f"{x:.17g}" for x in m.ravel())
    emitter = mi.load_string(f"""<emitter version="3.0.0" type="spot">
        <spectrum name="intensity" value="3"/><float name="cutoff_angle" value="25"/>
        <float name="beam_width" value="12"/><transform name="to_world">
        <matrix value="{matrix}"/></transform><texture name="texture" type="bitmap">
        <string name="filename" value="{tmp_path / "colour.png"}"/></texture></emitter>""")
    ours = SpotLight.from_properties(
        [{"intensity": 3.0, "cutoff_angle": 25.0, "beam_width": 12.0, "to_world": m,
          "texture": TextureSpec("bitmap", rgb=read_texture_image(tmp_path / "colour.png"))}],
        where=["test"],
    )  # fmt: skip
    expected, got = delta_light_values(emitter, ours, n=64)
    assert (expected[:, 1] > 0).sum() > 10 and (expected[:, 1] == 0).sum() > 5
    # Our sigmoid coefficients come from our own table, Mitsuba's from its: about 1 %.
    np.testing.assert_allclose(got, expected, rtol=2e-2, atol=1e-6)


def _scene(tmp_path, image="colour.png"):
    _images(tmp_path)
    spot = f"""<emitter type="spot"><spectrum name="intensity" value="4"/>
    <texture name="texture" type="bitmap"><string name="filename" value="{image}"/></texture>
    <float name="cutoff_angle" value="20"/><float name="beam_width" value="15"/>
    <transform name="to_world"><lookat origin="0, 0, 0" target="0.05, 0, 1" up="0, 1, 0"/>
    </transform>
  </emitter>"""
    return projected_image_scene(
        tmp_path / f"spot_{image}.xml", spot, '<integrator type="direct"/>'
    )


@pytest.mark.slow
def test_textured_spot_scene_passes_the_z_test_against_mitsuba(tmp_path):
    from ._mitsuba import z_test_against_mitsuba

    res = z_test_against_mitsuba(_scene(tmp_path), spp=64, ref_spp=1024)
    assert res.passed, res.message


@pytest.mark.slow
def test_a_mirrored_spot_texture_fails_the_z_test(tmp_path):
    from ._mitsuba import z_test_against_mitsuba

    mirrored = _scene(tmp_path, "mirrored.png")
    res = z_test_against_mitsuba(_scene(tmp_path), spp=64, ref_spp=1024, ours_path=mirrored)
    assert not res.passed, res.message


def test_a_spot_texture_that_is_no_bitmap_is_refused(tmp_path):
    path = tmp_path / "bad.xml"
    spot = '<emitter type="spot">\n<texture name="texture" type="checkerboard"/>\n</emitter>'
    path.write_text(f'<scene version="3.0.0">\n{spot}\n</scene>')
    with pytest.raises(SceneError, match="must be a bitmap texture"):
        load_scene(path)
