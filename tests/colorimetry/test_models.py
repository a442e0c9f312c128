"""CIELAB / LCh, uv / u'v', CIE 1931 RGB: colour-science, round trips, gradients."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads

import radiometria.colorimetry as rc

colour = pytest.importorskip("colour")

RNG = np.random.default_rng(0)
XYZ = RNG.uniform(0.0, 1.0, (200, 3))
XYZ[:5] *= 1e-3  # exercise the linear segment of f(t)
D65 = colour.xy_to_XYZ(np.array([0.3127, 0.3290]))
D50 = colour.xy_to_XYZ(np.array([0.3457, 0.3585]))


def test_XYZ_to_Lab_matches_colour():
    for w in (D65, D50):
        xy_w = colour.XYZ_to_xy(w)
        np.testing.assert_allclose(
            rc.XYZ_to_Lab(XYZ, w), colour.XYZ_to_Lab(XYZ, xy_w), rtol=1e-12, atol=1e-12
        )
        Lab = colour.XYZ_to_Lab(XYZ, xy_w)
        np.testing.assert_allclose(
            rc.Lab_to_XYZ(Lab, w), colour.Lab_to_XYZ(Lab, xy_w), rtol=1e-12, atol=1e-14
        )
    # Default white is D65 with Y = 1.
    np.testing.assert_allclose(rc.XYZ_to_Lab(XYZ), colour.XYZ_to_Lab(XYZ), rtol=1e-12, atol=1e-12)


def test_Lab_LCh_roundtrips_and_colour():
    Lab = np.asarray(rc.XYZ_to_Lab(XYZ))
    LCh = rc.Lab_to_LCh(Lab)
    np.testing.assert_allclose(LCh, colour.Lab_to_LCHab(Lab), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(rc.LCh_to_Lab(LCh), Lab, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(rc.Lab_to_XYZ(Lab), XYZ, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(
        rc.LCh_to_Lab(LCh), colour.LCHab_to_Lab(np.asarray(LCh)), rtol=1e-12, atol=1e-12
    )


def test_uv_matches_colour_and_roundtrips():
    xy = np.asarray(rc.XYZ_to_xy(XYZ))
    np.testing.assert_allclose(rc.xy_to_UCS_uv(xy), colour.xy_to_UCS_uv(xy), rtol=1e-13)
    np.testing.assert_allclose(rc.UCS_uv_to_xy(rc.xy_to_UCS_uv(xy)), xy, rtol=1e-13)
    np.testing.assert_allclose(
        rc.XYZ_to_UCS_uv(XYZ), colour.UCS_to_uv(colour.XYZ_to_UCS(XYZ)), rtol=1e-13
    )
    np.testing.assert_allclose(rc.xy_to_Luv_uv(xy), colour.xy_to_Luv_uv(xy), rtol=1e-13)
    np.testing.assert_allclose(rc.Luv_uv_to_xy(rc.xy_to_Luv_uv(xy)), xy, rtol=1e-13)
    np.testing.assert_allclose(
        rc.XYZ_to_Luv_uv(XYZ), colour.xy_to_Luv_uv(colour.XYZ_to_xy(XYZ)), rtol=1e-12
    )


def test_CIE_RGB_thesis_matrix():
    # Eq. 2.10: Y = 1.0000 R + 4.5907 G + 0.0601 B; the RGB CMFs map to the XYZ CMFs.
    np.testing.assert_allclose(rc.CIE_RGB_to_XYZ(np.eye(3))[:, 1], [1.0, 4.5907, 0.0601])
    rgb = rc.get_cmfs("CIE 1931 RGB")
    xyz = rc.get_cmfs()
    wl = np.asarray(rgb.wavelengths_nm)
    mapped = np.asarray(rc.CIE_RGB_to_XYZ(rgb.values))
    ref = np.asarray(xyz(jnp.asarray(wl)))
    # colour's Wright & Guild CMFs are in the thesis's luminance-unit normalisation, so the
    # matrix maps them onto xbar, ybar, zbar (to the 4-5 digits of the tabulations).
    np.testing.assert_allclose(mapped, ref, atol=2e-3 * ref.max())
    v = RNG.uniform(size=(7, 3))
    np.testing.assert_allclose(rc.XYZ_to_CIE_RGB(rc.CIE_RGB_to_XYZ(v)), v, rtol=1e-12)


def test_models_grads_jit_vmap():
    x = jnp.array([0.3, 0.4, 0.5])
    for f in (
        rc.XYZ_to_Lab,
        rc.XYZ_to_UCS_uv,
        rc.XYZ_to_Luv_uv,
        lambda v: rc.Lab_to_LCh(rc.XYZ_to_Lab(v)),
    ):
        check_grads(jax.jit(f), (x,), order=1, modes=["fwd", "rev"])
        batch = jnp.asarray(XYZ[:8])
        np.testing.assert_allclose(jax.jit(f)(batch), f(batch), rtol=1e-13)
        np.testing.assert_allclose(jax.vmap(f)(batch), f(batch), rtol=1e-13)
    check_grads(jax.jit(rc.Lab_to_XYZ), (jnp.array([50.0, 10.0, -20.0]),), order=2)
    check_grads(jax.jit(rc.LCh_to_Lab), (jnp.array([50.0, 10.0, 120.0]),), order=2)
    # Neutral colour: hue 0 and finite gradient.
    g = jax.jacfwd(rc.Lab_to_LCh)(jnp.array([50.0, 0.0, 0.0]))
    assert np.all(np.isfinite(g))
    assert np.all(np.isfinite(jax.grad(lambda v: rc.XYZ_to_Lab(v).sum())(jnp.zeros(3))))


def test_models_nan_propagates():
    out = rc.XYZ_to_Lab(np.array([np.nan, 0.5, 0.5]))
    assert np.isnan(float(out[1]))
    assert np.isnan(float(rc.Lab_to_LCh(np.array([50.0, np.nan, 1.0]))[1]))
