"""Integrators: closed-form checks (white furnace, one-bounce irradiance) and conventions."""

import math

import numpy as np
import pytest

from radiometria.camera import PinholeCamera
from radiometria.render import RenderScene, render

from ._synthetic import constant_table, inward_cube, merge, quad


def test_inward_cube_normals_point_inside():
    v, f = inward_cube()
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    centre = v[f].mean(axis=1)
    assert np.all(np.sum(n * centre, axis=1) < 0)


@pytest.mark.slow
@pytest.mark.parametrize("albedo", [0.5, 0.8])
def test_path_white_furnace(albedo):
    """Closed cube, every face albedo a and emitting Le: L = Le / (1 - a) everywhere."""
    le = 0.7
    v, f = inward_cube()
    scene = RenderScene.from_triangles(
        v,
        f,
        np.zeros(len(f), int),
        constant_table(albedo),
        np.zeros(len(f), int),
        constant_table(le),
    )
    cam = PinholeCamera.from_look_at(
        np.array([0.1, 0.2, -0.3]), np.array([0.5, 0.3, 1.0]), np.array([0.0, 1, 0]), 70.0, 16, 16
    )
    xyz = render(scene, camera=cam, spp=64, max_depth=80, seed=1, progress=False, return_xyz=True)
    expected = le / (1.0 - albedo)
    # Y of a constant spectrum is the constant itself (the film's normalisation).
    assert np.mean(xyz[..., 1]) == pytest.approx(expected, rel=5e-3)


def _irradiance_below_rectangle_centre(a, b, h, le):
    """E at the point under the centre of an a x b Lambertian rectangle at height h."""

    def corner(x, y):  # form factor, differential area to a parallel rectangle at a corner
        p, q = x / h, y / h
        return (
            p / math.sqrt(1 + p * p) * math.atan(q / math.sqrt(1 + p * p))
            + q / math.sqrt(1 + q * q) * math.atan(p / math.sqrt(1 + q * q))
        ) / (2 * math.pi)

    return math.pi * le * 4 * corner(a / 2, b / 2)


@pytest.mark.slow
@pytest.mark.parametrize("integrator", ["direct", "path"])
def test_direct_irradiance_under_rectangle_light(integrator):
    """Diffuse floor under a one-sided rectangular light: L = albedo / pi * E (closed form)."""
    a, b, h, le, albedo = 1.0, 0.6, 0.8, 3.0, 0.6
    floor = quad([[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]])  # normal +y
    light = quad([[-a / 2, h, -b / 2], [a / 2, h, -b / 2], [a / 2, h, b / 2], [-a / 2, h, b / 2]])
    v, f = merge(floor, light)
    n_floor = 2
    mat = np.zeros(len(f), int)
    emit = np.where(np.arange(len(f)) < n_floor, -1, 0)
    scene = RenderScene.from_triangles(v, f, mat, constant_table(albedo), emit, constant_table(le))
    # A narrow camera between light and floor, looking straight down at the centre.
    cam = PinholeCamera.from_look_at(
        np.array([0, h / 2, 0]), np.zeros(3), np.array([0.0, 0, 1]), 1.0, 8, 8
    )
    xyz = render(
        scene,
        camera=cam,
        spp=256,
        max_depth=2,
        integrator=integrator,
        seed=3,
        progress=False,
        return_xyz=True,
    )
    expected = albedo / math.pi * _irradiance_below_rectangle_centre(a, b, h, le)
    assert np.mean(xyz[..., 1]) == pytest.approx(expected, rel=5e-3)
