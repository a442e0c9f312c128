"""Integrators: closed-form checks (white furnace, one-bounce irradiance) and conventions."""

import math

import jax.numpy as jnp
import numpy as np
import pytest

from radiometria.camera import PinholeCamera
from radiometria.render import Direct, Path, RenderScene, SpectrumTable, render, wavelength_grid_nm

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
    xyz = render(
        scene,
        camera=cam,
        spp=64,
        integrator=Path(max_depth=80),
        seed=1,
        progress=False,
        return_xyz=True,
    )
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
@pytest.mark.parametrize(
    "integrator",
    [Direct(), Direct(emitter_samples=2, bsdf_samples=3), Path(max_depth=2)],
    ids=["direct", "direct 2+3", "path"],
)
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
        integrator=integrator,
        seed=3,
        progress=False,
        return_xyz=True,
    )
    expected = albedo / math.pi * _irradiance_below_rectangle_centre(a, b, h, le)
    assert np.mean(xyz[..., 1]) == pytest.approx(expected, rel=5e-3)


def _emitter_in_view():
    """A large one-sided quad light filling a narrow camera's view (seen from its front)."""
    v, f = quad([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]])  # normal +z
    cam = PinholeCamera.from_look_at(
        np.array([0.0, 0, 2]), np.zeros(3), np.array([0.0, 1, 0]), 10.0, 8, 8
    )
    return v, f, cam


@pytest.mark.slow
def test_blackbody_emitter_seen_directly():
    """A blackbody light (thesis eq. 1.24) seen directly: Y = s int B(l, T) ybar / int ybar."""
    from radiometria.colorimetry import get_cmfs
    from radiometria.radiometry import BlackbodySpectrum
    from radiometria.render import tabulate_spectrum
    from radiometria.upsampling import RGBIlluminantSpectrum

    temperature, scale = 4000.0, 1e-4
    values = tabulate_spectrum(BlackbodySpectrum(temperature, scale), RGBIlluminantSpectrum)
    grid = wavelength_grid_nm()
    cmfs = get_cmfs()
    ybar = np.interp(grid, np.asarray(cmfs.wavelengths_nm), np.asarray(cmfs.values)[:, 1])
    expected = np.trapezoid(values * ybar, grid) / np.trapezoid(ybar, grid)
    v, f, cam = _emitter_in_view()
    table = SpectrumTable(jnp.asarray(values[None], jnp.float32))
    scene = RenderScene.from_triangles(v, f, [0, 0], constant_table(0.0), [0, 0], table)
    xyz = render(
        scene, camera=cam, spp=64, integrator=Path(max_depth=1), progress=False, return_xyz=True
    )
    assert np.mean(xyz[..., 1]) == pytest.approx(expected, rel=5e-3)


def test_tabulate_spectrum_forms():
    """Scene spectra on the 1 nm grid: tabulated (zero outside), constant, blackbody, RGB."""
    from radiometria.radiometry import BlackbodySpectrum, PiecewiseLinearSpectrum, planck
    from radiometria.render import LinearRGB, tabulate_spectrum
    from radiometria.upsampling import RGBAlbedoSpectrum, RGBIlluminantSpectrum

    grid = wavelength_grid_nm()
    measured = PiecewiseLinearSpectrum(np.array([400.0, 500.0]), np.array([1.0, 3.0]))
    tab = tabulate_spectrum(measured, RGBAlbedoSpectrum)
    assert tab.dtype == np.float64 and tab.shape == grid.shape
    np.testing.assert_allclose(tab[grid == 450.0], 2.0)
    assert tab[grid == 399.0] == 0.0 and tab[grid == 501.0] == 0.0
    np.testing.assert_allclose(tabulate_spectrum(0.25, RGBAlbedoSpectrum), 0.25)
    bb = tabulate_spectrum(BlackbodySpectrum(5000.0, 2.0), RGBIlluminantSpectrum)
    np.testing.assert_allclose(bb, 2.0 * np.asarray(planck(grid, 5000.0)), rtol=1e-6)
    grey = tabulate_spectrum(LinearRGB(np.array([0.5, 0.5, 0.5])), RGBAlbedoSpectrum)
    np.testing.assert_allclose(grey, 0.5, atol=1e-3)
    with pytest.raises(ValueError, match="reflectance"):
        tabulate_spectrum(LinearRGB(np.array([1.5, 0.2, 0.2])), RGBAlbedoSpectrum)
    with pytest.raises(TypeError, match=r"(?s)LinearRGB.*wood\.png|wood\.png.*LinearRGB"):
        tabulate_spectrum("wood.png", RGBAlbedoSpectrum)


def test_sample_hero_wavelengths_stratified_and_unbiased():
    """Four wavelengths per variate, rotated by 1/4 in the CDF; E[1/p] = 830 - 360 nm."""
    import jax

    from radiometria.montecarlo import invert_visible_wavelengths_sample
    from radiometria.render import sample_hero_wavelengths

    u = jax.random.uniform(jax.random.key(0), (200_000,), dtype=jnp.float64)
    wl, pdf = sample_hero_wavelengths(u)
    assert wl.shape == pdf.shape == (200_000, 4)
    assert np.all((np.asarray(wl) >= 360.0) & (np.asarray(wl) <= 830.0))
    cdf = np.asarray(invert_visible_wavelengths_sample(wl))
    np.testing.assert_allclose(
        np.mod(cdf - cdf[:, :1], 1.0), [[0, 0.25, 0.5, 0.75]] * len(u), atol=1e-6
    )
    assert np.mean(1.0 / np.asarray(pdf)) == pytest.approx(470.0, rel=2e-3)


def test_path_radiance_takes_a_sample_array():
    """The array form of `u`: its shape is checked; max_depth 1 returns emission only."""
    from radiometria.render import path_radiance, sample_dimensions

    v, f, cam = _emitter_in_view()
    scene = RenderScene.from_triangles(
        v, f, [0, 0], constant_table(0.5), [0, 0], constant_table(2.0)
    )
    o = jnp.asarray([[0.0, 0, 2], [0.0, 0, 2]], jnp.float32)
    d = jnp.asarray([[0.0, 0, -1], [0.0, 0, 1]], jnp.float32)  # the light, then away from it
    wl = jnp.full((2, 4), 550.0, jnp.float32)
    assert sample_dimensions(1) == 0 and sample_dimensions(3) == 16
    out = path_radiance(scene, o, d, wl, jnp.zeros((2, 0), jnp.float32), max_depth=1)
    np.testing.assert_allclose(np.asarray(out), [[2.0] * 4, [0.0] * 4])
    u = jnp.full((2, sample_dimensions(3)), 0.5, jnp.float32)
    out = path_radiance(scene, o, d, wl, u, max_depth=3)
    np.testing.assert_allclose(np.asarray(out), [[2.0] * 4, [0.0] * 4])  # nothing to reflect
    with pytest.raises(ValueError, match="u"):
        path_radiance(scene, o, d, wl, jnp.zeros((2, 5), jnp.float32), max_depth=3)
    with pytest.raises(ValueError, match="max_depth"):
        path_radiance(scene, o, d, wl, u, max_depth=0)


@pytest.mark.slow
def test_scene_without_emitters_renders_black():
    v, f = inward_cube()
    zero = np.zeros(len(f), int)
    no_light = SpectrumTable(jnp.zeros((0, wavelength_grid_nm().shape[0]), jnp.float32))
    scene = RenderScene.from_triangles(v, f, zero, constant_table(0.5), zero - 1, no_light)
    cam = PinholeCamera.from_look_at(
        np.zeros(3), np.array([0.0, 0, 1]), np.array([0.0, 1, 0]), 60.0, 8, 8
    )
    img = np.asarray(render(scene, camera=cam, spp=2, integrator=Path(max_depth=3), progress=False))
    np.testing.assert_array_equal(img, 0.0)
