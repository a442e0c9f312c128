"""Pinhole camera: look-at, projection matrices (thesis eq. 2.28-2.30), rays and their inverse."""

import itertools
import json
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.camera as cam

SHARED = Path(__file__).resolve().parents[2].parent / "shared"
CORNELL_TO_WORLD = np.array(
    [[-1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, -1.0, 3.9], [0.0, 0.0, 0.0, 1.0]]
)


def _cornell_camera(width=256, height=256, fov_axis="smaller"):
    return cam.PinholeCamera.from_look_at(
        np.array([0.0, 0.0, 3.9]),
        np.array([0.0, 0.0, 0.0]),
        np.array([0.0, 1.0, 0.0]),
        39.3077,
        width,
        height,
        fov_axis,
    )


def test_look_at_cornell_box_matches_scene_json():
    m = cam.look_at(np.array([0.0, 0.0, 3.9]), np.array([0.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    np.testing.assert_allclose(m, CORNELL_TO_WORLD, atol=1e-15)
    path = SHARED / "cornell_box.json"
    if path.exists():  # the reference scene's Mitsuba to_world (float32 rounding)
        ref = np.array(json.loads(path.read_text())["camera"]["to_world"])
        np.testing.assert_allclose(m, ref, atol=1e-7)


def test_look_at_is_rigid_and_right_handed():
    key = jax.random.key(1)
    for k in jax.random.split(key, 5):
        o, t, up = jax.random.normal(k, (3, 3))
        m = np.asarray(cam.look_at(o, t, up))
        r = m[:3, :3]
        np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-12)
        assert np.linalg.det(r) == pytest.approx(1.0)
        d = (t - o) / np.linalg.norm(t - o)
        np.testing.assert_allclose(r[:, 2], d, atol=1e-12)  # camera +z looks at the target
        assert r[:, 1] @ np.asarray(up) > 0  # camera +y is on the side of `up`
        np.testing.assert_allclose(m[:3, 3], o)


def test_red_wall_is_on_the_left_of_the_image():
    c = _cornell_camera()
    red = np.array([[-1.0, 0.0, 0.0], [-1.0, 0.5, -0.5]])  # points on the red wall x = -1
    green = np.array([[1.0, 0.0, 0.0], [1.0, -0.5, 0.5]])
    ceiling = np.array([0.0, 1.0, 0.0])
    assert np.all(np.asarray(cam.project(c, red))[:, 0] < 128)
    assert np.all(np.asarray(cam.project(c, green))[:, 0] > 128)
    assert float(cam.project(c, ceiling)[1]) < 128  # up is the top of the image (small y)
    _, d = cam.generate_ray(c, np.array([[0.5, 128.0]]))
    assert float(d[0, 0]) < 0  # the leftmost pixel column looks towards -x


@pytest.mark.parametrize("fov_axis", ["x", "y", "diagonal", "smaller", "larger"])
def test_perspective_maps_frustum_to_unit_cube(fov_axis):
    fov, aspect, near, far = 50.0, 1.6, 0.5, 20.0
    p = np.asarray(cam.perspective(fov, aspect, near, far, fov_axis=fov_axis))
    tan_x = np.tan(np.deg2rad(float(cam.fov_x_deg(fov, aspect, fov_axis))) / 2)
    tan_y = tan_x / aspect
    corners = []
    for sx, sy, z in itertools.product((-1, 1), (-1, 1), (near, far)):
        corners.append([sx * z * tan_x, sy * z * tan_y, z, 1.0])
    clip = np.array(corners) @ p.T
    ndc = clip[:, :3] / clip[:, 3:]
    expected = np.array(list(itertools.product((-1, 1), (-1, 1), (-1, 1))), float)
    np.testing.assert_allclose(ndc, expected, atol=1e-12)
    # A point inside the frustum lands inside the cube; depth is monotone.
    inside = np.array([0.3 * 5 * tan_x, -0.2 * 5 * tan_y, 5.0, 1.0]) @ p.T
    assert np.all(np.abs(inside[:3] / inside[3]) < 1)


def test_perspective_frustum_off_centre_and_decomposition():
    l, r, b, t, n, f = -0.3, 0.5, -0.2, 0.4, 1.0, 10.0  # noqa: E741
    p = np.asarray(cam.perspective_frustum(l, r, b, t, n, f))
    # eq. 2.30 = eq. 2.29 @ eq. 2.28
    m228 = np.array(
        [[2 * n / (r - l), 0, -(r + l) / (r - l), 0], [0, 2 * n / (t - b), -(t + b) / (t - b), 0],
         [0, 0, 1, 0], [0, 0, 0, 1]]
    )  # fmt: skip
    m229 = np.array(
        [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, (f + n) / (f - n), -2 * f * n / (f - n)], [0, 0, 1, 0]]
    )
    np.testing.assert_allclose(p, m229 @ m228, atol=1e-14)
    for x, y, z, e in [
        (l, b, n, (-1, -1, -1)),
        (r, t, n, (1, 1, -1)),
        (l * f / n, t * f / n, f, (-1, 1, 1)),
    ]:
        c = p @ np.array([x, y, z, 1.0])
        np.testing.assert_allclose(c[:3] / c[3], e, atol=1e-12)


def test_fov_axis_conversions_match_mitsuba_rule():
    aspect = 2.0
    t = np.tan(np.deg2rad(30.0) / 2)
    assert float(cam.fov_x_deg(30.0, aspect, "x")) == pytest.approx(30.0)
    assert float(cam.fov_x_deg(30.0, aspect, "y")) == pytest.approx(
        np.rad2deg(2 * np.arctan(t * 2))
    )
    diag = np.rad2deg(2 * np.arctan(t / np.sqrt(1 + 1 / aspect**2)))
    assert float(cam.fov_x_deg(30.0, aspect, "diagonal")) == pytest.approx(diag)
    assert float(cam.fov_x_deg(30.0, aspect, "smaller")) == float(cam.fov_x_deg(30.0, aspect, "y"))
    assert float(cam.fov_x_deg(30.0, 0.5, "smaller")) == pytest.approx(30.0)
    assert float(cam.fov_x_deg(30.0, 0.5, "larger")) == float(cam.fov_x_deg(30.0, 0.5, "y"))


@pytest.mark.parametrize("size", [(256, 256), (320, 200), (90, 160)])
def test_generate_ray_inverts_project(size):
    w, h = size
    c = cam.PinholeCamera.from_look_at(
        np.array([1.0, 2.0, -3.0]), np.array([0.2, 0.1, 0.5]), np.array([0.1, 1.0, 0.0]), 47.0, w, h
    )
    xy = jax.random.uniform(jax.random.key(0), (200, 2)) * np.array([[float(w), float(h)]])
    o, d = cam.generate_ray(c, xy)
    np.testing.assert_allclose(jnp.linalg.norm(d, axis=-1), 1.0, atol=1e-12)
    t = jax.random.uniform(jax.random.key(1), (200, 1), minval=0.1, maxval=50.0)
    np.testing.assert_allclose(cam.project(c, o + t * d), xy, atol=1e-9)
    # ... and the other way round: project a world point, the ray through it hits it.
    pts = jax.random.normal(jax.random.key(2), (50, 3)) * 0.3 + np.array([[0.2, 0.1, 0.5]])
    o2, d2 = cam.generate_ray(c, cam.project(c, pts))
    v = pts - o2
    np.testing.assert_allclose(d2, v / jnp.linalg.norm(v, axis=-1, keepdims=True), atol=1e-9)


def test_project_behind_camera_is_nan_and_centre_maps_to_image_centre():
    c = _cornell_camera(320, 200)
    xy = np.asarray(cam.project(c, np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 5.0]])))
    np.testing.assert_allclose(xy[0], [160.0, 100.0], atol=1e-12)
    assert np.all(np.isnan(xy[1]))


def test_generate_ray_jit_vmap_grad_and_float32():
    c = _cornell_camera(64, 48)
    xy = np.array([[3.5, 7.25], [60.0, 1.0]])
    o, d = cam.generate_ray(c, xy)
    oj, dj = eqx.filter_jit(cam.generate_ray)(c, xy)
    np.testing.assert_allclose(dj, d, atol=1e-14)
    ov, dv = jax.vmap(lambda p: cam.generate_ray(c, p))(xy)
    np.testing.assert_allclose(dv, d, atol=1e-14)
    o32, d32 = cam.generate_ray(c, xy.astype(np.float32))
    assert d32.dtype == jnp.float32 and o32.dtype == jnp.float32
    np.testing.assert_allclose(d32, d, atol=1e-6)

    def loss(fov):
        c2 = cam.PinholeCamera.from_to_world(CORNELL_TO_WORLD, fov, 64, 48)
        return jnp.sum(cam.generate_ray(c2, xy)[1][:, 0])

    g = float(jax.grad(loss)(jnp.asarray(40.0)))
    eps = 1e-6
    fd = float(loss(jnp.asarray(40.0 + eps)) - loss(jnp.asarray(40.0 - eps))) / (2 * eps)
    assert np.isfinite(g) and g == pytest.approx(fd, rel=1e-6)


def test_rays_match_mitsuba_perspective_sensor():
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    cases = [
        (CORNELL_TO_WORLD, 39.3077, 256, 256, "smaller"),
        (np.asarray(cam.look_at(np.array([1.0, 2.0, -3.0]), np.array([0.2, 0.1, 0.5]),
                                np.array([0.1, 1.0, 0.0]))), 47.0, 320, 200, "x"),
        (CORNELL_TO_WORLD, 30.0, 160, 90, "y"),
        (CORNELL_TO_WORLD, 60.0, 100, 150, "diagonal"),
        (CORNELL_TO_WORLD, 35.0, 150, 100, "larger"),
        (CORNELL_TO_WORLD, 45.0, 200, 120, "smaller"),
    ]  # fmt: skip
    raster = np.array([[0.5, 0.5], [12.25, 80.0], [0.0, 0.0], [99.0, 3.0], [50.0, 45.0]])
    for to_world, fov, w, h, axis in cases:
        sensor = mi.load_dict(
            {
                "type": "perspective",
                "fov": fov,
                "fov_axis": axis,
                "to_world": mi.ScalarTransform4f(to_world.tolist()),
                "film": {"type": "hdrfilm", "width": w, "height": h},
            }
        )
        c = cam.PinholeCamera.from_to_world(to_world, fov, w, h, axis)
        o, d = (np.asarray(a) for a in cam.generate_ray(c, raster))
        for k, (x, y) in enumerate(raster):
            ray, _ = sensor.sample_ray(
                0.0, 0.5, mi.ScalarPoint2f(x / w, y / h), mi.ScalarPoint2f(0.5, 0.5)
            )
            d_mi = np.array(ray.d, float)
            np.testing.assert_allclose(d[k], d_mi / np.linalg.norm(d_mi), atol=2e-6)
            # Mitsuba starts the ray on the near plane: its origin lies on our ray.
            o_mi = np.array(ray.o, float)
            s = (o_mi - o[k]) @ d[k]
            np.testing.assert_allclose(o[k] + s * d[k], o_mi, atol=2e-6)


def test_camera_rejects_bad_input():
    o, t, up = np.array([0.0, 0.0, 3.9]), np.zeros(3), np.array([0.0, 1.0, 0.0])
    with pytest.raises(ValueError, match="fov_deg"):
        cam.PinholeCamera.from_look_at(o, t, up, -10.0, 32, 32)
    with pytest.raises(ValueError, match="fov_deg"):
        cam.PinholeCamera.from_look_at(o, t, up, 180.0, 32, 32)
    with pytest.raises(ValueError, match="fov_deg"):
        cam.perspective(0.0, 1.0, 0.1, 10.0)
    with pytest.raises(ValueError, match="width"):
        cam.PinholeCamera.from_look_at(o, t, up, 40.0, 0, 32)
    with pytest.raises(ValueError, match="height"):
        cam.PinholeCamera.from_to_world(CORNELL_TO_WORLD, 40.0, 32, 0)
    with pytest.raises(TypeError, match="width"):
        cam.PinholeCamera.from_to_world(CORNELL_TO_WORLD, 40.0, 32.0, 32)
    with pytest.raises(ValueError, match="fov_axis"):
        cam.PinholeCamera.from_to_world(CORNELL_TO_WORLD, 40.0, 32, 32, "z")
    with pytest.raises(ValueError, match="4x4"):
        cam.PinholeCamera.from_to_world(np.eye(3), 40.0, 32, 32)
    with pytest.raises(ValueError, match="near"):
        cam.perspective(40.0, 1.0, 1.0, 0.5)
    with pytest.raises(ValueError, match="left < right"):
        cam.perspective_frustum(1.0, -1.0, -1.0, 1.0, 0.1, 10.0)
    with pytest.raises(ValueError, match="origin"):
        cam.look_at(np.zeros(2), t, up)
    # concrete values are checked at once, traced ones when the program runs
    with pytest.raises(ValueError, match="parallel"):
        cam.look_at(o, t, np.array([0.0, 0.0, 1.0]))
    with pytest.raises(ValueError, match="differ"):
        cam.look_at(o, o, up)
    with pytest.raises(eqx.EquinoxRuntimeError, match="parallel"):
        eqx.filter_jit(cam.look_at)(o, t, np.array([0.0, 0.0, 1.0]))
    with pytest.raises(eqx.EquinoxRuntimeError, match="differ"):
        eqx.filter_jit(cam.look_at)(o, o, up)
    c = _cornell_camera(8, 8)
    with pytest.raises(ValueError, match="raster_xy"):
        cam.generate_ray(c, np.zeros((4, 3)))
    with pytest.raises(ValueError, match="points_world"):
        cam.project(c, np.zeros((4, 2)))
    # Under jit the fov check fires as a runtime error.
    make = eqx.filter_jit(lambda fov: cam.PinholeCamera.from_to_world(CORNELL_TO_WORLD, fov, 8, 8))
    with pytest.raises(eqx.EquinoxRuntimeError, match="fov_deg"):
        make(jnp.asarray(200.0))


def test_fov_from_focal_length_matches_published_35mm_angles():
    # Diagonal angles of view of 35 mm lenses as photography tables list them (24 mm 84.1,
    # 28 mm 75.4, 50 mm 46.8, 100 mm 24.4 degrees); Mitsuba's `focal_length` uses the same.
    for f_mm, published in ((24.0, 84.1), (28.0, 75.4), (50.0, 46.8), (100.0, 24.4)):
        assert cam.fov_from_focal_length_deg(f_mm) == pytest.approx(published, abs=0.05)
    for bad in (0.0, -35.0, float("nan")):
        with pytest.raises(ValueError, match=r"focal_length_mm.*> 0 \[mm\]"):
            cam.fov_from_focal_length_deg(bad)
