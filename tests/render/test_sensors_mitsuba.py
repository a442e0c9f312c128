"""The `orthographic` and `thinlens` sensors of a Mitsuba XML scene, against Mitsuba 3."""

import numpy as np
import pytest

from radiometria.camera import OrthographicCamera, ThinLensCamera
from radiometria.render._scenes._compile import scene_camera, scene_sampler
from radiometria.render._scenes._description import SceneError
from radiometria.render._scenes._mitsuba_xml import load_mitsuba_xml

from ._mitsuba import film_xml, floor_and_light_xml, mitsuba_moments, z_test_against_mitsuba

SIZE = 16

ORTHOGRAPHIC = """<sensor type="orthographic">
    <transform name="to_world"><scale x="1.6" y="1.6"/>
      <lookat origin="0.5, 1.5, 4" target="0, 0, 0" up="0, 1, 0"/></transform>"""
THINLENS = """<sensor type="thinlens">
    <float name="fov" value="50"/>
    <float name="aperture_radius" value="{radius}"/>
    <float name="focus_distance" value="{focus}"/>
    <transform name="to_world"><lookat origin="0, 0.6, 4.2" target="0, 0, 0" up="0, 1, 0"/>
    </transform>"""


def _xml(sensor: str, size: int = SIZE) -> str:
    """Three boxes at depths 2.6, 4.1 and 6.2 from the camera on a grey floor, lit by a
    rectangle light: depth of field blurs the near and far ones."""
    boxes = "".join(
        f'<shape type="cube"><transform name="to_world"><scale value="0.35"/>'
        f'<translate x="{x}" y="-0.65" z="{z}"/></transform>'
        f'<bsdf type="diffuse"><rgb name="reflectance" value="{rgb}"/></bsdf></shape>'
        for x, z, rgb in ((-0.9, 1.6, "0.8, 0.2, 0.1"), (0.1, 0.1, "0.2, 0.7, 0.2"),
                          (0.9, -2.0, "0.2, 0.3, 0.8"))
    )  # fmt: skip
    return f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  {sensor}
    {film_xml(size)}
  </sensor>
  {floor_and_light_xml(5, 5)}
  {boxes}
</scene>
"""


@pytest.mark.slow
@pytest.mark.parametrize("sensor", ["orthographic", "thinlens"])
def test_sensor_matches_mitsuba(tmp_path, sensor):
    """A 16 x 16 image through each sensor (the thin lens with a wide aperture, 0.6, that
    blurs the near and far boxes) rendered by Mitsuba 3 scalar_spectral (512 spp, moments) and
    by us (64 spp) passes the per-pixel z-test of Mitsuba's render suite."""
    text = ORTHOGRAPHIC if sensor == "orthographic" else THINLENS.format(radius=0.6, focus=4.1)
    path = tmp_path / "scene.xml"
    path.write_text(_xml(text))
    res = z_test_against_mitsuba(path, spp=64, ref_spp=512)
    assert res.passed, res.message


@pytest.mark.slow
def test_pinhole_fails_against_mitsubas_thin_lens(tmp_path):
    """The z-test can fail: our render with a pinhole (aperture 0) against Mitsuba's thin
    lens with a wide aperture (0.6) focused at 1.5, which blurs the whole scene."""
    from radiometria.montecarlo import pixel_z_test
    from radiometria.render import render

    lens, pinhole = tmp_path / "lens.xml", tmp_path / "pinhole.xml"
    lens.write_text(_xml(THINLENS.format(radius=0.6, focus=1.5)))
    pinhole.write_text(_xml(THINLENS.format(radius=0.0, focus=4.1)))
    mean, var = mitsuba_moments(lens, 512, seed=1)
    ours = np.asarray(render(pinhole, spp=64, return_xyz=True, progress=False), np.float64)
    res = pixel_z_test(ours, mean, var, 64, 512)
    assert not res.passed, res.message


def test_loader_builds_the_sensors(tmp_path):
    """The loader maps `orthographic` and `thinlens` to our cameras with their parameters."""
    path = tmp_path / "s.xml"
    path.write_text(_xml(THINLENS.format(radius=0.125, focus=4.1)))
    cam = scene_camera(load_mitsuba_xml(path))
    assert isinstance(cam, ThinLensCamera)
    assert float(cam.aperture_radius) == 0.125 and float(cam.focus_distance) == 4.1
    np.testing.assert_allclose(float(cam.fov_x_deg), 50.0)
    path.write_text(_xml(ORTHOGRAPHIC))
    cam = scene_camera(load_mitsuba_xml(path))
    assert isinstance(cam, OrthographicCamera)
    np.testing.assert_allclose(np.linalg.norm(np.asarray(cam.to_world)[:3, 0]), 1.6)


@pytest.mark.parametrize(
    ("sensor", "match"),
    [
        ('<sensor type="thinlens"><float name="fov" value="40"/>', "needs 'aperture_radius'"),
        ('<sensor type="thinlens"><float name="aperture_radius" value="-1"/>', "aperture_radius"),
        ('<sensor type="orthographic"><float name="fov" value="40"/>', "parameter 'fov'"),
        ('<sensor type="thinlens"><float name="aperture_radius" value="0.1"/>'
         '<float name="focus_distance" value="0"/>', "focus_distance"),
    ],
)  # fmt: skip
def test_loader_rejects_bad_sensors(tmp_path, sensor, match):
    """Each error names the file, the line and the parameter."""
    path = tmp_path / "bad.xml"
    path.write_text(_xml(sensor))
    with pytest.raises(SceneError, match=match) as err:
        load_mitsuba_xml(path)
    assert "bad.xml:3:" in str(err.value)


@pytest.mark.parametrize(
    ("name", "cls"),
    [("independent", "Independent"), ("stratified", "OwenSobol"), ("multijitter", "OwenSobol"),
     ("ldsampler", "OwenSobol"), ("sobol", "OwenSobol")],
)  # fmt: skip
def test_mitsuba_sampler_names(tmp_path, name, cls):
    """Each of Mitsuba's sampler names maps to a sampler of ours, with its sample_count."""
    path = tmp_path / "s.xml"
    path.write_text(_xml(ORTHOGRAPHIC).replace('"independent"><integer name="sample_count" '
                                               'value="16"', f'"{name}"><integer name='
                                               '"sample_count" value="12"'))  # fmt: skip
    desc = load_mitsuba_xml(path)
    assert desc.spp == 12
    assert type(scene_sampler(desc)).__name__ == cls


def test_unknown_sampler_is_refused(tmp_path):
    path = tmp_path / "bad.xml"
    path.write_text(_xml(ORTHOGRAPHIC).replace('"independent"', '"halton"'))
    with pytest.raises(SceneError, match="unsupported sampler type 'halton'.*line 6"):
        load_mitsuba_xml(path)


def test_render_uses_the_scenes_sampler(tmp_path):
    """A scene with `<sampler type="ldsampler">` renders with `OwenSobol`, bit-identical to
    passing it (the driver's default `Independent` gives other images)."""
    from radiometria.render import OwenSobol, render

    path = tmp_path / "s.xml"
    path.write_text(_xml(ORTHOGRAPHIC, size=8).replace('"independent"', '"ldsampler"'))
    kw = {"spp": 2, "progress": False}
    scene_default = np.asarray(render(path, **kw))
    np.testing.assert_array_equal(
        scene_default, np.asarray(render(path, sampler=OwenSobol(), **kw))
    )
