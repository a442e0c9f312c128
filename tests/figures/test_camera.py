"""Figures 2.5 and 2.6: the plotted pinhole geometry against a hand-written numpy pinhole."""

import numpy as np
import pytest

from radiometria.figures import FIGURES, make_figures
from radiometria.figures._camera import _FIG_CAMERA, pinhole_figure_data


@pytest.fixture(scope="module")
def data():
    return pinhole_figure_data()


def _camera_frame():
    """(origin, rows of world-to-camera rotation): Mitsuba's look-at, written out in numpy."""
    o, t, up = (np.asarray(_FIG_CAMERA[k], float) for k in ("origin", "target", "up"))
    forward = (t - o) / np.linalg.norm(t - o)
    left = np.cross(up, forward)
    left /= np.linalg.norm(left)
    return o, np.stack([left, np.cross(forward, left), forward])


def _tan_half():
    tan_x = np.tan(np.radians(_FIG_CAMERA["fov_x_deg"]) / 2)
    return tan_x, tan_x * _FIG_CAMERA["height"] / _FIG_CAMERA["width"]


def _numpy_pinhole(points):
    """Camera-space points, NDC (x, y) and raster positions of world points, by hand."""
    o, rot = _camera_frame()
    p = (points - o) @ rot.T
    tan_x, tan_y = _tan_half()
    ndc = np.stack([p[:, 0] / (p[:, 2] * tan_x), p[:, 1] / (p[:, 2] * tan_y)], axis=-1)
    w, h = _FIG_CAMERA["width"], _FIG_CAMERA["height"]
    raster = np.stack([w * (1 - ndc[:, 0]) / 2, h * (1 - ndc[:, 1]) / 2], axis=-1)
    return p, ndc, raster


def test_pinhole_figure_raster_equals_numpy_projection(data):
    p_cam, _, raster = _numpy_pinhole(data["points"])
    np.testing.assert_allclose(data["camera_points"], p_cam, atol=1e-12)
    np.testing.assert_allclose(data["raster"], raster, rtol=1e-12, atol=1e-10)
    w, h = _FIG_CAMERA["width"], _FIG_CAMERA["height"]
    assert np.all((raster > 0) & (raster < [w, h]))  # the whole cube is in the picture


def test_pinhole_figure_rays_pass_through_the_points(data):
    o = np.asarray(_FIG_CAMERA["origin"])
    np.testing.assert_allclose(data["ray_origin"], np.broadcast_to(o, (8, 3)), atol=1e-12)
    d = data["ray_direction"]
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-12)
    to_p = (data["points"] - o) / np.linalg.norm(data["points"] - o, axis=-1, keepdims=True)
    np.testing.assert_allclose(d, to_p, atol=1e-10)
    # q: on the near (film) plane, on the segment from o to p.
    _, rot = _camera_frame()
    q_cam = (data["film_points"] - o) @ rot.T
    np.testing.assert_allclose(q_cam[:, 2], _FIG_CAMERA["near"], atol=1e-12)
    p_cam = data["camera_points"]
    np.testing.assert_allclose(q_cam, p_cam * (_FIG_CAMERA["near"] / p_cam[:, 2:]), atol=1e-10)


def test_pinhole_figure_frustum_corners(data):
    o, rot = _camera_frame()
    tan_x, tan_y = _tan_half()
    signs = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]])  # raster corners TL, TR, BR, BL
    for key, depth in (("near_corners", _FIG_CAMERA["near"]), ("far_corners", _FIG_CAMERA["far"])):
        c = (data[key] - o) @ rot.T
        expected = np.c_[signs * [tan_x, tan_y] * depth, np.full(4, depth)]
        np.testing.assert_allclose(c, expected, atol=1e-10)


def test_projection_figure_ndc_and_depth_map_equal_numpy(data):
    n, f = _FIG_CAMERA["near"], _FIG_CAMERA["far"]
    p_cam, ndc_xy, _ = _numpy_pinhole(data["points"])
    z_ndc = lambda z: (f + n) / (f - n) - 2 * f * n / ((f - n) * z)  # noqa: E731 (eq. 2.29)
    np.testing.assert_allclose(data["ndc_points"][:, :2], ndc_xy, atol=1e-12)
    np.testing.assert_allclose(data["ndc_points"][:, 2], z_ndc(p_cam[:, 2]), atol=1e-12)
    assert np.all(np.abs(data["ndc_points"]) < 1.0)  # inside the frustum -> inside the cube
    np.testing.assert_allclose(data["depth_ndc"], z_ndc(data["depth_z"]), atol=1e-12)
    np.testing.assert_allclose(data["depth_ndc"][[0, -1]], [-1.0, 1.0], atol=1e-12)
    # The harmonic mean of the clip distances maps to 0 (thesis, after eq. 2.29).
    assert abs(z_ndc(2 * f * n / (f + n))) < 1e-12


@pytest.mark.parametrize("name", ["fig_2_5_pinhole", "fig_2_6_projection"])
def test_camera_figure_written(tmp_path, name):
    assert name in FIGURES
    paths = make_figures(tmp_path, [name], smoke=True)
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]
    assert all(p.stat().st_size > 1000 for p in paths)
