"""Projectors (`projector`, issue 12): Mitsuba 3's projected image.

The emitted irradiance-like value towards points is compared with Mitsuba 3's own `projector`
emitter (`sample_direction`, `scalar_spectral`, at four wavelengths, for a plain RGB image and
a coloured bitmap of aspect 2), and a scene lit by a tilted projector with the per-pixel
z-test against Mitsuba 3 `scalar_spectral`, with a negative control (the image mirrored) that
must fail. The closed form of a constant image and the bad parameters are in `test_lights`.
"""

import numpy as np
import pytest
from PIL import Image

from radiometria.render import LinearRGB
from radiometria.render._lights import ProjectorLight
from radiometria.render._textures import TextureSpec, read_texture_image

from ._mitsuba import delta_light_values, projected_image_scene

mi = pytest.importorskip("mitsuba")
dr = pytest.importorskip("drjit")


def _images(tmp_path):
    rng = np.random.default_rng(0)
    colour = np.kron(rng.integers(0, 2, (2, 4, 3)) * 200 + 30, np.ones((2, 2, 1)))  # 8 x 4
    Image.fromarray(colour.astype(np.uint8)).save(tmp_path / "colour.png")
    Image.fromarray(colour[:, ::-1].astype(np.uint8)).save(tmp_path / "mirrored.png")


@pytest.mark.parametrize("textured", [False, True])
def test_projector_matches_mitsubas_projector(tmp_path, textured):
    """The value of next-event estimation (intensity / distance^2) towards random points, in
    and out of the image: pi, the 1/cos^3 profile, the uv orientation, the aspect ratio and the
    spectra (an RGB irradiance D65-shaped, texels as albedo spectra without D65)."""
    _images(tmp_path)
    mi.set_variant("scalar_spectral")
    to_world = mi.ScalarTransform4f().look_at(origin=[0.3, -0.2, 0.5], target=[0.5, 0.4, 3.0],
                                              up=[0.2, 1.0, 0.0])  # fmt: skip
    m = np.asarray(to_world.matrix, np.float64)
    matrix = " ".join(f"{x:.17g}" for x in m.ravel())
    png = tmp_path / "colour.png"
    irradiance = (
        f'<texture name="irradiance" type="bitmap"><string name="filename" value="{png}"/>'
        "</texture>"
        if textured
        else '<rgb name="irradiance" value="0.8, 0.5, 0.2"/>'
    )
    emitter = mi.load_string(f"""<emitter version="3.0.0" type="projector">
        <float name="scale" value="1.5"/><float name="fov" value="40"/>
        <transform name="to_world"><matrix value="{matrix}"/></transform>
        {irradiance}</emitter>""")
    value = (
        TextureSpec("bitmap", rgb=read_texture_image(png))
        if textured
        else LinearRGB(np.array([0.8, 0.5, 0.2]))
    )
    ours = ProjectorLight.from_properties(
        [{"irradiance": value, "scale": 1.5, "fov": 40.0, "to_world": m}], where=["test"]
    )
    expected, got = delta_light_values(emitter, ours, n=96)
    assert (expected[:, 1] > 0).sum() > 10 and (expected[:, 1] == 0).sum() > 10
    # Our sigmoid coefficients come from our own table, Mitsuba's from its: about 1 %.
    np.testing.assert_allclose(got, expected, rtol=2e-2, atol=1e-6)


def _scene(tmp_path, image="colour.png"):
    _images(tmp_path)
    projector = f"""<emitter type="projector"><float name="scale" value="2"/>
    <float name="fov" value="45"/>
    <texture name="irradiance" type="bitmap"><string name="filename" value="{image}"/>
    </texture>
    <transform name="to_world"><lookat origin="0.3, 0.1, 0" target="0.05, 0, 1" up="0, 1, 0"/>
    </transform>
  </emitter>"""
    integrator = '<integrator type="path"><integer name="max_depth" value="3"/></integrator>'
    return projected_image_scene(tmp_path / f"projector_{image}.xml", projector, integrator)


@pytest.mark.slow
def test_projector_scene_passes_the_z_test_against_mitsuba(tmp_path):
    from ._mitsuba import z_test_against_mitsuba

    res = z_test_against_mitsuba(_scene(tmp_path), spp=64, ref_spp=1024)
    assert res.passed, res.message


@pytest.mark.slow
def test_a_mirrored_projector_image_fails_the_z_test(tmp_path):
    from ._mitsuba import z_test_against_mitsuba

    mirrored = _scene(tmp_path, "mirrored.png")
    res = z_test_against_mitsuba(_scene(tmp_path), spp=64, ref_spp=1024, ours_path=mirrored)
    assert not res.passed, res.message
