"""Film: spectral samples -> XYZ -> RGB, normalisation, scatter-add accumulation, bad input."""

import colour
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.camera as cam
from radiometria.colorimetry import get_illuminant

CIE_MIN, CIE_MAX = 360.0, 830.0


def _midpoints(n):
    """Deterministic quadrature: n midpoints of [360, 830] nm with the uniform pdf."""
    wl = CIE_MIN + (np.arange(n) + 0.5) * (CIE_MAX - CIE_MIN) / n
    return wl, np.full(n, 1.0 / (CIE_MAX - CIE_MIN))


def test_constant_spectrum_gives_unit_luminance():
    film = cam.Film(2, 1)
    wl, pdf = _midpoints(4700)
    xyz = cam.film_samples_to_XYZ(film, jnp.ones((1, wl.size)), wl[None, :], pdf[None, :])
    assert float(xyz[0, 1]) == pytest.approx(1.0, abs=1e-5)
    # Equal-energy white: X = Y = Z up to the CIE table's own normalisation (CIE 015).
    np.testing.assert_allclose(xyz[0], [1.0, 1.0, 1.0], atol=2e-3)
    # ... and with random uniform wavelengths (4 per sample, hero style), within MC error.
    n, k = 20_000, 4
    lam = jax.random.uniform(jax.random.key(0), (n, k), minval=CIE_MIN, maxval=CIE_MAX)
    p = jnp.full((n, k), 1.0 / (CIE_MAX - CIE_MIN))
    film = cam.film_add_samples(film, jnp.zeros((n,), jnp.int32), jnp.ones((n, k)), lam, p)
    y = cam.film_develop(film, "XYZ")[0, 0, 1]
    per_sample = cam.film_samples_to_XYZ(film, jnp.ones((n, k)), lam, p)[:, 1]
    se = float(jnp.std(per_sample)) / np.sqrt(n)
    assert abs(float(y) - 1.0) < 5 * se
    assert float(cam.film_develop(film, "XYZ")[0, 1, 1]) == 0.0  # empty pixel stays black


def test_d65_white_develops_to_rgb_one():
    """D65 normalised to Y = 1 gives linear sRGB (1, 1, 1) (deterministic quadrature)."""
    film = cam.Film(1, 1)
    d65 = get_illuminant("D65")
    wl, pdf = _midpoints(2000)
    L = np.interp(wl, np.asarray(d65.wavelengths_nm), np.asarray(d65.values))
    xyz = cam.film_samples_to_XYZ(film, L[None, :], wl[None, :], pdf[None, :])
    L = L / float(xyz[0, 1])
    film = cam.film_add_samples(
        film, jnp.zeros((1,), jnp.int32), L[None, :], wl[None, :], pdf[None, :]
    )
    rgb = cam.film_develop(film, "sRGB")
    np.testing.assert_allclose(rgb[0, 0], [1.0, 1.0, 1.0], atol=2e-3)
    # The same through colour-science's own CMFs and sRGB matrix (independent implementation).
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    film_c = cam.Film(1, 1, cmfs=(cmfs.wavelengths, cmfs.values))
    film_c = cam.film_add_samples(
        film_c, jnp.zeros((1,), jnp.int32), L[None, :], wl[None, :], pdf[None, :]
    )
    m = colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB
    # colour's sRGB matrix is IEC 61966-2-1's rounded one; ours derives from the primaries.
    np.testing.assert_allclose(cam.film_develop(film_c, m)[0, 0], rgb[0, 0], atol=3e-4)


def test_xyz_matches_colour_science_for_a_smooth_spectrum():
    """XYZ of a spectrum is its integral against colour-science's CIE 1931 CMFs (linearly
    interpolated, fine trapezoid reference) divided by the integral of ybar."""
    wl, pdf = _midpoints(4700)
    spectrum = lambda x: 1.0 + 0.5 * np.sin(x / 40.0)  # noqa: E731
    film = cam.Film(1, 1)
    ours = np.asarray(
        cam.film_samples_to_XYZ(film, spectrum(wl)[None, :], wl[None, :], pdf[None, :])
    )
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    fine = np.linspace(CIE_MIN, CIE_MAX, 470_001)
    xbar = np.stack([np.interp(fine, cmfs.wavelengths, cmfs.values[:, c]) for c in range(3)], -1)
    ref = np.trapezoid(spectrum(fine)[:, None] * xbar, fine, axis=0)
    ref /= np.trapezoid(cmfs.values[:, 1], cmfs.wavelengths)
    np.testing.assert_allclose(ours[0], ref, rtol=2e-6)


def test_evenly_spaced_cmfs_are_looked_up_without_a_search():
    """The 1 nm CIE table is found evenly spaced, and its direct row lookup gives the XYZ of
    the searched lookup (a response without the grid); an uneven table keeps the search."""
    film = cam.Film(1, 1)
    assert film.cmf_grid_nm == (360.0, 1.0) and film.response.cmf_grid_nm == (360.0, 1.0)
    searched = cam.SpectralResponse(film.cmf_wavelengths_nm, film.cmf_values)
    assert searched.cmf_grid_nm is None
    rng = np.random.default_rng(3)
    wl = rng.uniform(350.0, 840.0, (64, 4))
    wl[0] = [360.0, 361.0, 829.5, 830.0]
    L, pdf = rng.random((64, 4)), rng.uniform(0.5, 2.0, (64, 4)) / 470.0
    direct = cam.film_samples_to_XYZ(film.response, L, wl, pdf)
    np.testing.assert_allclose(
        direct, cam.film_samples_to_XYZ(searched, L, wl, pdf), rtol=1e-12, atol=1e-15
    )
    uneven = cam.Film(
        1, 1, cmfs=(np.delete(film.cmf_wavelengths_nm, 5), np.delete(film.cmf_values, 5, 0))
    )
    assert uneven.cmf_grid_nm is None


def test_film_add_accepts_flat_xy_and_raster_pixels_and_drops_outside():
    film = cam.Film(4, 3, cmfs=_flat())
    xyz = jnp.asarray([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0], [1.0, 1.0, 1.0]])
    w = jnp.asarray([1.0, 2.0, 1.0, 5.0])
    a = cam.film_add_XYZ(film, jnp.asarray([5, 5, 11, 12], jnp.int32), xyz, w)
    b = cam.film_add_XYZ(film, jnp.asarray([[1, 1], [1, 1], [3, 2], [4, 0]], jnp.int32), xyz, w)
    c = cam.film_add_XYZ(
        film, jnp.asarray([[1.2, 1.9], [1.99, 1.0], [3.5, 2.5], [-0.1, 0.5]]), xyz, w
    )
    for f in (a, b, c):
        np.testing.assert_allclose(f.weight_sum[1, 1], 3.0)
        np.testing.assert_allclose(f.xyz_sum[1, 1], [9.0, 12.0, 15.0])
        np.testing.assert_allclose(f.xyz_sum[2, 3], [7.0, 8.0, 9.0])
        assert float(jnp.sum(f.weight_sum)) == 4.0  # the fourth sample fell outside and is dropped
        np.testing.assert_allclose(cam.film_develop(f, "XYZ")[1, 1], [3.0, 4.0, 5.0])
    merged = cam.film_merge(a, b)
    np.testing.assert_allclose(merged.weight_sum, 2 * a.weight_sum)


def _flat():
    return np.array([CIE_MIN, CIE_MAX]), np.ones((2, 3))


def test_film_accumulation_is_jittable_and_memory_bounded():
    film = cam.Film(8, 8, cmfs=_flat())
    add = eqx.filter_jit(cam.film_add_samples)
    key = jax.random.key(0)
    for k in jax.random.split(key, 3):  # same shapes: one compilation, sums grow
        ka, kb = jax.random.split(k)
        pix = jax.random.randint(ka, (1000,), 0, 64)
        lam = jax.random.uniform(kb, (1000, 4), minval=CIE_MIN, maxval=CIE_MAX)
        film = add(film, pix, jnp.ones((1000, 4)), lam, jnp.full((1000, 4), 1 / 470.0), 1.0)
    assert film.xyz_sum.shape == (8, 8, 3)
    assert float(jnp.sum(film.weight_sum)) == pytest.approx(3000.0)
    # A flat CMF of 1 divided by its integral 470: Y = L / p / 470 = 1 exactly per sample.
    np.testing.assert_allclose(cam.film_develop(film, "XYZ")[..., 1], 1.0, rtol=1e-12)


def test_film_float32():
    film = cam.Film(2, 2, dtype=jnp.float32)
    wl, pdf = _midpoints(64)
    film = cam.film_add_samples(
        film, jnp.zeros((1,), jnp.int32), jnp.ones((1, 64), jnp.float32),
        wl[None, :].astype(np.float32), pdf[None, :].astype(np.float32),
    )  # fmt: skip
    rgb = cam.film_develop(film)
    assert rgb.dtype == jnp.float32
    assert float(cam.film_develop(film, "XYZ")[0, 0, 1]) == pytest.approx(1.0, abs=1e-3)


def test_film_rejects_bad_input():
    with pytest.raises(ValueError, match="width"):
        cam.Film(0, 4)
    with pytest.raises(ValueError, match="height"):
        cam.Film(4, 0)
    with pytest.raises(TypeError, match="width"):
        cam.Film(4.0, 4)
    with pytest.raises(ValueError, match="cmfs"):
        cam.Film(2, 2, cmfs=(np.arange(3.0), np.ones((3, 2))))
    with pytest.raises(TypeError, match="cmfs"):
        cam.Film(2, 2, cmfs="CIE")
    film = cam.Film(2, 2, cmfs=_flat())
    with pytest.raises(ValueError, match="broadcast"):
        cam.film_samples_to_XYZ(film, jnp.ones((3, 4)), jnp.ones((3, 5)), jnp.ones((3, 4)))
    with pytest.raises(ValueError, match="XYZ"):
        cam.film_add_XYZ(film, jnp.zeros((3,), jnp.int32), jnp.ones((3, 4)))
    with pytest.raises(ValueError, match="pixel"):
        cam.film_add_XYZ(film, jnp.zeros((3, 3), jnp.int32), jnp.ones((3, 3)))
    with pytest.raises(ValueError, match="weight"):
        cam.film_add_XYZ(film, jnp.zeros((3,), jnp.int32), jnp.ones((3, 3)), jnp.ones((4,)))
    with pytest.raises(ValueError, match="colourspace"):
        cam.film_develop(film, np.eye(2))
    with pytest.raises(ValueError, match="sRGBB"):
        cam.film_develop(film, "sRGBB")
    with pytest.raises(TypeError, match="filter"):
        cam.splat_samples(film, jnp.zeros((2, 2)), jnp.zeros((2, 3)), "gaussian")
    with pytest.raises(ValueError, match="size"):
        cam.film_merge(film, cam.Film(3, 2, cmfs=_flat()))
