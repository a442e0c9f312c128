"""Orthographic and thin-lens cameras: rays against Mitsuba 3's sensors and closed forms."""

import numpy as np
import pytest

from radiometria.camera import OrthographicCamera, PinholeCamera, ThinLensCamera, look_at

W, H = 16, 8


def _mitsuba_rays(sensor: dict, pos: np.ndarray, aperture: np.ndarray):
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_spectral")
    s = mi.load_dict({**sensor, "film": {"type": "hdrfilm", "width": W, "height": H}})
    rays = [
        s.sample_ray(0.0, 0.5, mi.Point2f(*p), mi.Point2f(*a))[0]
        for p, a in zip(pos, aperture, strict=True)
    ]
    return np.array([r.o for r in rays]), np.array([r.d for r in rays])


def _variates(n=24, seed=0):
    rng = np.random.default_rng(seed)
    return rng.random((n, 2)), rng.random((n, 2))


@pytest.mark.parametrize("kind", ["orthographic", "thinlens"])
def test_rays_match_mitsuba_sensors(kind):
    """Ray origins and directions of both sensors equal Mitsuba 3's `sample_ray` for the
    same film position and aperture variates (to float32 rounding), including a scaled
    `to_world` for the orthographic camera (its scale sets the imaged extent)."""
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_spectral")
    frame = mi.ScalarTransform4f().look_at([0.3, 1.0, 4.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    pos, ap = _variates()
    if kind == "orthographic":
        tw = frame @ mi.ScalarTransform4f().scale([1.5, 1.5, 1.0])
        sensor = {"type": kind, "to_world": tw}
        cam = OrthographicCamera.from_to_world(np.array(tw.matrix), W, H)
    else:
        sensor = {"type": kind, "to_world": frame, "fov": 40.0, "aperture_radius": 0.2,
                  "focus_distance": 3.0}  # fmt: skip
        cam = ThinLensCamera.from_to_world(np.array(frame.matrix), 40.0, W, H, 0.2, 3.0)
    ref_o, ref_d = _mitsuba_rays(sensor, pos, ap)
    o, d = cam.sample_ray(pos * [W, H], ap)
    np.testing.assert_allclose(np.asarray(o), ref_o, atol=5e-6)
    np.testing.assert_allclose(np.asarray(d), ref_d, atol=5e-6)


def test_orthographic_rays_closed_form():
    """Parallel rays along the viewing direction, origins on the near plane spanning
    `2 half_width` across the image and `2 half_width / aspect` down it."""
    cam = OrthographicCamera.from_look_at(
        np.array([0, 0, 5.0]), np.zeros(3), np.array([0.0, 1, 0]), 2.0, W, H
    )
    raster = np.array([[0.0, 0.0], [W, 0.0], [0.0, H], [W / 2, H / 2]])
    o, d = (np.asarray(x) for x in cam.generate_ray(raster))
    np.testing.assert_allclose(d, np.tile([0.0, 0.0, -1.0], (4, 1)), atol=1e-12)
    # Camera +x is the image's left, world -x with this look_at (diag(-1, 1, -1)): the
    # top-left corner is at world x = -half_width.
    np.testing.assert_allclose(o[0], [-2.0, 2.0 / (W / H), 5.0 - 1e-2], atol=1e-12)
    np.testing.assert_allclose(o[1] - o[0], [4.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(o[2] - o[0], [0.0, -4.0 / (W / H), 0.0], atol=1e-12)
    np.testing.assert_allclose(o[3], [0.0, 0.0, 5.0 - 1e-2], atol=1e-12)


def _lens_rim(n=64):
    """Aperture variates on the square's border: the concentric map sends them to the rim."""
    t = np.linspace(0.0, 1.0, n, endpoint=False)
    return np.concatenate(
        [np.stack([t, np.zeros(n)], -1), np.stack([np.full(n, 1 - 1e-12), t], -1)]
    )


def test_thin_lens_focal_plane_is_sharp_and_defocus_matches_the_thin_lens_formula():
    """All rays of one raster point meet at one point of the plane of focus, where the
    pinhole camera's ray of that point also goes; on a plane at depth z they cover a disk of
    radius r |1 - z / d_f| (similar triangles of the thin-lens model)."""
    r, df, fov = 0.25, 3.0, 50.0
    o, t, u = np.zeros(3), np.array([0, 0, 1.0]), np.array([0, 1.0, 0])
    cam = ThinLensCamera.from_look_at(o, t, u, fov, W, H, r, df)
    pin = PinholeCamera.from_look_at(o, t, u, fov, W, H, "x")
    rim = _lens_rim()
    for raster in ([3.3, 2.7], [W / 2, H / 2], [14.0, 7.5]):
        xy = np.tile(raster, (len(rim), 1))
        o, d = (np.asarray(x) for x in cam.sample_ray(xy, rim))
        _, dp = (np.asarray(x) for x in pin.generate_ray(np.asarray(raster)))

        def at(z, o=o, d=d):
            return o + d * ((z - o[:, 2]) / d[:, 2])[:, None]

        np.testing.assert_allclose(at(df), np.tile(dp * df / dp[2], (len(rim), 1)), atol=1e-9)
        for z in (1.0, 2.0, 6.0):
            p = at(z)
            centre = dp * z / dp[2]
            radius = np.linalg.norm(p - centre, axis=-1)
            np.testing.assert_allclose(radius, r * abs(1 - z / df), rtol=1e-9, atol=1e-12)


def test_thin_lens_without_aperture_is_the_pinhole():
    """A zero aperture radius gives the pinhole camera's rays (origins moved to the near
    plane along them)."""
    to_world = look_at(np.array([1.0, 2.0, 3.0]), np.zeros(3), np.array([0, 1.0, 0]))
    cam = ThinLensCamera.from_to_world(to_world, 35.0, W, H, 0.0, 2.0)
    pin = PinholeCamera.from_to_world(to_world, 35.0, W, H, "x")
    pos, ap = _variates()
    o, d = (np.asarray(x) for x in cam.sample_ray(pos * [W, H], ap))
    op, dp = (np.asarray(x) for x in pin.generate_ray(pos * [W, H]))
    np.testing.assert_allclose(d, dp, atol=1e-12)
    np.testing.assert_allclose(np.cross(o - op, dp), 0.0, atol=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [({"aperture_radius": -0.1}, "aperture_radius"), ({"focus_distance": 0.0}, "focus_distance")],
)
def test_thin_lens_rejects_bad_lenses(kwargs, match):
    args = {"aperture_radius": 0.1, "focus_distance": 1.0, **kwargs}
    with pytest.raises(ValueError, match=match):
        ThinLensCamera.from_to_world(np.eye(4), 40.0, W, H, **args)


CROP = {"crop_offset_x": 5, "crop_offset_y": 2, "crop_width": 7, "crop_height": 4}


@pytest.mark.parametrize("kind", ["perspective", "thinlens", "orthographic"])
def test_crop_window_and_principal_point_rays_match_mitsuba(kind):
    """A film crop window (all sensors) and a principal point offset (`perspective`): our
    rays through raster positions of the cropped image equal Mitsuba 3's `sample_ray` for the
    same position sample of its cropped film (Mitsuba's position sample spans the crop
    window); `project` inverts `generate_ray` with both."""
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_spectral")
    frame = mi.ScalarTransform4f().look_at([0.3, 1.0, 4.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    m = np.array(frame.matrix)
    window = tuple(CROP.values())
    cw, ch = CROP["crop_width"], CROP["crop_height"]
    sensor = {"type": kind, "to_world": frame}
    if kind == "perspective":
        pp = (0.13, -0.21)
        sensor |= {"fov": 40.0, "principal_point_offset_x": pp[0],
                   "principal_point_offset_y": pp[1]}  # fmt: skip
        cam = PinholeCamera.from_to_world(
            m, 40.0, W, H, "x", principal_point=pp, crop_window=window
        )
    elif kind == "thinlens":
        sensor |= {"fov": 40.0, "aperture_radius": 0.2, "focus_distance": 3.0}
        cam = ThinLensCamera.from_to_world(m, 40.0, W, H, 0.2, 3.0, crop_window=window)
    else:
        cam = OrthographicCamera.from_to_world(m, W, H, crop_window=window)
    s = mi.load_dict({**sensor, "film": {"type": "hdrfilm", "width": W, "height": H, **CROP}})
    pos, ap = _variates(seed=3)
    rays = [
        s.sample_ray(0.0, 0.5, mi.Point2f(*p), mi.Point2f(*a))[0]
        for p, a in zip(pos, ap, strict=True)
    ]
    o, d = cam.sample_ray(pos * [cw, ch], ap)
    np.testing.assert_allclose(np.asarray(d), np.array([r.d for r in rays]), atol=5e-6)
    if kind != "perspective":  # Mitsuba starts pinhole rays at the near plane, we at the eye
        np.testing.assert_allclose(np.asarray(o), np.array([r.o for r in rays]), atol=5e-6)
    else:
        o, d = cam.generate_ray(pos * [cw, ch])
        back = cam.project(np.asarray(o) + 2.5 * np.asarray(d))
        np.testing.assert_allclose(np.asarray(back), pos * [cw, ch], atol=1e-9)


def test_cropped_pinhole_importance_integrates_to_one_over_its_window():
    """W_e cos(theta) integrates to 1 over the solid angle of the crop window (the window's
    share of the film area enters A), checked by a midpoint rule over the window."""
    cam = PinholeCamera.from_to_world(
        np.eye(4), 50.0, W, H, "x", principal_point=(0.05, 0.1), crop_window=(3, 1, 9, 5)
    )
    n = 400
    xy = (np.stack(np.meshgrid(np.arange(n), np.arange(n)), -1).reshape(-1, 2) + 0.5) / n
    _, d = cam.generate_ray(xy * [9, 5])
    d = np.asarray(d)
    cos = d[:, 2]
    # Solid angle per raster cell: (pixel area at unit depth) * cos^3; A_px = 4 tx ty / (W H).
    tx, ty = (float(t) for t in cam.tan_half_fov())
    d_omega = (4 * tx * ty / (W * H)) * (9 * 5 / n**2) * cos**3
    total = np.sum(np.asarray(cam.importance(cos)) * cos * d_omega)
    np.testing.assert_allclose(total, 1.0, rtol=1e-9)


def test_crop_window_outside_the_film_is_refused():
    with pytest.raises(ValueError, match=r"does not fit in the 16 x 8 film"):
        PinholeCamera.from_to_world(np.eye(4), 40.0, W, H, crop_window=(5, 0, 12, 4))
    with pytest.raises(ValueError, match=r"principal_point"):
        PinholeCamera.from_to_world(np.eye(4), 40.0, W, H, principal_point=(0.1, 0.2, 0.3))
    with pytest.raises(ValueError, match=r"crop_width"):
        OrthographicCamera.from_to_world(np.eye(4), W, H, crop_window=(0, 0, 0, 4))
