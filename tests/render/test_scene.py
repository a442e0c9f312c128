"""Scene descriptions: the built-in Cornell boxes, our JSON format and its errors."""

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from radiometria.radiometry import PiecewiseLinearSpectrum
from radiometria.render import LinearRGB, SceneError, load_scene, triangle_normals

SHARED = Path(__file__).resolve().parents[3] / "shared"
DATA = Path(__file__).resolve().parents[2] / "radiometria" / "render" / "data"


# sha256 of the project's ../shared/ scene files (the CEO's data), so the packaged copies are
# checked even in a clone that has no shared/ beside it.
SHARED_SHA256 = {
    "cornell_box.json": "f81c468dea2b2b3dfa55bc289ce20ec26407b7bb1ddacec52f9556667b7541ec",
    "cornell_box_measured.json": "6ea8bfe5aa10af34ed8939e583eacaddb5b280b5a97efef0c138490657a248b0",
}


@pytest.mark.parametrize("name", sorted(SHARED_SHA256))
def test_packaged_data_is_the_shared_data(name):
    packaged = (DATA / name).read_bytes()
    assert hashlib.sha256(packaged).hexdigest() == SHARED_SHA256[name]
    if (SHARED / name).exists():
        assert packaged == (SHARED / name).read_bytes()


def test_cornell_box_builtin():
    s = load_scene("cornell-box")
    assert s.n_triangles == 36 and len(s.vertices) == 4 * 6 + 8 * 2
    assert [m.name for m in s.materials] == ["white", "green", "red"]
    assert all(m.type == "diffuse" and not m.two_sided for m in s.materials)
    red = s.materials[2].params["reflectance"]
    assert isinstance(red, LinearRGB)
    np.testing.assert_allclose(red.rgb, [0.570068, 0.0430135, 0.0443706])
    (light,) = s.emitters
    np.testing.assert_allclose(light.total_area, 0.46 * 0.38, rtol=1e-6)
    assert isinstance(light.radiance, LinearRGB)
    np.testing.assert_allclose(light.radiance.rgb, [18.387, 13.9873, 6.75357])
    assert np.all(s.face_emitter[light.triangles] == 0) and np.sum(s.face_emitter >= 0) == 2
    n = np.asarray(triangle_normals(s.vertices, s.faces[light.triangles]))
    np.testing.assert_allclose(n, [[0, -1, 0]] * 2, atol=1e-7)  # the light faces down
    np.testing.assert_allclose(s.camera.origin, [0, 0, 3.9], rtol=1e-7)
    np.testing.assert_allclose(s.camera.direction, [0, 0, -1], atol=1e-7)
    assert s.camera.fov_deg == 39.3077 and s.camera.fov_axis == "smaller"
    assert (s.film.width, s.film.height, s.film.filter) == (256, 256, "gaussian")
    assert s.film.filter_params == {"stddev": 0.5, "radius": 2.0}
    assert s.max_depth == 8 and s.rr_depth == 5


def test_cornell_box_matches_mitsuba():
    """Each shape's vertices equal those of Mitsuba's own `cornell_box()` (up to ordering)."""
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    ms = mi.load_dict(mi.cornell_box(), optimize=False)  # no merging of shapes
    s = load_scene("cornell-box")
    for shape in ms.shapes():
        theirs = np.array(shape.vertex_positions_buffer()).reshape(-1, 3)
        i = s.shape_names.index(shape.id())
        ours = s.vertices[np.unique(s.faces[s.face_shape == i])]
        key = lambda a: a[np.lexsort(np.round(a, 5).T)]  # noqa: E731
        np.testing.assert_allclose(
            key(np.unique(ours.round(6), axis=0)),
            key(np.unique(theirs.round(6), axis=0)),
            atol=2e-6,
        )
    cam = np.array(mi.traverse(ms.sensors()[0])["to_world"].matrix)
    np.testing.assert_allclose(s.camera.to_world, cam, atol=1e-6)


def test_cornell_box_measured_builtin():
    s = load_scene("cornell-box-measured")
    assert s.n_triangles == 2 * (6 + 5 + 5) and s.unit == "mm"
    assert [m.name for m in s.materials] == ["white", "green", "red"]
    white = s.materials[0].params["reflectance"]
    assert isinstance(white, PiecewiseLinearSpectrum)
    wl, refl = np.asarray(white.wavelengths_nm), np.asarray(white.values)
    assert len(wl) == len(refl) == 76 and wl[0] == 400 and wl[-1] == 700
    (light,) = s.emitters
    np.testing.assert_allclose(light.total_area, 130.0 * 105.0)
    assert isinstance(light.radiance, PiecewiseLinearSpectrum)
    wl, val = light.radiance.wavelengths_nm, light.radiance.values
    np.testing.assert_allclose(wl, [400, 500, 600, 700])
    np.testing.assert_allclose(val, [0.0, 8.0, 15.6, 18.4])
    # the light sits just below the ceiling, facing down
    ly = s.vertices[s.faces[light.triangles]][..., 1]
    np.testing.assert_allclose(ly, 548.8 - 0.1)
    # every quad faces the interior: walls towards the room's centre, blocks outwards
    n = np.asarray(triangle_normals(s.vertices, s.faces))
    c = s.vertices[s.faces].mean(1)
    room = 0.5 * (s.vertices.min(0) + s.vertices.max(0))
    for i, name in enumerate(s.shape_names):
        sel = s.face_shape == i
        if "block" in name:
            want = c[sel] - s.vertices[s.faces[sel]].reshape(-1, 3).mean(0)
        else:
            want = room - c[sel]
        assert np.all(np.sum(n[sel] * want, axis=1) > 0), name
    # Looking along +z with up +y: left = up x dir = +x, so the rotation is the identity
    # (Mitsuba's look_at convention), and the translation is the camera position.
    expected = np.array(
        [[1.0, 0, 0, 278], [0, 1.0, 0, 273], [0, 0, 1.0, -800], [0, 0, 0, 1.0]], dtype=float
    )
    np.testing.assert_allclose(s.camera.to_world, expected, atol=1e-4)
    assert (s.film.width, s.film.height) == (512, 512)


def _box_json(tmp_path, edit=None, text=None):
    data = json.loads((DATA / "cornell_box.json").read_text())
    if edit is not None:
        edit(data)
    p = tmp_path / "scene.json"
    p.write_text(text if text is not None else json.dumps(data, indent=1))
    return p


def test_json_path_loads_like_the_builtin(tmp_path):
    a = load_scene(_box_json(tmp_path))
    b = load_scene("cornell-box")
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_array_equal(a.faces, b.faces)
    assert a.materials[0].name == "white" and a.source.endswith("scene.json")


def test_json_errors_name_the_file_and_field(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.json"):
        load_scene(tmp_path / "nope.json")
    with pytest.raises(ValueError, match="built-in"):
        load_scene("cornell-boxx")
    with pytest.raises(SceneError, match=r"scene.json:3:\d+: malformed JSON"):
        load_scene(_box_json(tmp_path, text='{\n "camera": {\n  "fov_deg": ,\n}'))
    with pytest.raises(SceneError, match=r"field 'camera': missing key 'fov_deg'"):
        load_scene(_box_json(tmp_path, lambda d: d["camera"].pop("fov_deg")))
    with pytest.raises(SceneError, match=r"field 'shapes\[1\].vertices'"):
        load_scene(_box_json(tmp_path, lambda d: d["shapes"][1].update(vertices=[[0, 1]])))
    with pytest.raises(SceneError, match=r"shapes\[2\].material.*'gold'"):
        load_scene(_box_json(tmp_path, lambda d: d["shapes"][2].update(material="gold")))
    with pytest.raises(SceneError, match=r"film.width"):
        load_scene(_box_json(tmp_path, lambda d: d["film"].update(width=-3)))


def test_degenerate_triangles_dropped_but_zero_area_lights_rejected(tmp_path):
    def add_degenerate(d):
        d["shapes"][1]["faces"].append([0, 0, 1])  # floor: a repeated index

    s = load_scene(_box_json(tmp_path, add_degenerate))
    assert s.n_triangles == 36

    def flat_light(d):
        d["shapes"][0]["vertices"][2] = [0.0, 0.99, -0.18]  # collinear with the first two

    with pytest.raises(SceneError, match="shape 'light'.*zero area"):
        load_scene(_box_json(tmp_path, flat_light))
