"""Mesh files and the Mitsuba 3 XML subset, checked against Mitsuba itself."""

import json
import textwrap
from pathlib import Path

import numpy as np
import pytest

import radiometria.render as rr
from radiometria.radiometry import BlackbodySpectrum
from radiometria.render import LinearRGB, SceneError, load_mesh, load_mitsuba_xml, load_scene
from radiometria.render._scenes._json import load_json

SCENE = """\
<scene version="3.0.0">
  <default name="spp" value="16"/>
  <integrator type="path"><integer name="max_depth" value="6"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <string name="fov_axis" value="y"/>
    <transform name="to_world"><lookat origin="0, 1, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    <film type="hdrfilm">
      <integer name="width" value="64"/><integer name="height" value="48"/>
      <rfilter type="tent"/>
    </film>
  </sensor>
  <bsdf type="twosided" id="gray">
    <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.3, 0.4"/></bsdf>
  </bsdf>
  <shape type="rectangle" id="floor">
    <transform name="to_world">
      <scale value="2"/><rotate x="1" angle="-90"/><translate y="-1"/>
    </transform>
    <ref id="gray"/>
  </shape>
  <shape type="cube" id="box">
    <transform name="to_world">
      <scale x="0.3" y="0.5" z="0.2"/><rotate y="1" angle="30"/><translate value="0.2 -0.5 0.1"/>
    </transform>
    <bsdf type="roughconductor">
      <string name="material" value="Au"/><float name="alpha" value="0.2"/>
    </bsdf>
  </shape>
  <shape type="obj" id="mesh">
    <string name="filename" value="tet.obj"/>
    <transform name="to_world"><translate x="-0.5"/></transform>
    <bsdf type="dielectric"><float name="int_ior" value="1.5"/></bsdf>
  </shape>
  <shape type="rectangle" id="light">
    <transform name="to_world">
      <matrix value="0.3 0 0 0  0 0 0.3 0.9  0 -0.3 0 0  0 0 0 1"/>
    </transform>
    <emitter type="area">
      <spectrum name="radiance" type="blackbody"><float name="temperature" value="4000"/></spectrum>
    </emitter>
  </shape>
</scene>
"""
TET = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


@pytest.fixture
def scene_file(tmp_path):
    (tmp_path / "tet.obj").write_text(TET)
    p = tmp_path / "scene.xml"
    p.write_text(SCENE)
    return p


def test_mitsuba_xml_loads_the_subset(scene_file):
    s = load_mitsuba_xml(scene_file)
    assert s.shape_names == ("floor", "box", "mesh", "light")
    assert s.n_triangles == 2 + 12 + 4 + 2
    gray, gold, glass, _ = s.materials
    assert gray.type == "diffuse" and gray.two_sided and gray.name == "gray"
    assert isinstance(gray.params["reflectance"], LinearRGB)
    np.testing.assert_allclose(gray.params["reflectance"].rgb, [0.2, 0.3, 0.4])
    assert gold.type == "roughconductor" and gold.params["material"] == "Au"
    assert gold.params["alpha"] == 0.2
    assert glass.type == "dielectric" and glass.params["int_ior"] == 1.5
    (light,) = s.emitters
    assert isinstance(light.radiance, BlackbodySpectrum)
    assert float(light.radiance.temperature) == 4000.0 and float(light.radiance.scale) == 1.0
    np.testing.assert_allclose(light.total_area, 0.36)
    # An emitter without a BSDF gets Mitsuba 3's default for emitters: black diffuse
    # (as mi.load_dict of an emitting rectangle shows: SmoothDiffuse, reflectance 0).
    assert s.face_material[s.face_shape == 3][0] == 3
    assert s.materials[3].params == {"reflectance": 0.0}
    assert (s.camera.fov_deg, s.camera.fov_axis) == (40.0, "y")
    assert (s.film.width, s.film.height, s.film.filter) == (64, 48, "tent")
    assert s.max_depth == 6 and s.spp == 16
    assert load_mitsuba_xml(scene_file, params={"spp": 4}).spp == 4
    assert load_scene(scene_file).n_triangles == s.n_triangles


def test_mitsuba_xml_triangles_match_mitsuba(scene_file):
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    ms = mi.load_file(str(scene_file), optimize=False)
    s = load_mitsuba_xml(scene_file)
    for shape in ms.shapes():
        v = np.array(shape.vertex_positions_buffer()).reshape(-1, 3)
        f = np.array(shape.faces_buffer()).reshape(-1, 3)
        ours = s.vertices[s.faces[s.face_shape == s.shape_names.index(shape.id())]]
        # same triangles in the same order, same winding
        np.testing.assert_allclose(ours, v[f], atol=1e-6, err_msg=shape.id())
    cam = np.array(mi.traverse(ms.sensors()[0])["to_world"].matrix)
    np.testing.assert_allclose(s.camera.to_world, cam, atol=1e-6)


def _dict_to_xml(d: dict) -> str:
    """The XML of Mitsuba's `cornell_box()` dict (the subset it uses)."""

    def matrix(t):
        m = np.array(t.matrix).ravel()
        return f'<transform name="to_world"><matrix value="{" ".join(map(repr, m.tolist()))}"/></transform>'  # noqa: E501

    def rgb(name, spec):
        return f'<rgb name="{name}" value="{", ".join(map(str, spec["value"]))}"/>'

    out = ['<scene version="3.0.0">']
    for key, val in d.items():
        if not isinstance(val, dict):
            continue
        t = val["type"]
        if t == "path":
            out.append(
                f'<integrator type="path"><integer name="max_depth" value="{val["max_depth"]}"/></integrator>'  # noqa: E501
            )
        elif t == "diffuse":
            out.append(
                f'<bsdf type="diffuse" id="{key}">{rgb("reflectance", val["reflectance"])}</bsdf>'
            )
        elif t == "perspective":
            film = val["film"]
            out.append(
                f'<sensor type="perspective"><float name="fov" value="{val["fov"]}"/>'
                f'<string name="fov_axis" value="{val["fov_axis"]}"/>{matrix(val["to_world"])}'
                f'<film type="hdrfilm"><integer name="width" value="{film["width"]}"/>'
                f'<integer name="height" value="{film["height"]}"/><rfilter type="gaussian"/></film>'  # noqa: E501
                "</sensor>"
            )
        elif t in ("rectangle", "cube"):
            body = matrix(val["to_world"]) + f'<ref id="{val["bsdf"]["id"]}"/>'
            if "emitter" in val:
                body += (
                    f'<emitter type="area">{rgb("radiance", val["emitter"]["radiance"])}</emitter>'
                )
            out.append(f'<shape type="{t}" id="{key}">{body}</shape>')
    return "\n".join(out + ["</scene>"])


def test_mitsuba_cornell_box_dict_matches_our_json(tmp_path):
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    p = tmp_path / "cbox.xml"
    p.write_text(_dict_to_xml(mi.cornell_box()))
    xml, ref = load_mitsuba_xml(p), load_scene("cornell-box")
    assert xml.shape_names == ref.shape_names and xml.n_triangles == ref.n_triangles
    for i, name in enumerate(ref.shape_names):
        a = np.unique(xml.vertices[xml.faces[xml.face_shape == i]].reshape(-1, 3).round(5), axis=0)
        b = np.unique(ref.vertices[ref.faces[ref.face_shape == i]].reshape(-1, 3).round(5), axis=0)
        np.testing.assert_allclose(a, b, atol=2e-5, err_msg=name)
        # same orientation: the summed normals agree
        na = np.cross(
            *np.swapaxes(np.diff(xml.vertices[xml.faces[xml.face_shape == i]], axis=1), 0, 1)
        )
        nb = np.cross(
            *np.swapaxes(np.diff(ref.vertices[ref.faces[ref.face_shape == i]], axis=1), 0, 1)
        )
        np.testing.assert_allclose(na.sum(0), nb.sum(0), atol=1e-5, err_msg=name)
    assert [m.name for m in xml.materials] == ["white", "green", "red"]
    np.testing.assert_allclose(xml.emitters[0].total_area, ref.emitters[0].total_area, rtol=1e-6)
    np.testing.assert_allclose(xml.camera.to_world, ref.camera.to_world, atol=1e-6)
    assert (xml.camera.fov_deg, xml.camera.fov_axis, xml.max_depth) == (39.3077, "smaller", 8)
    assert xml.film.filter_params == ref.film.filter_params


def _write(tmp_path, body: str):
    p = tmp_path / "bad.xml"
    p.write_text(textwrap.dedent(body))
    return p


@pytest.mark.parametrize(
    "body, match",
    [
        ('<scene>\n  <shape type="rectangle">\n    <texture type="bitmap"/>\n  </shape>\n</scene>',
         r"bad.xml:3: <texture>: missing attribute 'name'"),
        ('<scene>\n\n  <emitter type="sunsky"/>\n</scene>', r"bad.xml:3: .*unsupported emitter \(outside a <shape>\) type 'sunsky'"),  # noqa: E501
        ('<scene>\n  <volume/>\n</scene>', r"bad.xml:2: .*unsupported tag <volume>"),
        ('<scene>\n  <bsdf type="pplastic"/>\n</scene>', r"bad.xml:2: .*unsupported BSDF type 'pplastic'"),  # noqa: E501
        ('<scene>\n  <shape type="cube">\n   <float name="radius" value="1"/>\n  </shape>\n</scene>',  # noqa: E501
         r"bad.xml:3: .*unsupported parameter 'radius'"),
        ('<scene>\n  <shape type="cube">\n  </shap>\n</scene>', r"bad.xml:3:\d+: malformed XML"),
        ('<scene>\n  <shape type="cube"><ref id="nope"/></shape>\n</scene>', r"bad.xml:2: .*unknown id 'nope'"),  # noqa: E501
        ('<scene>\n  <sensor type="perspective"><float name="fov" value="$f"/></sensor>\n</scene>',
         r"bad.xml:2: .*no value for the parameter"),
        ('<scene>\n  <shape type="obj"><string name="filename" value="missing.obj"/></shape>\n</scene>',  # noqa: E501
         r"missing.obj"),
        ('<scene>\n <shape type="rectangle" id="lamp">\n  <transform name="to_world"><scale x="0"/></transform>\n'  # noqa: E501
         '  <emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter>\n </shape>\n</scene>',  # noqa: E501
         r"bad.xml:2: shape 'lamp'.*zero area"),
    ],
)  # fmt: skip
def test_mitsuba_xml_errors_name_file_and_line(tmp_path, body, match):
    with pytest.raises((SceneError, FileNotFoundError), match=match):
        load_mitsuba_xml(_write(tmp_path, body))


def test_mitsuba_xml_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.xml"):
        load_mitsuba_xml(tmp_path / "nope.xml")


@pytest.mark.parametrize("suffix", ["obj", "ply"])
def test_load_mesh_obj_and_ply(tmp_path, suffix):
    trimesh = pytest.importorskip("trimesh")
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.5]])
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    p = tmp_path / f"tet.{suffix}"
    trimesh.Trimesh(v, f, process=False).export(p)
    mesh = load_mesh(p)
    np.testing.assert_allclose(np.asarray(mesh.vertices), v)
    np.testing.assert_array_equal(np.asarray(mesh.faces), f)
    with pytest.raises(FileNotFoundError):
        load_mesh(tmp_path / f"none.{suffix}")
    bad = tmp_path / f"bad.{suffix}"
    bad.write_text("this is not a mesh\n")
    with pytest.raises(SceneError, match=f"bad.{suffix}"):
        load_mesh(bad)


def test_binary_scene_file_is_named(tmp_path):
    bad = tmp_path / "garbage.xml"
    bad.write_bytes(b"\xa6\x00\x01\xffbinary")
    with pytest.raises(SceneError, match=r"garbage\.xml: not UTF-8 text"):
        load_scene(bad)
    bad_json = tmp_path / "garbage.json"
    bad_json.write_bytes(b"\xa6\x00\x01\xffbinary")
    with pytest.raises(SceneError, match=r"garbage\.json: not UTF-8 text"):
        load_scene(bad_json)


@pytest.mark.parametrize(
    "value", ["1, -2, 1", "1, nan, 1", "400:0.5, 500:-0.1"], ids=["negative", "nan", "spectrum"]
)
def test_bad_emitter_radiance_names_file_line_and_parameter(tmp_path, value):
    tag = "spectrum" if ":" in value else "rgb"
    xml = (
        '<scene version="3.0.0">\n  <shape type="rectangle">\n'
        f'    <emitter type="area"><{tag} name="radiance" value="{value}"/></emitter>\n'
        "  </shape>\n</scene>"
    )
    path = tmp_path / "lamp.xml"
    path.write_text(xml)
    pattern = (
        r"lamp\.xml:3: (parameter 'radiance': .*finite and >= 0|<rgb name='radiance'>: non-fin)"
    )
    with pytest.raises(SceneError, match=pattern):
        load_scene(path)


def test_bad_json_reflectance_names_the_field(tmp_path):
    data = json.loads((Path(rr.__file__).parent / "data" / "cornell_box.json").read_text())
    name = next(iter(data["materials"]))
    key = next(k for k in data["materials"][name] if k != "type")
    data["materials"][name][key] = [0.5, -0.1, 0.2]
    path = tmp_path / "box.json"
    path.write_text(json.dumps(data))
    with pytest.raises(SceneError, match=rf"box\.json: field 'materials\.{name}\.{key}'"):
        load_scene(path)


def test_json_two_sided_material(tmp_path):
    """`"two_sided": true` makes a material two-sided (and is not read as a spectrum); a
    non-boolean value is refused by field."""
    data = json.loads((Path(rr.__file__).parent / "data" / "cornell_box.json").read_text())
    name = next(iter(data["materials"]))
    data["materials"][name]["two_sided"] = True
    path = tmp_path / "box.json"
    path.write_text(json.dumps(data))
    desc = load_json(path.read_text(), str(path))
    assert [m.two_sided for m in desc.materials if m.name == name] == [True]
    assert all(m.two_sided is False for m in desc.materials if m.name != name)
    assert "two_sided" not in next(m for m in desc.materials if m.name == name).params
    assert load_scene(path).n_triangles > 0
    data["materials"][name]["two_sided"] = "yes"
    path.write_text(json.dumps(data))
    with pytest.raises(SceneError, match=rf"materials\.{name}\.two_sided'.*true or false"):
        load_scene(path)


def test_degenerate_camera_transform_is_refused(tmp_path):
    xml = (
        '<scene version="3.0.0">\n  <sensor type="perspective">\n'
        '    <transform name="to_world"><scale z="0"/></transform>\n  </sensor>\n</scene>'
    )
    path = tmp_path / "cam.xml"
    path.write_text(xml)
    with pytest.raises(SceneError, match=r"cam\.xml:2: .*degenerate camera transform"):
        load_scene(path)


def test_parameter_of_the_wrong_kind_is_named(tmp_path):
    xml = (
        '<scene version="3.0.0">\n  <sensor type="perspective">\n'
        '    <film type="hdrfilm"><spectrum name="width" value="7"/></film>\n'
        "  </sensor>\n</scene>"
    )
    path = tmp_path / "film.xml"
    path.write_text(xml)
    with pytest.raises(SceneError, match=r"film\.xml:3: .*parameter 'width' must be an <integer>"):
        load_scene(path)


def test_xml_entity_expansion_bomb_is_refused(tmp_path):
    """A 'billion laughs' file fails fast with the file and line named (expat's amplification
    limit), without expanding 10^9 entities."""
    levels = ['<!ENTITY lol0 "lolololololololololol">'] + [
        f'<!ENTITY lol{i} "{f"&lol{i - 1};" * 10}">' for i in range(1, 10)
    ]
    xml = (
        '<?xml version="1.0"?>\n<!DOCTYPE lolz [\n' + "\n".join(levels) + "\n]>\n"
        '<scene version="3.0.0"><string name="x" value="&lol9;"/></scene>\n'
    )
    path = tmp_path / "bomb.xml"
    path.write_text(xml)
    with pytest.raises(SceneError, match=r"bomb\.xml:\d+:\d+: malformed XML: .*amplification"):
        load_scene(path)
