"""Mitsuba 3's shapes (issue 12): analytic shapes tessellated with Mitsuba's parametrisation,
OBJ/PLY vertex normals and uvs, `serialized` meshes, `shapegroup` + `instance`, and shading
normals, each checked against Mitsuba 3 itself: its ray intersections (uvs, shading normals)
and its renders (the per-pixel z-test of Mitsuba's render suite)."""

import zlib

import numpy as np
import pytest

from radiometria.render._scenes._description import SceneError
from radiometria.render._scenes._mitsuba_xml import load_mitsuba_xml
from radiometria.render._scenes._shapes import SPHERE_MAX_RADIAL_ERROR, sphere

from ._mitsuba import floor_and_light_xml, mitsuba, perspective_xml, z_test_against_mitsuba

SIZE = 16


def _xml(body: str, *, depth: int = 6, origin="0, 0.6, 4.2", size: int = SIZE) -> str:
    """A small scene: the shapes of `body` on a grey floor, lit by a rectangle light."""
    return f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="{depth}"/></integrator>
  {perspective_xml(origin, 45, size)}
  {floor_and_light_xml(4, 4)}
{body}
</scene>
"""


def _one_shape(tmp_path, body: str):
    path = tmp_path / "one.xml"
    path.write_text(f'<scene version="3.0.0">{body}</scene>')
    return path


ANALYTIC = {
    "rectangle": '<shape type="rectangle"><transform name="to_world"><rotate y="1" angle="20"/>'
    '<translate z="0.3"/></transform></shape>',
    "disk": '<shape type="disk"><transform name="to_world"><scale x="0.7" y="1.2"/>'
    '<rotate x="1" angle="-30"/></transform></shape>',
    "cube": '<shape type="cube"><transform name="to_world"><scale value="0.5"/>'
    '<rotate x="1" angle="35"/><rotate y="1" angle="20"/></transform></shape>',
    "cylinder": '<shape type="cylinder"><float name="radius" value="0.4"/>'
    '<point name="p0" value="-0.2, -0.5, 0.1"/><point name="p1" value="0.3, 0.6, -0.2"/></shape>',
    "sphere": '<shape type="sphere"><point name="center" value="0.1, 0.2, -0.3"/>'
    '<float name="radius" value="0.6"/><transform name="to_world"><scale value="1.3"/>'
    '<translate x="0.2"/></transform></shape>',
    "flipped sphere": '<shape type="sphere"><boolean name="flip_normals" value="true"/></shape>',
}


@pytest.mark.parametrize("name", list(ANALYTIC))
def test_analytic_shape_uvs_and_normals_match_mitsubas_intersections(tmp_path, name):
    """Rays aimed at the centroid of each of our triangles, along its interpolated normal,
    hit Mitsuba's analytic shape (or its cube mesh) where Mitsuba reports the same uv and
    shading normal as our interpolation (up to the tessellation's sag)."""
    mi = mitsuba()
    path = _one_shape(tmp_path, ANALYTIC[name])
    d = load_mitsuba_xml(path)
    scene = mi.load_file(str(path))
    f = d.faces[:: max(1, len(d.faces) // 200)]
    corners = d.vertices[f]
    c = corners.mean(axis=1)
    g = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    g /= np.linalg.norm(g, axis=1, keepdims=True)
    n = g if d.vertex_normals is None else d.vertex_normals[f].mean(axis=1)
    n = np.where(np.isnan(n), g, n)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    assert np.all(np.sum(n * g, axis=1) > 0.9)  # shading normals on the winding's side
    uv = d.vertex_uvs[f].mean(axis=1)
    for k in range(len(f)):
        si = scene.ray_intersect(mi.Ray3f(mi.Point3f(c[k] + 0.05 * g[k]), mi.Vector3f(-g[k])))
        assert si.is_valid()
        np.testing.assert_allclose(np.array(si.uv), uv[k], atol=4e-3)
        np.testing.assert_allclose(np.array(si.sh_frame.n), n[k], atol=4e-3)
        np.testing.assert_allclose(np.array(si.n), g[k], atol=0.05)


def test_sphere_tessellation_error_bound():
    """Every point of the sphere mesh lies within the documented radial error."""
    m = sphere()
    b = np.random.default_rng(0).dirichlet([1, 1, 1], size=(len(m.faces), 16))
    p = np.einsum("fsk,fkd->fsd", b, m.vertices[m.faces])
    err = 1.0 - np.linalg.norm(p, axis=-1)
    assert err.min() >= -1e-12 and err.max() <= SPHERE_MAX_RADIAL_ERROR


def _obj_sphere(path, rings=6, segments=12) -> None:
    """A coarse sphere as OBJ with vertex normals and uvs (Mitsuba's flipped v)."""
    m = sphere((0.0, 0.0, 0.0), 1.0, rings, segments)
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in m.vertices]
    lines += [f"vn {x:.9g} {y:.9g} {z:.9g}" for x, y, z in m.normals]
    lines += [f"vt {u:.9g} {1 - v:.9g}" for u, v in m.uvs]
    lines += ["f " + " ".join(f"{i + 1}/{i + 1}/{i + 1}" for i in tri) for tri in m.faces]
    path.write_text("\n".join(lines) + "\n")


def write_serialized(path, meshes, version: int = 4) -> None:
    """Mitsuba's serialized format (the layout documented in its serialized.cpp):
    `meshes` is a list of `(vertices, faces, normals | None, uvs | None)`."""
    out, offsets = b"", []
    for v, f, n, uv in meshes:
        offsets.append(len(out))
        flags = 0x1000 | (0x0001 if n is not None else 0) | (0x0002 if uv is not None else 0)
        body = np.uint32(flags).tobytes()
        if version == 4:
            body += b"mesh\x00"
        body += np.array([len(v), len(f)], "<u8").tobytes()
        for a in (v, n, uv):
            if a is not None:
                body += np.asarray(a, "<f4").tobytes()
        body += np.asarray(f, "<u4").tobytes()
        out += np.array([0x041C, version], "<u2").tobytes() + zlib.compress(body)
    out += np.array(offsets, "<u8" if version == 4 else "<u4").tobytes()
    out += np.uint32(len(meshes)).tobytes()
    path.write_bytes(out)


def _meshes_body(tmp_path) -> str:
    _obj_sphere(tmp_path / "ball.obj")
    coarse = sphere((0.0, 0.0, 0.0), 1.0, 5, 10)
    tri = (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float), np.array([[0, 1, 2]]), None, None)
    write_serialized(tmp_path / "two.serialized", [tri, (coarse.vertices, coarse.faces,
                                                         coarse.normals, coarse.uvs)])  # fmt: skip
    return """
  <shape type="obj"><string name="filename" value="ball.obj"/>
    <transform name="to_world"><scale value="0.45"/><translate x="-0.55" y="-0.3"/></transform>
    <bsdf type="roughconductor"><string name="material" value="Cu"/>
      <float name="alpha" value="0.15"/><string name="distribution" value="ggx"/></bsdf>
  </shape>
  <shape type="serialized"><string name="filename" value="two.serialized"/>
    <integer name="shape_index" value="1"/>
    <transform name="to_world"><scale value="0.4"/><translate x="0.55" y="-0.3"/></transform>
  </shape>
  <shape type="shapegroup" id="pair">
    <shape type="cube"><transform name="to_world"><scale value="0.15"/></transform>
      <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.3, 0.2"/></bsdf></shape>
    <shape type="cylinder"><float name="radius" value="0.08"/>
      <point name="p1" value="0, 0.5, 0"/></shape>
  </shape>
  <shape type="instance"><ref id="pair"/>
    <transform name="to_world"><translate x="-0.3" y="0.5" z="-0.5"/></transform></shape>
  <shape type="instance"><ref id="pair"/>
    <transform name="to_world"><rotate y="1" angle="40"/><translate x="0.4" y="0.5" z="-0.5"/>
    </transform></shape>
"""


SCENES = {
    "analytic": "\n".join(
        f'<shape type="{t}"><transform name="to_world"><scale value="{s}"/>'
        f'<rotate x="1" angle="{a}"/><rotate y="1" angle="25"/><translate x="{x}" y="{y}"/>'
        f"</transform>{extra}"
        "</shape>"
        for t, s, a, x, y, extra in [
            ("cube", 0.3, 30, -0.8, -0.6, ""),
            ("sphere", 0.4, 0, 0.0, -0.55, ""),
            ("cylinder", 0.3, -60, 0.8, -0.6, '<float name="radius" value="0.7"/>'),
            ("disk", 0.35, 20, -0.5, 0.4, ""),
            ("rectangle", 0.3, -20, 0.5, 0.4, ""),
        ]
    ),
    "specular spheres": """
  <shape type="sphere"><point name="center" value="-0.55, -0.4, 0"/>
    <float name="radius" value="0.5"/><bsdf type="dielectric"/></shape>
  <shape type="sphere"><point name="center" value="0.55, -0.4, 0"/>
    <float name="radius" value="0.5"/><bsdf type="conductor"/></shape>""",
}


@pytest.mark.parametrize("name", [*SCENES, "meshes"])
def test_shapes_pass_mitsubas_pixel_z_test(tmp_path, name):
    """A scene of the shapes (analytic shapes on a floor; a glass and a mirror sphere, where
    only exact shading normals reflect the light where Mitsuba's analytic sphere does; a
    coarse OBJ ball with vertex normals, a serialized mesh and two instances of a group)
    rendered by Mitsuba 3 scalar_spectral and by us passes the per-pixel z-test."""
    body = _meshes_body(tmp_path) if name == "meshes" else SCENES[name]
    path = tmp_path / "scene.xml"
    path.write_text(_xml(body))
    res = z_test_against_mitsuba(path, spp=64, ref_spp=512)
    assert res.passed, res.message


def test_flat_shading_of_a_coarse_ball_fails_the_z_test(tmp_path):
    """The same coarse OBJ ball with `face_normals` in our file only (flat facets, no
    shading normals) fails against Mitsuba's smooth one: the test can fail."""
    from radiometria.montecarlo import pixel_z_test
    from radiometria.render import render

    from ._mitsuba import mitsuba_moments

    _obj_sphere(tmp_path / "ball.obj", 4, 8)
    ball = (
        '<shape type="obj"><string name="filename" value="ball.obj"/>{}'
        '<transform name="to_world"><scale value="0.8"/></transform>'
        '<bsdf type="conductor"/></shape>'
    )
    good, flat = tmp_path / "smooth.xml", tmp_path / "flat.xml"
    good.write_text(_xml(ball.format(""), depth=3, size=16))
    flat.write_text(_xml(ball.format('<boolean name="face_normals" value="true"/>'), depth=3,
                         size=16))  # fmt: skip
    mean, var = mitsuba_moments(good, 512, seed=1)
    ours = np.asarray(render(flat, spp=64, return_xyz=True, progress=False), np.float64)
    res = pixel_z_test(ours, mean, var, 64, 512)
    assert not res.passed, res.message


# ---------------------------------------------------------------------------------------------
# Loader behaviour and bad input


def test_obj_and_ply_keep_normals_and_uvs(tmp_path):
    """File normals and uvs reach the description (OBJ's v flipped, as Mitsuba's default);
    without file normals a mesh gets Mitsuba's angle-weighted vertex normals; `face_normals`
    drops them."""
    mi = mitsuba()
    (tmp_path / "t.obj").write_text(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 4 2\n"
    )  # fmt: skip
    xml = '<shape type="obj"><string name="filename" value="t.obj"/>{}</shape>'
    d = load_mitsuba_xml(_one_shape(tmp_path, xml.format("")))
    ref = mi.load_dict({"type": "obj", "filename": str(tmp_path / "t.obj")})
    np.testing.assert_allclose(
        d.vertex_normals, np.array(ref.vertex_normals_buffer()).reshape(-1, 3), atol=1e-6
    )
    flat = '<boolean name="face_normals" value="true"/>'
    assert load_mitsuba_xml(_one_shape(tmp_path, xml.format(flat))).vertex_normals is None
    (tmp_path / "n.ply").write_text(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
        "property float u\nproperty float v\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n"
        "0 0 0 0 0.6 0.8 0 0\n1 0 0 0 0 1 1 0\n0 1 0 0 0 2 0.25 1\n3 0 1 2\n"
    )
    d = load_mitsuba_xml(_one_shape(tmp_path, '<shape type="ply"><string name="filename" '
                                    'value="n.ply"/></shape>'))  # fmt: skip
    ref = mi.load_dict({"type": "ply", "filename": str(tmp_path / "n.ply")})
    np.testing.assert_allclose(
        d.vertex_normals, np.array(ref.vertex_normals_buffer()).reshape(-1, 3), atol=1e-6
    )
    np.testing.assert_allclose(
        d.vertex_uvs, np.array(ref.vertex_texcoords_buffer()).reshape(-1, 2), atol=1e-6
    )
    _obj_sphere(tmp_path / "ball.obj", 3, 6)  # Mitsuba orders vertices its own way
    d = load_mitsuba_xml(_one_shape(tmp_path, xml.replace("t.obj", "ball.obj").format("")))
    ref = mi.load_dict({"type": "obj", "filename": str(tmp_path / "ball.obj")})
    rf = np.array(ref.faces_buffer()).reshape(-1, 3)
    for ours, theirs, k in ((d.vertex_uvs, ref.vertex_texcoords_buffer(), 2),
                            (d.vertex_normals, ref.vertex_normals_buffer(), 3)):  # fmt: skip
        np.testing.assert_allclose(ours[d.faces], np.array(theirs).reshape(-1, k)[rf], atol=1e-6)


@pytest.mark.parametrize(
    "body,message",
    [
        ('<shape type="sphere"><float name="radius" value="-1"/></shape>', r"'radius' must be"),
        ('<shape type="cylinder"><float name="radius" value="0"/></shape>', r"'radius' must be"),
        ('<shape type="cylinder"><point name="p1" value="0,0,0"/></shape>', r"'p0' and 'p1'"),
        ('<shape type="cube"><transform name="to_world"><scale z="0"/></transform></shape>',
         r"'to_world'.*degenerate"),
        ('<shape type="rectangle"><transform name="to_world"><scale y="0"/></transform>'
         "</shape>", r"'to_world'.*degenerate"),
        ('<shape type="instance"><ref id="nope"/></shape>', r"no 'shapegroup' with id 'nope'"),
        ('<shape type="shapegroup" id="g"><shape type="cube"><emitter type="area">'
         '<rgb name="radiance" value="1"/></emitter></shape></shape>', r"cannot be emitters"),
        ('<shape type="disk"><float name="radius" value="2"/></shape>',
         r"unsupported parameter 'radius'"),
    ],
)  # fmt: skip
def test_bad_shapes_name_file_line_and_parameter(tmp_path, body, message):
    path = _one_shape(tmp_path, body)
    with pytest.raises(SceneError, match=message) as info:
        load_mitsuba_xml(path)
    assert str(info.value).startswith(f"{path}:1:"), info.value


def test_rectangle_with_scaled_z_is_fine(tmp_path):
    """A flat shape only needs its own two axes kept (Mitsuba's Cornell box scales z)."""
    body = '<shape type="rectangle"><transform name="to_world"><scale z="0"/></transform></shape>'
    assert load_mitsuba_xml(_one_shape(tmp_path, body)).n_triangles == 2


_C, _S = np.cos(np.pi / 6), np.sin(np.pi / 6)


@pytest.mark.parametrize(
    ("transform", "linear", "translation"),
    [
        ("", np.eye(3), np.zeros(3)),
        ('<scale value="2"/><rotate y="1" angle="30"/><translate x="1"/>',
         2.0 * np.array([[_C, 0, _S], [0, 1, 0], [-_S, 0, _C]]), np.array([1.0, 0, 0])),
        ('<scale x="2" y="1" z="1"/>', None, None),  # an ellipsoid: no true sphere
    ],
    ids=["plain", "similarity", "non-uniform scale"],
)  # fmt: skip
def test_an_emitting_sphere_keeps_its_true_sphere(tmp_path, transform, linear, translation):
    """A `sphere` emitter records the true sphere its triangles tessellate (for the cone
    sampling of its light samples), carried through `to_world` when that is a similarity;
    `flip_normals` (emitting inwards) drops it."""
    path = tmp_path / "s.xml"

    def load(flip=""):
        body = ('<shape type="sphere"><point name="center" value="0.5, 0, -1"/>'
                f'<float name="radius" value="0.8"/>{flip}'
                f'<transform name="to_world">{transform}</transform><emitter type="area">'
                '<rgb name="radiance" value="1"/></emitter></shape>')  # fmt: skip
        path.write_text(f'<scene version="3.0.0">{perspective_xml("0, 0, 5", 30, 8)}{body}</scene>')
        return load_mitsuba_xml(path)

    d = load()
    true_sphere = d.emitters[0].sphere
    if linear is None:
        assert true_sphere is None
        return
    center = linear @ np.array([0.5, 0.0, -1.0]) + translation
    np.testing.assert_allclose(true_sphere[0], center, atol=1e-12)
    assert true_sphere[1] == pytest.approx(0.8 * np.cbrt(np.linalg.det(linear)), rel=1e-12)
    tri = d.faces[d.emitters[0].triangles]  # the mesh's vertices lie on it
    r = np.linalg.norm(d.vertices[tri.ravel()] - true_sphere[0], axis=1)
    np.testing.assert_allclose(r, true_sphere[1], rtol=1e-12)
    assert load('<boolean name="flip_normals" value="true"/>').emitters[0].sphere is None
