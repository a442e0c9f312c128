"""`radiometria render` and `radiometria lut check` on hostile input: one line on stderr that
names the file, exit status 2, no traceback. Covers meshes referenced by a scene, coefficient
tables, degenerate transforms, and negative or non-finite spectral values in every form the
XML and JSON readers accept. Every case fails while loading, before anything is compiled."""

import copy
import json
import re
from pathlib import Path

import pytest

import radiometria.render as rr
from radiometria import cli

XML = """<scene version="3.0.0">
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world">{cam}</transform>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
  </sensor>
  <shape type="{kind}">{mesh}
    <transform name="to_world">{tw}</transform>
    <bsdf type="diffuse">{refl}</bsdf>
  </shape>
  <shape type="rectangle">
    <emitter type="area">{rad}</emitter>
  </shape>
</scene>
"""
OK = {
    "cam": '<lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/>',
    "kind": "rectangle",
    "mesh": "",
    "tw": '<scale value="2"/>',
    "refl": '<rgb name="reflectance" value="0.5, 0.5, 0.5"/>',
    "rad": '<rgb name="radiance" value="1, 1, 1"/>',
}
BB = (
    '<spectrum name="radiance" type="blackbody">'
    '<float name="temperature" value="{t}"/>{s}</spectrum>'
)
NAN_MATRIX = '<matrix value="nan 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1"/>'
MESH = '<string name="filename" value="{}"/>'
# (case, XML fields, message after "FILE:LINE: ")
XML_CASES = [
    ("camera_singular", {"cam": '<scale value="0"/>'}, r"2: <sensor>: degenerate camera transform"),
    ("camera_nan", {"cam": NAN_MATRIX}, r"4: <matrix>: non-finite number"),
    ("shape_nan", {"tw": NAN_MATRIX}, r"8: <matrix>: non-finite number"),
    ("shape_overflow", {"tw": '<scale value="1e999"/>'}, r"8: <scale>: non-finite number"),
    (
        "rgb_negative",
        {"refl": '<rgb name="reflectance" value="-0.5, 0.5, 0.5"/>'},
        r"9: parameter 'reflectance': values must be finite and >= 0",
    ),
    (
        "rgb_nan",
        {"refl": '<rgb name="reflectance" value="nan, 0.5, 0.5"/>'},
        r"9: <rgb name='reflectance'>: non-finite number",
    ),
    (
        "float_negative",
        {"refl": '<float name="reflectance" value="-0.5"/>'},
        r"9: parameter 'reflectance': values must be finite and >= 0",
    ),
    (
        "spectrum_negative",
        {"refl": '<spectrum name="reflectance" value="-0.5"/>'},
        r"9: parameter 'reflectance': values must be",
    ),
    (
        "spectrum_list_inf",
        {"refl": '<spectrum name="reflectance" value="400:0.5, 700:inf"/>'},
        r"9: parameter 'reflectance': values must be",
    ),
    (
        "radiance_negative",
        {"rad": '<rgb name="radiance" value="-1, 1, 1"/>'},
        r"12: parameter 'radiance': values must be finite and >= 0",
    ),
    (
        "radiance_inf",
        {"rad": '<rgb name="radiance" value="inf, 1, 1"/>'},
        r"12: <rgb name='radiance'>: non-finite number",
    ),
    (
        "radiance_list_nan",
        {"rad": '<spectrum name="radiance" value="400:1, 700:nan"/>'},
        r"12: parameter 'radiance': values must be",
    ),
    (
        "blackbody_scale_negative",
        {"rad": BB.format(t=4000, s='<float name="scale" value="-1"/>')},
        r"12: parameter 'radiance': values must be",
    ),
    (
        "blackbody_scale_inf",
        {"rad": BB.format(t=4000, s='<float name="scale" value="inf"/>')},
        r"12: <float name='scale'>: non-finite",
    ),
    (
        "blackbody_temperature_negative",
        {"rad": BB.format(t=-4000, s="")},
        r"12: <spectrum name='radiance'>: a blackbody spectrum needs a temperature > 0",
    ),
    ("mesh_missing", {"kind": "obj", "mesh": MESH.format("absent.obj")}, r"7: mesh file not found"),
    (
        "mesh_index",
        {"kind": "obj", "mesh": MESH.format("bad.obj")},
        r"7: .*bad\.obj: line 9: face index 9 is outside",
    ),
    (
        "mesh_nan",
        {"kind": "obj", "mesh": MESH.format("nan.obj")},
        r"7: .*nan\.obj: line 2: vertex 2 has a non-finite",
    ),
    (
        "mesh_terabyte_ply",
        {"kind": "ply", "mesh": MESH.format("huge.ply")},
        r"7: .*huge\.ply: header line 3 declares 1,000,000,000,000 'vertex'",
    ),
    (
        "mesh_garbage",
        {"kind": "obj", "mesh": MESH.format("garbage.obj")},
        r"7: .*garbage\.obj: binary data",
    ),
]
TET = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
MESH_FILES = {
    "bad.obj": (TET + "f 1 2 9\n").encode(),
    "nan.obj": TET.replace("v 1 0 0", "v nan 0 0").encode(),
    "garbage.obj": bytes(range(256)),
    "huge.ply": b"ply\nformat ascii 1.0\nelement vertex 1000000000000\nproperty float x\n"
    b"property float y\nproperty float z\nend_header\n0 0 0\n",
}


def _run(argv, capsys) -> str:
    status = cli.main(["--no-cache", *argv])
    err = capsys.readouterr().err.strip()
    assert status == 2, (status, err)
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert err.startswith("radiometria: error: "), err
    return err


@pytest.mark.parametrize("case,fields,message", XML_CASES, ids=[c[0] for c in XML_CASES])
def test_render_hostile_xml_scene_prints_one_line(tmp_path, capsys, case, fields, message):
    for name, data in MESH_FILES.items():
        (tmp_path / name).write_bytes(data)
    scene = tmp_path / f"{case}.xml"
    scene.write_text(XML.format(**{**OK, **fields}))
    err = _run(["render", str(scene), "--spp", "1", "--out", str(tmp_path / "o.exr")], capsys)
    assert re.search(rf"{re.escape(str(scene))}:{message}", err), err
    assert not (tmp_path / "o.exr").exists()


def _cornell():
    return json.loads((Path(rr.__file__).parent / "data" / "cornell_box.json").read_text())


def _set(path, value):
    def edit(d):
        node = d
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value
        return d

    return edit


def _drop_to_world_and_set(key, value):
    """The camera from `origin`/`looks_towards`/`up` alone, with `key` replaced."""

    def edit(d):
        d["camera"].pop("to_world")
        d["camera"][key] = value
        return d

    return edit


JSON_CASES = [
    (
        "reflectance_negative",
        _set(("materials", "white", "reflectance_linear_srgb"), [-0.1, 0.5, 0.5]),
        r"reflectance_linear_srgb'?: values must be finite and >= 0",
    ),
    (
        "radiance_negative",
        _set(("shapes", 0, "emitter", "radiance_linear_srgb"), [-1, 1, 1]),
        r"radiance_linear_srgb'?: values must be finite and >= 0",
    ),
    (
        "radiance_object_negative",
        _set(
            ("shapes", 0, "emitter", "radiance_linear_srgb"),
            {"wavelengths_nm": [400, 700], "values": [1, -1]},
        ),
        r"radiance_linear_srgb'?: values must be finite and >= 0",
    ),
    (
        "radiance_overflow",
        _set(("shapes", 0, "emitter", "radiance_linear_srgb"), [1e999, 1, 1]),
        r"radiance_linear_srgb",
    ),
    ("vertex_index", _set(("shapes", 1, "faces"), [[0, 1, 9]]), r"outside"),
    (
        "camera_singular",
        _set(("camera", "to_world"), [[1, 0, 0, 0], [0, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]),
        r"camera\.to_world'?: degenerate camera transform",
    ),
    ("camera_up_parallel", _drop_to_world_and_set("up", [0, 0, -1]), r"degenerate camera"),
]


@pytest.mark.parametrize("case,edit,message", JSON_CASES, ids=[c[0] for c in JSON_CASES])
def test_render_hostile_json_scene_prints_one_line(tmp_path, capsys, case, edit, message):
    scene = tmp_path / f"{case}.json"
    scene.write_text(json.dumps(edit(copy.deepcopy(_cornell()))))
    err = _run(["render", str(scene), "--spp", "1", "--out", str(tmp_path / "o.exr")], capsys)
    assert str(scene) in err and re.search(message, err), err


@pytest.mark.parametrize(
    "name,data,message",
    [
        ("garbage.npz", b"\x00\xff" * 32, r"not a readable \.npz file"),
        ("garbage.coeff", b"\x00\xff" * 32, r"not an rgb2spec file"),
        ("huge.coeff", b"SPEC" + (10**6).to_bytes(4, "little"), r"outside \[2, 1024\]"),
    ],
)
def test_lut_check_hostile_table_prints_one_line(tmp_path, capsys, name, data, message):
    path = tmp_path / name
    path.write_bytes(data)
    err = _run(["lut", "check", str(path)], capsys)
    assert str(path) in err and re.search(message, err), err
