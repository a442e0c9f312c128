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


# --- CIELUV ----------------------------------------------------------------------------------


def test_XYZ_to_Luv_matches_colour():
    for w in (D65, D50):
        xy_w = colour.XYZ_to_xy(w)
        Luv = colour.XYZ_to_Luv(XYZ, xy_w)
        np.testing.assert_allclose(rc.XYZ_to_Luv(XYZ, w), Luv, rtol=1e-12, atol=1e-11)
        np.testing.assert_allclose(
            rc.Luv_to_XYZ(Luv, w), colour.Luv_to_XYZ(Luv, xy_w), rtol=1e-11, atol=1e-14
        )
        np.testing.assert_allclose(
            rc.Luv_to_uv(Luv, w), colour.Luv_to_uv(Luv, xy_w), rtol=1e-11, atol=1e-14
        )
        uv = np.asarray(rc.XYZ_to_Luv_uv(XYZ))
        L = RNG.uniform(1.0, 100.0, len(XYZ))
        np.testing.assert_allclose(
            rc.uv_to_Luv(uv, w, L), colour.uv_to_Luv(uv, xy_w, L), rtol=1e-10, atol=1e-10
        )
    np.testing.assert_allclose(rc.XYZ_to_Luv(XYZ), colour.XYZ_to_Luv(XYZ), rtol=1e-12, atol=1e-11)
    # The white itself has L* = 100 and u* = v* = 0.
    np.testing.assert_allclose(rc.XYZ_to_Luv(D50, D50), [100.0, 0.0, 0.0], atol=1e-12)


def test_Luv_roundtrips_and_LCHuv_matches_colour():
    Luv = np.asarray(rc.XYZ_to_Luv(XYZ, D50))
    np.testing.assert_allclose(rc.Luv_to_XYZ(Luv, D50), XYZ, rtol=1e-11, atol=1e-15)
    LCHuv = rc.Luv_to_LCHuv(Luv)
    np.testing.assert_allclose(LCHuv, colour.Luv_to_LCHuv(Luv), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(rc.LCHuv_to_Luv(LCHuv), Luv, rtol=1e-12, atol=1e-11)
    np.testing.assert_allclose(
        rc.LCHuv_to_Luv(LCHuv), colour.LCHuv_to_Luv(np.asarray(LCHuv)), rtol=1e-12, atol=1e-11
    )
    uv = rc.Luv_to_uv(Luv, D50)
    np.testing.assert_allclose(uv, rc.XYZ_to_Luv_uv(XYZ), rtol=1e-11)
    np.testing.assert_allclose(rc.uv_to_Luv(uv, D50, Luv[:, 0]), Luv, rtol=1e-10, atol=1e-9)
    # One white per colour.
    whites = np.where(np.arange(7)[:, None] % 2 == 0, D50, D65)  # (7, 3)
    out = rc.XYZ_to_Luv(XYZ[:7], whites)
    np.testing.assert_allclose(out[::2], Luv[:7:2], rtol=1e-13)
    np.testing.assert_allclose(rc.Luv_to_XYZ(out, whites), XYZ[:7], rtol=1e-11)


def test_Luv_black_is_finite_with_finite_gradients():
    np.testing.assert_allclose(rc.XYZ_to_Luv(np.zeros(3)), 0.0)
    np.testing.assert_allclose(rc.Luv_to_XYZ(np.zeros(3)), 0.0)
    np.testing.assert_allclose(rc.Luv_to_uv(np.zeros(3)), 0.0)
    for f, x in [
        (rc.XYZ_to_Luv, jnp.zeros(3)),
        (rc.Luv_to_XYZ, jnp.zeros(3)),
        (rc.Luv_to_LCHuv, jnp.array([50.0, 0.0, 0.0])),
    ]:
        assert np.all(np.isfinite(jax.jacfwd(f)(x))), f.__name__
        assert np.all(np.isfinite(jax.jacrev(f)(x))), f.__name__


def test_Luv_grads_jit_vmap():
    x = jnp.array([0.3, 0.4, 0.5])
    luv = jnp.array([60.0, 20.0, -30.0])
    batch = jnp.asarray(XYZ[:8])
    for f, arg in [
        (rc.XYZ_to_Luv, x),
        (rc.Luv_to_XYZ, luv),
        (rc.Luv_to_LCHuv, luv),
        (rc.LCHuv_to_Luv, jnp.array([60.0, 25.0, 200.0])),
        (rc.Luv_to_uv, luv),
    ]:
        check_grads(f, (arg,), order=1, modes="rev")
        inputs = batch if f is rc.XYZ_to_Luv else rc.XYZ_to_Luv(batch)
        np.testing.assert_allclose(jax.jit(f)(inputs), f(inputs), rtol=1e-13)
        np.testing.assert_allclose(jax.vmap(f)(inputs), f(inputs), rtol=1e-13)
    with pytest.raises((ValueError, TypeError), match="Luv"):
        rc.Luv_to_XYZ(np.ones(2))
