"""Mesh attributes and Mitsuba's `mesh_attribute` texture (issue 12): PLY properties read
with Mitsuba's naming, per-vertex colours interpolated as spectra and per-face values, as
BSDF parameters, against Mitsuba 3 pixel by pixel; bad input named."""

from pathlib import Path

import numpy as np
import pytest

from radiometria.render import compile_scene, load_scene
from radiometria.render._scenes._description import SceneError
from radiometria.render._scenes._mesh_files import read_mesh
from radiometria.render._textures._mesh_attribute import corner_spectra

SIZE = 24


def _grid_ply(path: Path, *, n: int = 4, seed: int = 0, header_extra: str = "") -> dict:
    """An n x n vertex grid over [-1, 1]^2 at z = 0 (ASCII PLY) with a random colour per
    vertex (`color_0..2`, floats in [0.05, 0.95]), a random weight per face (`weight_0`), a
    1-channel `foo_0` per vertex and an unsuffixed `bar` (not an attribute, as in Mitsuba)."""
    rng = np.random.default_rng(seed)
    xs = np.linspace(-1.0, 1.0, n)
    x, y = np.meshgrid(xs, xs)
    v = np.stack([x.ravel(), y.ravel(), np.zeros(n * n)], axis=1)
    f = np.array(
        [[a, a + 1, a + n + 1] for j in range(n - 1) for a in range(j * n, j * n + n - 1)]
        + [[a, a + n + 1, a + n] for j in range(n - 1) for a in range(j * n, j * n + n - 1)]
    )
    color = rng.uniform(0.05, 0.95, (len(v), 3))
    foo = rng.uniform(0.0, 2.0, len(v))
    weight = rng.uniform(0.0, 1.0, len(f))
    head = ["ply", "format ascii 1.0", f"element vertex {len(v)}"]
    head += [f"property float {p}" for p in ("x", "y", "z", "color_0", "color_1", "color_2")]
    head += ["property float foo_0", "property float bar", f"element face {len(f)}"]
    head += ["property list uchar int vertex_indices", "property float weight_0", "end_header"]
    rows = [
        " ".join(f"{t:.9g}" for t in (*p, *c, s, 7.0))
        for p, c, s in zip(v, color, foo, strict=True)
    ]
    rows += [f"3 {a} {b} {c} {w:.9g}" for (a, b, c), w in zip(f, weight, strict=True)]
    path.write_text("\n".join(head + rows) + "\n")
    return {"v": v, "f": f, "color": color, "foo": foo, "weight": weight}


def _scene(left: str, right: str) -> str:
    """Two grids side by side under a constant sky: a diffuse one whose reflectance is
    `left`, and a blend of a red and a blue diffuse BSDF with weight `right`."""
    return f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="2"/></integrator>
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 5.5" target="0, 0, 0" up="0, 1, 0"/>
    </transform>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm"><integer name="width" value="{SIZE}"/>
      <integer name="height" value="{SIZE}"/><rfilter type="gaussian"/></film>
  </sensor>
  <emitter type="constant"><rgb name="radiance" value="1, 1, 1"/></emitter>
  <shape type="ply" id="left"><string name="filename" value="grid.ply"/>
    <transform name="to_world"><translate x="-1.05"/></transform>
    <bsdf type="diffuse">{left}</bsdf></shape>
  <shape type="ply" id="right"><string name="filename" value="grid.ply"/>
    <transform name="to_world"><translate x="1.05"/></transform>
    <bsdf type="blendbsdf">{right}
      <bsdf type="diffuse"><rgb name="reflectance" value="0.9, 0.2, 0.1"/></bsdf>
      <bsdf type="diffuse"><rgb name="reflectance" value="0.1, 0.3, 0.9"/></bsdf></bsdf></shape>
</scene>
"""


def _attr(param: str, name: str, scale: str = "") -> str:
    return (f'<texture type="mesh_attribute" name="{param}"><string name="name" value="{name}"/>'
            f"{scale}</texture>")  # fmt: skip


VERTEX_COLOR = _attr("reflectance", "vertex_color")
FACE_WEIGHT = _attr("weight", "face_weight")


def test_ply_attributes_follow_mitsubas_naming(tmp_path):
    """`<name>_<i>` properties are the channels of `<name>`, `r g b` (8-bit: divided by 255)
    are `color`, unsuffixed properties are no attribute; the 1-channel attributes equal
    what Mitsuba 3's own PLY reader gives."""
    data = _grid_ply(tmp_path / "grid.ply")
    _, _, _, _, attrs = read_mesh(tmp_path / "grid.ply", "", attributes=True)
    assert sorted(attrs) == ["face_weight", "vertex_color", "vertex_foo"]
    np.testing.assert_allclose(attrs["vertex_color"], data["color"], rtol=1e-7)
    np.testing.assert_allclose(attrs["vertex_foo"][:, 0], data["foo"], rtol=1e-7)
    np.testing.assert_allclose(attrs["face_weight"][:, 0], data["weight"], rtol=1e-7)
    rgb = tmp_path / "rgb.ply"
    rgb.write_text(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0 255 0 51\n1 0 0 0 255 0\n0 1 0 0 0 255\n3 0 1 2\n"
    )
    _, _, _, _, attrs = read_mesh(rgb, "", attributes=True)
    np.testing.assert_allclose(attrs["vertex_color"][0], [1.0, 0.0, 0.2])
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_spectral")
    params = mi.traverse(mi.load_dict({"type": "ply", "filename": str(tmp_path / "grid.ply")}))
    np.testing.assert_allclose(np.asarray(params["vertex_foo"]), data["foo"], rtol=1e-6)
    np.testing.assert_allclose(np.asarray(params["face_weight"]), data["weight"], rtol=1e-6)


@pytest.mark.slow
def test_mesh_attribute_textures_match_mitsuba(tmp_path):
    """Vertex colours as a diffuse reflectance (the corners' spectra interpolated with the
    hit's barycentrics) and a face weight as a blend weight (a scalar parameter), against
    Mitsuba 3 `scalar_spectral` by the per-pixel z-test; the same grids with constant
    parameters fail it."""
    pytest.importorskip("mitsuba")
    from ._mitsuba import z_test_against_mitsuba

    _grid_ply(tmp_path / "grid.ply")
    path, plain = tmp_path / "scene.xml", tmp_path / "plain.xml"
    path.write_text(_scene(VERTEX_COLOR, FACE_WEIGHT))
    plain.write_text(
        _scene('<rgb name="reflectance" value="0.5"/>', '<float name="weight" value="0.5"/>')
    )
    res = z_test_against_mitsuba(path, spp=64, ref_spp=512)
    assert res.passed, res.message
    res = z_test_against_mitsuba(path, spp=64, ref_spp=512, ours_path=plain)
    assert not res.passed, res.message


def test_mesh_attribute_spectra_and_scale(tmp_path):
    """A hit's reflectance is sum_i b_i S(c_i) of its triangle's corners (thesis eq. 2.27),
    times `scale`: checked at the corners and the centroid of a triangle of the compiled
    scene, against the coefficient table's spectra of the file's colours."""
    import jax.numpy as jnp

    from radiometria.upsampling import get_lut, sigmoid_polynomial_jakob2019

    data = _grid_ply(tmp_path / "grid.ply")
    path = tmp_path / "scene.xml"
    path.write_text(_scene(_attr("reflectance", "vertex_color", '<float name="scale" '
                                 'value="0.5"/>'), FACE_WEIGHT))  # fmt: skip
    scene, _, _ = compile_scene(load_scene(path))
    assert scene.surface_width == 4 + 2 * 12  # u, v, b1, b2, two baked attributes
    face = 4
    wl = jnp.linspace(400.0, 700.0, 4, dtype=jnp.float32)[None, :]
    corners = data["color"][data["f"][face]]
    want = np.asarray(
        sigmoid_polynomial_jakob2019(get_lut("sRGB").coefficients(jnp.asarray(corners)), wl[0])
    )
    tex = scene.materials.plugins[0].reflectance
    for b, expected in (((0.0, 0.0), want[0]), ((1.0, 0.0), want[1]), ((0.0, 1.0), want[2]),
                        ((1 / 3, 1 / 3), want.mean(axis=0))):  # fmt: skip
        uv = jnp.concatenate(
            [jnp.zeros(2, jnp.float32), jnp.asarray(b, jnp.float32), scene.face_attributes[face]]
        )[None, :]
        got = np.asarray(tex(jnp.zeros(1, jnp.int32), wl, uv))[0]
        np.testing.assert_allclose(got, 0.5 * expected, rtol=2e-3, atol=1e-4)


def test_missing_attribute_names_the_shape_and_its_attributes(tmp_path):
    _grid_ply(tmp_path / "grid.ply")
    path = tmp_path / "scene.xml"
    path.write_text(_scene(_attr("reflectance", "vertex_colour"), FACE_WEIGHT))
    with pytest.raises(
        SceneError,
        match=r"shape 'left' .*'vertex_colour'.*does not have \(its attributes: face_weight, "
        r"vertex_color, vertex_foo\)",
    ):
        compile_scene(load_scene(path))


@pytest.mark.parametrize(
    "body,match",
    [
        (
            '<shape type="rectangle"><emitter type="area">'
            + _attr("radiance", "vertex_color")
            + "</emitter></shape>",
            r"scene.xml:\d+: .*mesh_attribute texture is not supported for parameter 'radiance'",
        ),
        (
            '<shape type="rectangle"><bsdf type="diffuse"><texture type="mesh_attribute" '
            'name="reflectance"><string name="name" value="color"/></texture></bsdf></shape>',
            r"scene.xml:\d+: .*starts with 'vertex_' or 'face_', got 'color'",
        ),
    ],
)
def test_bad_mesh_attribute_textures_are_refused(tmp_path, body, match):
    path = tmp_path / "scene.xml"
    path.write_text(f'<scene version="3.0.0">{body}</scene>')
    with pytest.raises(SceneError, match=match):
        load_scene(path)


def test_non_finite_attribute_and_bad_channel_count_are_refused(tmp_path):
    bad = tmp_path / "bad.ply"
    bad.write_text(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nproperty float foo_0\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n"
        "0 0 0 1\n1 0 0 nan\n0 1 0 2\n3 0 1 2\n"
    )
    with pytest.raises(SceneError, match=r"bad.ply.*'vertex_foo' has a non-finite value in row 1"):
        read_mesh(bad, "", attributes=True)
    with pytest.raises(ValueError, match="1 or 3 channels, got 2"):
        corner_spectra(np.zeros((2, 2)), "albedo")
