"""Media in Mitsuba 3 XML scenes: parsing, binding to shapes and the sensor, compiling, and
errors that name the file, the line and the parameter (thesis ch. 4 and 9)."""

import numpy as np
import pytest

from radiometria.render import SceneError, compile_scene, load_mitsuba_xml, render
from radiometria.render._media import HomogeneousMediumPlugin
from radiometria.render._spectral import tabulate_spectrum
from radiometria.upsampling import RGBAlbedoSpectrum, RGBUnboundedSpectrum

SCENE = """<scene version="3.0.0">
  <medium type="homogeneous" id="fog">
    <rgb name="sigma_t" value="{sigma_t}"/>
    <rgb name="albedo" value="{albedo}"/>
    <float name="scale" value="2"/>
    <phase type="hg"><float name="g" value="{g}"/></phase>
  </medium>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    <medium type="homogeneous"><float name="sigma_t" value="0.01"/>
      <float name="albedo" value="1"/></medium>
  </sensor>
  <integrator type="volpath"><integer name="max_depth" value="4"/></integrator>
  <shape type="cube">
    <bsdf type="null"/>
    <ref name="interior" id="fog"/>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><translate z="-3"/></transform>
    <emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter>
  </shape>
</scene>
"""


def _write(tmp_path, **kw):
    values = {"sigma_t": "0.5, 1.0, 1.5", "albedo": "0.8, 0.5, 0.2", "g": "0.3"}
    values.update(kw)
    path = tmp_path / "media.xml"
    path.write_text(SCENE.format(**values))
    return path


def test_media_are_loaded_bound_and_compiled(tmp_path):
    desc = load_mitsuba_xml(_write(tmp_path))
    assert [m.type for m in desc.media] == ["homogeneous", "homogeneous"]
    assert desc.integrator == "volpath"
    fog = desc.media[0]
    assert fog.params["scale"] == 2.0 and fog.params["g"] == pytest.approx(0.3)
    assert desc.camera_medium == 1
    cube = desc.face_shape == 0
    # the cube has an interior (fog) and, as in Mitsuba, a vacuum outside; the light bounds
    # no medium
    assert np.all(desc.face_interior[cube] == 0) and np.all(desc.face_exterior[cube] == -1)
    assert np.all(desc.face_interior[~cube] == -2) and np.all(desc.face_exterior[~cube] == -2)
    scene, _, _ = compile_scene(desc)
    (plugin,) = scene.media.plugins
    assert isinstance(plugin, HomogeneousMediumPlugin) and scene.camera_medium == 1
    # RGB sigma_t is an unbounded spectrum times scale; RGB albedo an albedo spectrum
    sigma = 2.0 * tabulate_spectrum(fog.params["sigma_t"], RGBUnboundedSpectrum)
    albedo = tabulate_spectrum(fog.params["albedo"], RGBAlbedoSpectrum)
    np.testing.assert_allclose(np.asarray(plugin.sigma_t.values[0]), sigma, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(plugin.albedo.values[0]), albedo, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(plugin.g), [0.3, 0.0], rtol=1e-6)
    np.testing.assert_allclose(np.asarray(plugin.sigma_t.values[1]), 0.01, rtol=1e-6)


@pytest.mark.parametrize(
    ("kw", "parameter", "line"),
    [
        ({"sigma_t": "-1, 1, 1"}, "sigma_t", 3),
        ({"sigma_t": "nan, 1, 1"}, "sigma_t", 3),
        ({"albedo": "0.5, 1.2, 0.5"}, "albedo", 4),
        ({"g": "1.0"}, "g", 6),
        ({"g": "-1.5"}, "g", 6),
    ],
)
def test_bad_medium_values_name_file_line_and_parameter(tmp_path, kw, parameter, line):
    path = _write(tmp_path, **kw)
    with pytest.raises(SceneError, match=rf"media\.xml:{line}:.*'{parameter}'"):
        load_mitsuba_xml(path)


def test_unknown_medium_reference_and_type_are_refused(tmp_path):
    path = tmp_path / "bad.xml"
    text = SCENE.format(sigma_t="1, 1, 1", albedo="0.5, 0.5, 0.5", g="0")
    path.write_text(text.replace('id="fog"/>', 'id="smoke"/>'))
    with pytest.raises(SceneError, match=r"bad\.xml:\d+:.*unknown medium id 'smoke'"):
        load_mitsuba_xml(path)
    path.write_text(text.replace('type="homogeneous" id="fog"', 'type="foggy" id="fog"'))
    with pytest.raises(SceneError, match=r"bad\.xml:2:.*unsupported medium type 'foggy'"):
        load_mitsuba_xml(path)


def test_media_scene_renders_through_the_driver(tmp_path):
    """The file's `volpath` integrator renders it through `render` (the driver's sampler
    variates): a finite, non-black image."""
    img = np.asarray(render(load_mitsuba_xml(_write(tmp_path)), spp=4, seed=0))
    assert img.shape == (8, 8, 3) and np.all(np.isfinite(img)) and img.max() > 0


def test_vol_files_written_by_mitsuba_are_read_in_its_layout(tmp_path):
    """Mitsuba 3's own VolumeGrid.write (x fastest, channels interleaved) is read back."""
    mi = pytest.importorskip("mitsuba")
    from radiometria.render._scenes._volume_files import read_vol

    mi.set_variant("scalar_spectral")
    data = np.random.default_rng(1).random((3, 4, 5, 3)).astype(np.float32)
    mi.VolumeGrid(data).write(str(tmp_path / "m.vol"))
    np.testing.assert_array_equal(read_vol(tmp_path / "m.vol"), data)


def _vol_bytes(tmp_path, mutate):
    import struct

    from radiometria.render._scenes._volume_files import write_vol

    path = tmp_path / "bad.vol"
    write_vol(path, np.ones((2, 2, 2)))
    b = bytearray(path.read_bytes())
    mutate(b, struct)
    path.write_bytes(bytes(b))
    return path


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda b, s: b.__setitem__(slice(0, 3), b"VOX"), "magic"),
        (lambda b, s: b.__setitem__(3, 2), "version 2"),
        (lambda b, s: b.__setitem__(slice(4, 8), s.pack("<i", 2)), "encoding 2"),
        (lambda b, s: b.__setitem__(slice(20, 24), s.pack("<i", 2)), "channel count 2"),
        (lambda b, s: b.__setitem__(slice(8, 12), s.pack("<i", 0)), r"xres = 0 outside"),
        (lambda b, s: b.__setitem__(slice(16, 20), s.pack("<i", 2**30)), "zres = 1073741824"),
        (lambda b, s: b.__setitem__(slice(8, 12), s.pack("<i", 3)), "the file has 80 bytes"),
        (lambda b, s: b.__delitem__(slice(60, None)), "the file has 60 bytes"),
        (lambda b, s: b.__delitem__(slice(20, None)), "truncated header"),
        (lambda b, s: b.__setitem__(slice(52, 56), s.pack("<f", float("nan"))), "nan"),
        (lambda b, s: b.__setitem__(slice(52, 56), s.pack("<f", -1.0)), r"-1\.0"),
    ],
)
def test_hostile_vol_files_are_scene_errors_naming_the_file(tmp_path, mutate, message):
    """Each bad .vol, referenced from a scene, is a SceneError naming the scene line, the
    file and the problem (sizes are checked before anything is allocated)."""
    vol = _vol_bytes(tmp_path, mutate)
    scene = tmp_path / "grid.xml"
    scene.write_text(
        '<scene version="3.0.0">\n<medium type="heterogeneous" id="m">\n'
        '<volume name="sigma_t" type="gridvolume">'
        f'<string name="filename" value="{vol.name}"/></volume></medium>\n</scene>\n'
    )
    with pytest.raises(SceneError, match=rf"grid\.xml:3: volume file .*bad\.vol.*{message}"):
        load_mitsuba_xml(scene)


def test_emitter_shapes_without_a_bsdf_get_mitsubas_default(tmp_path):
    """The default BSDF of a BSDF-less emitting shape and of a plain one, against what
    Mitsuba 3 instantiates for the same file."""
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_spectral")
    path = tmp_path / "defaults.xml"
    path.write_text(
        '<scene version="3.0.0">\n'
        '<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/>'
        "</emitter></shape>\n"
        '<shape type="rectangle"><transform name="to_world"><translate z="-1"/></transform>'
        "</shape>\n</scene>\n"
    )
    desc = load_mitsuba_xml(path)
    scene = mi.load_file(str(path))
    theirs = [
        float(np.mean(np.asarray(mi.traverse(s.bsdf())["reflectance.value"], np.float64)))
        for s in scene.shapes()
    ]
    ours = []
    for shape in range(2):
        face = int(np.flatnonzero(desc.face_shape == shape)[0])
        material = desc.materials[int(desc.face_material[face])]
        assert material.type == "diffuse"
        value = material.params["reflectance"]
        ours.append(float(np.mean(getattr(value, "rgb", value))))
    emits = [bool(s.is_emitter()) for s in scene.shapes()]
    assert sorted(zip(emits, theirs, strict=True)) == [(False, 0.5), (True, 0.0)]
    assert ours == [0.0, 0.5]
