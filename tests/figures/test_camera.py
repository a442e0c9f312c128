"""Figures 2.5 and 2.6: the plotted pinhole geometry against a hand-written numpy pinhole; the
filter figure: profiles against closed forms normalised by SciPy quadrature, histograms against
the cell integrals of those closed forms."""

import numpy as np
import pytest
from scipy import integrate

from radiometria.figures import FIGURES, make_figures
from radiometria.figures._camera import _FIG_CAMERA, filters_figure_data, pinhole_figure_data


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


@pytest.mark.parametrize(
    "name",
    [
        "fig_2_5_pinhole",
        "fig_2_6_projection",
    ],
)
def test_camera_figure_written(tmp_path, name):
    assert name in FIGURES
    paths = make_figures(tmp_path, [name], smoke=True)
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]
    assert all(p.stat().st_size > 1000 for p in paths)


# --- reconstruction filters ----------------------------------------------------------------


def _mitchell(x, B=1 / 3, C=1 / 3, r=2.0):
    """(2 / r) k(2x / r), Mitchell & Netravali (1988) eq. 8, which integrates to 1."""
    x = np.abs(2 * np.asarray(x, float) / r)
    inner = ((12 - 9 * B - 6 * C) * x**3 + (-18 + 12 * B + 6 * C) * x**2 + (6 - 2 * B)) / 6
    outer = (
        (-B - 6 * C) * x**3 + (6 * B + 30 * C) * x**2 + (-12 * B - 48 * C) * x + (8 * B + 24 * C)
    ) / 6
    return 2 / r * np.where(x < 1, inner, np.where(x < 2, outer, 0.0))


def _normalised(fn, r):
    z, _ = integrate.quad(fn, -r, r, points=[0.0], limit=200, epsabs=1e-13)
    return lambda x: fn(x) / z


def _closed_forms():
    """The 1D profiles f_1 of the figure's filters (defaults), by name, with their radius."""
    s, rg = 0.5, 2.0
    gauss = lambda x: np.maximum(np.exp(-(x**2) / (2 * s * s)) - np.exp(-(rg**2) / (2 * s * s)), 0)  # noqa: E731
    lanczos = lambda x: np.where(np.abs(x) < 3, np.sinc(x) * np.sinc(x / 3), 0.0)  # noqa: E731
    return {
        "box": (lambda x: np.where(np.abs(x) < 0.5, 1.0, 0.0), 0.5),
        "tent": (lambda x: np.maximum(1 - np.abs(x), 0.0), 1.0),
        "Gaussian": (_normalised(gauss, rg), rg),
        "Mitchell-Netravali": (_mitchell, 2.0),
        "Lanczos": (_normalised(lanczos, 3.0), 3.0),
    }


@pytest.fixture(scope="module")
def filters():
    return filters_figure_data(smoke=True)


def test_filters_figure_profiles_equal_closed_forms(filters):
    x = filters["x"]
    forms = _closed_forms()
    assert [d["title"].split(" (")[0] for d in filters["filters"]] == list(forms)
    for d, (name, (fn, r)) in zip(filters["filters"], forms.items(), strict=True):
        assert d["filter"].radius == pytest.approx(r)
        # Unit integrals (SciPy quad): box, tent and Mitchell without normalisation.
        total, _ = integrate.quad(fn, -r, r, points=[0.0], limit=200)
        assert total == pytest.approx(1.0, abs=1e-9), name
        far = np.abs(np.abs(x) - r) > 1e-3  # away from the box's jump
        np.testing.assert_allclose(
            d["profile"][far], fn(x[far]), rtol=1e-5, atol=1e-6, err_msg=name
        )
    # Mitchell and Lanczos have negative lobes; the others do not.
    neg = {d["title"].split(" (")[0]: d["profile"].min() < -1e-3 for d in filters["filters"]}
    assert neg == {
        "box": False,
        "tent": False,
        "Gaussian": False,
        "Mitchell-Netravali": True,
        "Lanczos": True,
    }


def test_filters_figure_histograms_estimate_the_filter(filters):
    """The weighted 1D histogram is an unbiased estimate of the bin averages of f_1 (eq. 2.35),
    within 5 of its own standard errors (plus 1e-3 for the float32 sampling), and the 2D
    histogram's x-marginal is the density |f_1| / int |f_1| (binomial standard errors)."""
    n, bins = filters["n"], filters["bins"]
    width = np.diff(bins)
    for d, (name, (fn, r)) in zip(filters["filters"], _closed_forms().items(), strict=True):
        assert d["offset"].shape == (n, 2) and np.all(np.abs(d["offset"]) <= r + 1e-6)
        cells = np.array(
            [integrate.quad(fn, a, b)[0] for a, b in zip(bins[:-1], bins[1:], strict=True)]
        )
        # Var(w 1_bin) <= max(w^2) P(bin), P(bin) = int_bin |f_1| / int |f_1| (p ~ |f|): a
        # standard error from the model, not from the (few) samples in the tails.
        abs_bins = np.array(
            [
                integrate.quad(lambda t, fn=fn: abs(fn(t)), a, b, limit=100)[0]
                for a, b in zip(bins[:-1], bins[1:], strict=True)
            ]
        )
        se = np.abs(d["weight"]).max() * np.sqrt(abs_bins / abs_bins.sum() / n) / width
        error = np.abs(d["hist"] - cells / width)
        np.testing.assert_array_less(error, 5 * se + 1e-4, err_msg=name)
        # The marginals of the sampling density in x and in y, from h2 (separable, p ~ |f|).
        abs_cells = np.array(
            [
                integrate.quad(lambda t, fn=fn: abs(fn(t)), a, b, limit=100)[0]
                for a, b in zip(d["xe"][:-1], d["xe"][1:], strict=True)
            ]
        )
        p = abs_cells / abs_cells.sum()
        cell = np.diff(d["xe"])[0] * np.diff(d["ye"])[0]
        for axis in (1, 0):
            observed = d["h2"].sum(axis=axis) * cell
            bound = 5 * np.sqrt(p * (1 - p) / n) + 1e-4
            np.testing.assert_array_less(np.abs(observed - p), bound, err_msg=name)
        assert d["h2"].sum() * cell == pytest.approx(1.0)
