"""RGB albedo / unbounded / illuminant spectra (pbrt-v4 semantics) and the ColorChecker."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.upsampling as up


@pytest.fixture(scope="module")
def lut():
    return up.get_lut()


def _rgb_of(values, space="sRGB"):
    """Linear RGB of spectra sampled on the forward model's 1 nm grid (reflective)."""
    m = up.forward_model(space)
    return values @ m.weights_XYZ @ m.matrix_XYZ_to_RGB.T


def test_colorchecker_roundtrip(lut, colorchecker):
    """The 24 ColorChecker patches (N. Ohta's spectra -> sRGB) round-trip under 0.5 CIEDE2000."""
    wl, _, names, rgb = colorchecker
    de, _ = up.roundtrip_delta_E(lut, rgb)
    assert de.max() < 0.5, dict(zip(names, de.round(3), strict=True))
    # The albedo spectrum reproduces the colour: same measure, computed from the spectrum.
    spec = np.asarray(up.RGBAlbedoSpectrum(lut, rgb)(wl))
    np.testing.assert_allclose(_rgb_of(spec), rgb, atol=0.02)


def test_albedo_is_bounded(lut):
    rgb = np.random.default_rng(3).random((500, 3)) ** np.array([1.0, 2.0, 4.0])
    wl = np.linspace(360.0, 830.0, 471)
    s = np.asarray(up.RGBAlbedoSpectrum(lut, rgb)(wl))
    assert s.shape == (500, 471) and s.min() >= 0.0 and s.max() <= 1.0
    with pytest.raises(ValueError, match="> 1"):
        up.RGBAlbedoSpectrum(lut, np.array([1.5, 0.2, 0.1]))


def test_unbounded_keeps_the_scale(lut):
    rgb = np.array([[3.0, 1.5, 0.3], [0.2, 0.1, 0.05], [0.0, 0.0, 0.0], [7.0, 7.0, 7.0]])
    spec = up.RGBUnboundedSpectrum(lut, rgb)
    np.testing.assert_allclose(np.asarray(spec.scale), 2 * rgb.max(axis=1))
    wl = up.forward_model().wavelengths_nm
    v = np.asarray(spec(wl))
    assert np.all(v[2] == 0.0)
    np.testing.assert_allclose(v[3], 7.0, rtol=1e-12)  # grey: flat at 7
    out = _rgb_of(v)
    np.testing.assert_allclose(
        out[:2] / rgb[:2].max(1, keepdims=True), rgb[:2] / rgb[:2].max(1, keepdims=True), atol=0.01
    )
    assert np.asarray(spec(550.0)).shape == (4,)


def test_illuminant_white_is_the_normalised_illuminant(lut):
    m = up.forward_model("sRGB")
    wl = m.wavelengths_nm
    white = up.RGBIlluminantSpectrum(lut, np.array([1.0, 1.0, 1.0]), "sRGB")
    np.testing.assert_allclose(np.asarray(white(wl)), m.illuminant, rtol=1e-12)
    # Emission of RGB (1, 1, 1): Y = 1 in pbrt's relative convention, chromaticity of D65.
    import radiometria.colorimetry as cm

    cmf = np.asarray(cm.get_cmfs().values)
    XYZ = np.asarray(white(wl)) @ cmf / cmf[:, 1].sum()
    np.testing.assert_allclose(XYZ[1], 1.0, rtol=1e-12)
    np.testing.assert_allclose(XYZ[:2] / XYZ.sum(), [0.3127, 0.3290], atol=1e-4)
    assert np.asarray(white(300.0)) == 0.0 and np.asarray(white(900.0)) == 0.0
    # A colour: the emission over the illuminant reproduces the colour's chromaticity.
    rgb = np.array([2.0, 0.5, 0.25])
    e = np.asarray(up.RGBIlluminantSpectrum(lut, rgb)(wl)) / m.illuminant
    out = _rgb_of(e)
    np.testing.assert_allclose(out / out.max(), rgb / rgb.max(), atol=0.01)
    with pytest.raises(ValueError, match="colour space"):
        up.RGBIlluminantSpectrum(lut, rgb, "Display P3")


def test_spectra_jit_vmap_grad(lut):
    wl = jnp.linspace(400.0, 700.0, 4)

    def f(rgb):
        return jnp.sum(
            up.RGBAlbedoSpectrum(lut, rgb)(wl) + up.RGBIlluminantSpectrum(lut, 2 * rgb)(wl)
        )

    rgb = jnp.array([[0.2, 0.5, 0.1], [0.5, 0.5, 0.5], [0.0, 0.0, 0.0], [1.0, 0.0, 0.3]])
    g = jax.vmap(jax.grad(f))(rgb)
    assert np.all(np.isfinite(np.asarray(g)))
    np.testing.assert_allclose(
        np.asarray(jax.jit(jax.vmap(f))(rgb)), np.asarray(jax.vmap(f)(rgb)), rtol=1e-12
    )


def test_illuminant_table_is_looked_up_by_its_even_spacing():
    """The colour space's illuminant table (1 nm) is found evenly spaced, and its direct row
    lookup equals NumPy's interpolation of the table (0 outside), at and between the rows."""
    s = up.RGBIlluminantSpectrum(up.get_lut(), jnp.asarray([0.2, 0.5, 0.9]))
    assert s.illuminant_grid_nm == (360.0, 1.0)
    wl = np.concatenate([np.linspace(350.0, 840.0, 977), [360.0, 830.0, 555.0]])
    want = np.interp(wl, s.illuminant_wavelengths_nm, s.illuminant_values, left=0.0, right=0.0)
    np.testing.assert_allclose(np.asarray(s.illuminant(wl)), want, rtol=1e-12, atol=1e-15)
