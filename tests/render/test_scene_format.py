"""The Mitsuba 3 scene format's structure: `<path>`, `<include>`, `<default>` and `$name`,
`<ref>`, ids, the `moment` wrapper; what the loader reads is checked against Mitsuba 3 reading
the same files where Mitsuba is installed."""

import numpy as np
import pytest

from radiometria.render import SceneError, load_scene
from radiometria.render._scenes._mitsuba_xml import load_mitsuba_xml

OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


def _scene(body: str, version: str = "3.0.0") -> str:
    return f'<scene version="{version}">\n{body}\n</scene>\n'


def _write(path, text):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


@pytest.fixture
def tree(tmp_path):
    """main.xml includes parts/materials.xml (which includes parts/deeper/light.xml) and finds
    `tri.obj` through a <path>; the included files name files relative to their own folder."""
    _write(tmp_path / "meshes" / "tri.obj", OBJ)
    _write(tmp_path / "parts" / "deeper" / "quad.obj", OBJ + "v 1 1 0\nf 2 4 3\n")
    _write(
        tmp_path / "parts" / "materials.xml",
        _scene(
            '<bsdf type="diffuse" id="red"><rgb name="reflectance" value="$red, 0.1, 0.1"/>'
            '</bsdf>\n<include filename="deeper/light.xml"/>'
        ),
    )
    _write(
        tmp_path / "parts" / "deeper" / "light.xml",
        _scene(
            '<shape type="obj" id="light"><string name="filename" value="quad.obj"/>'
            '<emitter type="area"><rgb name="radiance" value="$power"/></emitter></shape>'
        ),
    )
    return _write(
        tmp_path / "main.xml",
        _scene(
            '<default name="red" value="0.8"/>\n<default name="power" value="4"/>\n'
            '<default name="spp" value="8"/>\n<default name="kind" value="obj"/>\n'
            '<default name="fov" value="30"/>\n<default name="depth" value="3"/>\n'
            '<path value="meshes"/>\n<include filename="parts/materials.xml"/>\n'
            '<bsdf type="twosided" id="red2"><ref id="red"/></bsdf>\n'
            '<shape type="$kind" id="tri"><string name="filename" value="tri.obj"/>'
            '<ref id="red2"/></shape>\n'
            '<sensor type="perspective"><float name="fov" value="$fov"/>'
            '<sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>'
            '<film type="hdrfilm"><integer name="width" value="8"/>'
            '<integer name="height" value="8"/></film></sensor>\n'
            '<integrator type="moment"><integrator type="path">'
            '<integer name="max_depth" value="$depth"/></integrator></integrator>'
        ),
    )


def test_paths_includes_defaults_refs_and_moment(tree):
    s = load_scene(tree)
    assert s.shape_names == ("light", "tri")
    assert s.n_triangles == 3
    red, red2 = s.materials[0], s.materials[s.face_material[s.face_shape == 1][0]]
    np.testing.assert_allclose(red.params["reflectance"].rgb, [0.8, 0.1, 0.1])
    assert not red.two_sided and red2.two_sided and red2.params == red.params
    np.testing.assert_allclose(s.emitters[0].radiance.rgb, [4.0, 4.0, 4.0])
    assert (s.spp, s.camera.fov_deg, s.integrator, s.max_depth) == (8, 30.0, "path", 3)
    # values given by the caller (radiometria render -D) win over <default>, in included files too
    s = load_scene(tree, params={"red": 0.25, "spp": "2", "depth": 5})
    np.testing.assert_allclose(s.materials[0].params["reflectance"].rgb, [0.25, 0.1, 0.1])
    assert (s.spp, s.max_depth) == (2, 5)


def test_mitsuba_reads_the_same_tree(tree):
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    # Mitsuba instantiates shapes after parsing, with the main file's folder and the <path>
    # folders only: an included file's mesh must lie there for it (we also look beside the
    # including file first)
    (tree.parent / "meshes" / "quad.obj").write_text(OBJ + "v 1 1 0\nf 2 4 3\n")
    ms = mi.load_file(str(tree), red="0.25")
    ours = load_scene(tree, params={"red": "0.25"})
    assert sorted(sh.id() for sh in ms.shapes()) == sorted(ours.shape_names)
    for shape in ms.shapes():
        v = np.array(shape.vertex_positions_buffer()).reshape(-1, 3)
        f = np.array(shape.faces_buffer()).reshape(-1, 3)
        mine = ours.vertices[ours.faces[ours.face_shape == ours.shape_names.index(shape.id())]]
        np.testing.assert_allclose(mine, v[f], atol=1e-6)
    params = mi.traverse(ms)
    key = next(k for k in params.keys() if k.endswith("reflectance.value"))
    np.testing.assert_allclose(np.array(params[key]), [0.25, 0.1, 0.1], rtol=1e-6)
    assert ms.sensors()[0].sampler().sample_count() == ours.spp


def test_include_cycle_is_named(tmp_path):
    a = _write(tmp_path / "a.xml", _scene('<include filename="sub/b.xml"/>'))
    _write(tmp_path / "sub" / "b.xml", _scene('<include filename="../a.xml"/>'))
    with pytest.raises(SceneError, match=r"b\.xml:2: <include>: include cycle: .*a\.xml -> "):
        load_mitsuba_xml(a)
    self_loop = _write(tmp_path / "c.xml", _scene('<include filename="c.xml"/>'))
    with pytest.raises(SceneError, match="include cycle"):
        load_mitsuba_xml(self_loop)


@pytest.mark.parametrize(
    ("body", "error", "match"),
    [
        ('<include filename="missing.xml"/>', FileNotFoundError, "missing.xml"),
        ('<path value="no/such/folder"/>', SceneError, "search path"),
        ('<default name="x"/>', SceneError, "needs a 'name' and a 'value'"),
        ('<shape type="$nope"/>', SceneError, r":2: <shape>: no value for the parameter"),
        (
            '<bsdf type="diffuse" id="a"/><bsdf type="diffuse" id="a"/>',
            SceneError,
            "duplicate id 'a'",
        ),
        ('<shape type="cube"><ref id="ghost"/></shape>', SceneError, "unknown id 'ghost'"),
        (
            '<shape type="cube" id="c"/><shape type="cube"><ref id="c"/></shape>',
            SceneError,
            r"'c' \(the <shape> at .*\) cannot be referenced here; a <bsdf> is needed",
        ),
        (
            '<integrator type="moment"/>',
            SceneError,
            "exactly one nested <integrator>",
        ),
        ('<include filename="x.xml" extra="1"/>', SceneError, "unknown attribute 'extra'"),
    ],
)
def test_structure_errors_are_named(tmp_path, body, error, match):
    path = _write(tmp_path / "s.xml", _scene(body))
    with pytest.raises(error, match=match):
        load_mitsuba_xml(path)


def _box_xml(tmp_path):
    """A lit rectangle seen by a camera whose film width is the parameter $w."""
    return _write(
        tmp_path / "box.xml",
        _scene(
            '<default name="w" value="6"/>\n'
            '<sensor type="perspective"><float name="fov" value="60"/>'
            '<transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/>'
            '</transform><film type="hdrfilm"><integer name="width" value="$w"/>'
            '<integer name="height" value="2"/></film></sensor>\n'
            '<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/>'
            "</emitter></shape>"
        ),
    )


@pytest.mark.slow
def test_cli_define_sets_defaults(tmp_path, capsys):
    """`radiometria render SCENE -D name=value` overrides the file's <default>."""
    from radiometria.camera import read_exr
    from radiometria.cli import main

    scene, out = _box_xml(tmp_path), tmp_path / "img.exr"
    assert main(["render", str(scene), "--spp", "1", "--out", str(out), "-D", "w=3"]) == 0
    assert read_exr(out)[0].shape == (2, 3, 3)
    assert main(["render", str(scene), "--spp", "1", "--out", str(out), "-D", "w"]) == 2
    assert "-D expects NAME=VALUE" in capsys.readouterr().err
    argv = ["render", "cornell-box", "--spp", "1", "--out", str(out), "-D", "w=3"]
    assert main(argv) == 2
    assert "is not an .xml scene" in capsys.readouterr().err


def test_default_emission_is_mitsubas_d65_white(tmp_path):
    """An emitter without its radiance/intensity emits Mitsuba's default, white as an
    illuminant (D65, Y = 1), not an equal-energy spectrum (found by Mitsuba's own
    `orthographic_sensor/test_orthographic.xml`: X 5 % high, Z 8 % low before the fix)."""
    pytest.importorskip("mitsuba")
    from radiometria.render import render

    from ._mitsuba import mitsuba_moments

    path = _write(
        tmp_path / "sky.xml",
        _scene(
            '<emitter type="constant"/>\n<integrator type="path"/>\n'
            '<shape type="rectangle"><transform name="to_world"><translate z="-5"/>'
            "</transform></shape>\n"  # behind the camera: a scene needs a shape
            '<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>'
            '<integer name="height" value="8"/><rfilter type="box"/></film></sensor>'
        ),
    )
    spp, ref_spp = 64, 256
    mean, var = mitsuba_moments(path, ref_spp)
    ours = np.asarray(render(path, spp=spp, return_xyz=True, progress=False), np.float64)
    # the image means: standard error of both from Mitsuba's per-sample variance
    n = mean.shape[0] * mean.shape[1]
    se = np.sqrt(var.mean((0, 1)) / n * (1 / spp + 1 / ref_spp))
    diff = np.abs(ours.mean((0, 1)) - mean.mean((0, 1)))
    assert np.all(diff < 4 * se + 1e-3), (ours.mean((0, 1)), mean.mean((0, 1)), se)


@pytest.mark.parametrize("param", ['integer name="max_depth" value="0"',
                                   'integer name="rr_depth" value="-2"'])  # fmt: skip
def test_an_integrator_parameter_out_of_range_names_the_file_and_line(tmp_path, param):
    """The integrator's own range check (`max_depth >= 1`) is reported with the file and the
    line of the `<integrator>`, as every other scene error (found by the loader fuzz test)."""
    body = '<shape type="obj"><string name="filename" value="tri.obj"/></shape>\n'
    body += f'<integrator type="path">\n  <{param}/>\n</integrator>'
    _write(tmp_path / "tri.obj", OBJ)
    path = _write(tmp_path / "scene.xml", _scene(body))
    name = param.split('"')[1]
    with pytest.raises(SceneError, match=rf"scene\.xml:3: <integrator>: `{name}` must be an int"):
        load_scene(path)


@pytest.mark.parametrize("scale", ["1.5e154", "1e200"])
def test_a_transform_that_overflows_is_a_scene_error(tmp_path, scale):
    """A `to_world` whose lengths overflow float64 is refused with the file, the line and the
    parameter named, not a NumPy overflow warning (found by the loader fuzz test)."""
    body = f'<shape type="sphere"><transform name="to_world"><scale value="{scale}"/>'
    body += "</transform></shape>"
    path = _write(tmp_path / "scene.xml", _scene(body))
    with pytest.raises(SceneError, match=r"scene\.xml:2: shape 'sphere': parameter 'to_world'"):
        load_scene(path)
