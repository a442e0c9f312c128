"""Light tracing (`ptracer`): closed forms and agreement with the path tracer (issue 14)."""

import colour
import jax.numpy as jnp
import numpy as np
import pytest

from radiometria.camera import BoxFilter, PinholeCamera, write_exr
from radiometria.montecarlo import pixel_z_test
from radiometria.render import Path, RenderScene, compile_scene, load_scene, render
from radiometria.render._integrators import PTracer

from ._mitsuba import cornell_box_xml, mitsuba
from ._synthetic import constant_table, quad
from .test_envmap import (
    _bilinear_y,
    _directions,
    _envmap,
    _grey_map,
    _scene as _envmap_scene,
    _uv_grid,
)

LE = 2.0  # constant emitted spectral radiance: Y = LE


def _wall_scene_and_camera(size=8):
    """A camera at the origin looking along +z at an emitting quad at z = 2 that exactly
    fills its (square, 60 degree) field of view, the quad's normal towards the camera."""
    h = 2.0 * np.tan(np.radians(30.0))
    v, f = quad([[-h, -h, 2.0], [-h, h, 2.0], [h, h, 2.0], [h, -h, 2.0]])
    scene = RenderScene.from_triangles(
        v, f, np.zeros(2, int), constant_table(0.0), np.zeros(2, int), constant_table(LE)
    )
    normal = np.asarray(scene.normal[0])
    assert normal[2] < 0  # faces the camera
    camera = PinholeCamera.from_look_at(
        np.array([0.0, 0, 0]), np.array([0.0, 0, 1]), np.array([0.0, 1, 0]), 60.0, size, size
    )
    return scene, camera


def test_ptracer_emitter_seen_directly_closed_form():
    # Every light path's depth-0 splat carries L cos_l W_e cos_c / (d^2 p_A), which for a
    # plane facing the camera is the same for all points: the image sum is exact, and each
    # pixel's value is L times its share of the hits over its expected share (binomial),
    # up to the hero wavelengths' noise.
    scene, camera = _wall_scene_and_camera()
    spp = 64
    image = np.asarray(
        render(scene, camera=camera, spp=spp, integrator=PTracer(max_depth=1),
               rfilter=BoxFilter(), return_xyz=True, progress=False)
    )  # fmt: skip
    y = image[..., 1]
    np.testing.assert_allclose(y.mean(), LE, rtol=2e-3)
    # n_j ~ Binomial(N, 1/64) with mean spp = 64, sd 8: 7 sd is 0.875 of the mean
    assert np.all(np.abs(y / LE - 1.0) < 7 * 8 / 64)
    assert y.std() > 0  # light tracing is noisy here, unlike the path tracer
    path = np.asarray(
        render(scene, camera=camera, spp=4, integrator=Path(max_depth=1), rfilter=BoxFilter(),
               return_xyz=True, progress=False)
    )  # fmt: skip
    # (hero-wavelength noise only: Y = L in expectation)
    np.testing.assert_allclose(path[..., 1].mean(), LE, rtol=1e-2)
    np.testing.assert_allclose(path[..., 1], LE, rtol=0.1)


def test_ptracer_hide_emitters_and_bad_parameters():
    scene, camera = _wall_scene_and_camera(size=4)
    image = render(scene, camera=camera, spp=2, integrator=PTracer(max_depth=1, hide_emitters=True),
                   progress=False)  # fmt: skip
    assert float(jnp.max(jnp.abs(image))) == 0.0
    with pytest.raises(ValueError, match="max_depth"):
        PTracer(max_depth=0)
    with pytest.raises(ValueError, match="unknown ptracer parameter"):
        PTracer.from_properties({"max_depht": 3}, where="scene.xml")
    assert PTracer.from_properties({"max_depth": -1, "hide_emitters": True}).hide_emitters


def test_pinhole_importance_integrates_to_one():
    # int W_e cos dw over the film = 1: as the sum over a fine raster grid of the solid angle
    # of each cell (cos^3 / (d^2) dA on the plane at unit depth) times W_e cos.
    camera = PinholeCamera.from_look_at(
        np.array([0.0, 0, 0]), np.array([0.0, 0, 1]), np.array([0.0, 1, 0]), 50.0, 12, 8
    )
    n = 240
    x = (np.arange(n * 12 // 8 * 1) + 0.5) / (n * 12 // 8) * 12
    y = (np.arange(n) + 0.5) / n * 8
    raster = np.stack(np.meshgrid(x, y), axis=-1).reshape(-1, 2)
    o, d = camera.generate_ray(jnp.asarray(raster))
    s = camera.sample_wi(o + 3.0 * d)
    assert bool(jnp.all(s.valid))
    np.testing.assert_allclose(np.asarray(s.raster), raster, atol=1e-6)
    cos = np.asarray(d[:, 2])
    tan_x, tan_y = (float(t) for t in camera.tan_half_fov())
    cell = (2 * tan_x / x.size) * (2 * tan_y / y.size)  # area on the plane z = 1
    total = np.sum(np.asarray(s.importance) * cos * cos**3 * cell)
    np.testing.assert_allclose(total, 1.0, rtol=1e-6)
    # the pinhole's density per solid angle at the point: d^2 / cos
    np.testing.assert_allclose(np.asarray(s.pdf), 9.0 / cos, rtol=1e-6)


def _moments(integrator, seeds, spp, size, max_depth):
    images = np.stack([
        np.asarray(render("cornell-box", spp=spp, width=size, height=size, seed=s,
                          integrator=integrator, return_xyz=True, progress=False))
        for s in seeds
    ])  # fmt: skip
    return images.mean(axis=0), images.var(axis=0, ddof=1) / len(seeds)


@pytest.mark.slow
def test_ptracer_agrees_with_path_on_cornell_box():
    # Both estimates of the filtered pixel values (Gaussian filter, splatting) by independent
    # renders; the z-test's variance is that of the difference of the two means.
    size, spp, depth, n = 16, 16, 4, 6
    pt, var_pt = _moments(PTracer(max_depth=depth), range(n), spp, size, depth)
    ref, var_ref = _moments(Path(max_depth=depth), range(100, 100 + n), spp, size, depth)
    total = n * spp
    result = pixel_z_test(
        pt, ref, (var_pt + var_ref) * total, total, None, required_fraction=0.99,
        variance_floor=1e-8,
    )  # fmt: skip
    assert result.passed, result.message
    np.testing.assert_allclose(pt.mean(axis=(0, 1)), ref.mean(axis=(0, 1)), rtol=0.05)


def _cornell_light_luminance() -> float:
    """Y of the Cornell box light's radiance: its spectrum (as the compiled scene holds it)
    against colour-science's CIE 1931 y-bar, by 1 nm quadrature over 360-830 nm."""
    rs, _, _ = compile_scene(load_scene("cornell-box"), width=4, height=4)
    nm = np.arange(360.0, 831.0)
    le = np.asarray(rs.light.radiance(jnp.zeros(1, int), jnp.asarray(nm[None], jnp.float32)))
    ybar = (
        colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
        .align(colour.SpectralShape(360, 830, 1))
        .values[:, 1]
    )
    return float(np.sum(le[0] * ybar) / np.sum(ybar))


def _cornell_light_coverage(size: int) -> np.ndarray:
    """Area [px^2] of each pixel covered by the image of the Cornell box light (the quad
    |x| <= 0.23, y = 0.99, -0.18 <= z <= 0.2, seen from (0, 0, 3.9) along -z, fov 39.3077
    degrees on the square film), by exact perspective projection of its corners (a trapezoid
    with horizontal edges) and a fine quadrature in y."""
    t = np.tan(np.radians(39.3077 / 2))

    def raster(x, y, z):
        depth = 3.9 - z
        return size / 2 * (1 - x / (depth * t)), size / 2 * (1 - y / (depth * t))

    (xa, ya), (xb, yb) = raster(0.23, 0.99, -0.18), raster(0.23, 0.99, 0.2)
    n = 100_000
    s = (np.arange(n) + 0.5) / n
    ys = ya + s * (yb - ya)  # from the far edge (z = -0.18) to the near one
    half = np.abs(size / 2 - (xa + s * (xb - xa)))  # half-width of the light's image at ys
    lo, hi = size / 2 - half, size / 2 + half
    cols = np.arange(size)
    width = np.clip(np.minimum(hi[:, None], cols + 1) - np.maximum(lo[:, None], cols), 0, None)
    cover = np.zeros((size, size))
    np.add.at(cover, np.floor(ys).astype(int), width * abs(yb - ya) / n)
    return cover


def test_ptracer_cornell_light_pixels_closed_form():
    # max_depth 1 on the Cornell box (box filter): pixel j is Y(L) times the area of the
    # light's image inside it, Y(L) by quadrature of the light's spectrum against the CIE
    # 1931 y-bar of colour-science. Per pixel to 1.5 % (a 2 % bias fails; the light-tracing
    # noise of the smallest covered pixel is ~0.3 % at 512 spp), the sum to 0.3 %.
    size = 16
    y_le = _cornell_light_luminance()
    expected = y_le * _cornell_light_coverage(size)
    image = np.asarray(
        render("cornell-box", spp=512, width=size, height=size, integrator=PTracer(max_depth=1),
               rfilter=BoxFilter(), return_xyz=True, progress=False)
    )[..., 1]  # fmt: skip
    lit = expected > 0.05 * expected.max()
    assert lit.sum() == 4  # (the light's image spans 4 pixels of row 2)
    np.testing.assert_allclose(image[lit], expected[lit], rtol=0.015)
    np.testing.assert_allclose(image.sum(), expected.sum(), rtol=3e-3)
    np.testing.assert_array_equal(image[expected == 0], 0.0)


def test_ptracer_agrees_with_mitsuba_ptracer(tmp_path):
    # Mitsuba 3's ptracer (scalar_spectral) on the same XML Cornell box, box filter (with a
    # wider filter Mitsuba normalises each splat's footprint, a different estimator at the
    # border). Both renderers trace spp x pixels light paths per render; the per-pixel
    # variance of one render is estimated across Mitsuba's independent renders.
    pytest.importorskip("mitsuba", reason="Mitsuba 3 is the optional reference renderer")
    mi = mitsuba()
    depth, spp, n_ours, n_mi = 3, 32, 4, 16
    xml = cornell_box_xml(16, 16).replace('<rfilter type="gaussian"/>', '<rfilter type="box"/>')
    xml = xml.replace(
        '<integrator type="path"><integer name="max_depth" value="8"/>',
        f'<integrator type="ptracer"><integer name="max_depth" value="{depth}"/>',
    )
    assert 'type="ptracer"' in xml and 'type="box"' in xml
    path = tmp_path / "cbox_ptracer.xml"
    path.write_text(xml)
    scene = mi.load_file(str(path))
    ref = np.stack([np.asarray(mi.render(scene, spp=spp, seed=100 + s), np.float64)
                    for s in range(n_mi)])  # fmt: skip
    ours = np.stack([np.asarray(render(path, spp=spp, seed=s, progress=False), np.float64)
                     for s in range(n_ours)])  # fmt: skip
    result = pixel_z_test(
        ours.mean(axis=0), ref.mean(axis=0), ref.var(axis=0, ddof=1), n_ours, n_mi,
        variance_floor=1e-8,
    )  # fmt: skip
    assert result.passed, result.message
    np.testing.assert_allclose(ours.mean(axis=(0, 1, 2)), ref.mean(axis=(0, 1, 2)), rtol=0.01)


@pytest.mark.slow
def test_ptracer_envmap_equals_quadrature(tmp_path):
    # Light paths from an environment map (directions from its 2-D distribution, origins on
    # the disk of the scene's radius): a white plane (normal +z) under a grey map turned
    # 90 degrees about x reflects (1/pi) int L(w) max(w_z, 0) dw everywhere (the quadrature of
    # test_envmap, written from Mitsuba's equirectangular convention). The pixels are
    # independent estimates (light paths land in them independently): their mean is within
    # 5 standard errors of the quadrature and within 5 %; a 10 % bias fails both.
    grey = _grey_map()
    exr = write_exr(tmp_path / "sky.exr", grey)
    rot = '<transform name="to_world"><rotate x="1" angle="90"/></transform>'
    plane = (
        '<shape type="rectangle"><transform name="to_world"><scale value="1"/></transform>'
        '<bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf></shape>'
    )
    path = tmp_path / "plane.xml"
    path.write_text(_envmap_scene(_envmap(exr, rot), plane, integrator="ptracer", fov=30.0))
    image = np.asarray(render(path, spp=256, seed=2, progress=False, return_xyz=True), np.float64)[
        ..., 1
    ]
    u, v = _uv_grid(2048)
    world_z = _directions(u, v)[:, 1]  # the rotation maps local +y to world +z
    dw = 2 * np.pi**2 * np.sin(np.pi * v) / u.size
    expected = np.sum(_bilinear_y(grey, u, v) * np.maximum(world_z, 0) * dw) / np.pi
    sem = image.std() / np.sqrt(image.size)
    assert abs(image.mean() - expected) < 5 * sem, (image.mean(), expected, sem)
    assert abs(image.mean() / expected - 1) < 0.05, (image.mean(), expected)
