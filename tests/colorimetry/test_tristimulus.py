"""sd_to_XYZ (emissive and reflective), tristimulus weights, XYZ <-> xyY <-> xy."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads

import radiometria.colorimetry as rc
from radiometria.constants import K_M

colour = pytest.importorskip("colour")

WL1 = np.arange(360.0, 831.0)
WL5 = np.arange(360.0, 831.0, 5.0)


def _colour_sd_to_XYZ(R, wl, illuminant=None, k=None):
    """colour-science's method "Integration" on the same grid (arrays + explicit shape)."""
    shape = colour.SpectralShape(wl[0], wl[-1], wl[1] - wl[0])
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    if illuminant is None:
        ill = colour.sd_ones(shape)
    else:
        ill = colour.SpectralDistribution(illuminant, wl)
    return colour.colorimetry.sd_to_XYZ_integration(R, cmfs, ill, k=k, shape=shape)


@pytest.mark.parametrize("wl", [WL1, WL5], ids=["1nm", "5nm"])
def test_sd_to_XYZ_reflective_matches_colour(wl):
    rng = np.random.default_rng(0)
    R = rng.uniform(0, 1, (7, wl.size))
    S = np.asarray(rc.daylight_spd(6504.0, jnp.asarray(wl)))
    ours = rc.sd_to_XYZ(R, wl, illuminant=S)
    ref = _colour_sd_to_XYZ(R, wl, S) / 100.0
    np.testing.assert_allclose(ours, ref, rtol=1e-12)


@pytest.mark.parametrize("wl", [WL1, WL5], ids=["1nm", "5nm"])
def test_sd_to_XYZ_emissive_matches_colour(wl):
    rng = np.random.default_rng(1)
    L = rng.uniform(0, 0.01, (5, wl.size))  # W sr^-1 m^-2 nm^-1
    ours = rc.sd_to_XYZ(L, wl)
    # colour divides by 100 when k is given.
    ref = _colour_sd_to_XYZ(L, wl, None, k=K_M) * 100.0
    np.testing.assert_allclose(ours, ref, rtol=1e-12)


def test_sd_to_XYZ_vs_colour_spectral_distribution_documented_difference():
    # colour interpolates a 5 nm spectrum to the 1 nm CMF grid (Sprague); we sample the CMFs on
    # the 5 nm grid (CIE 15). For smooth spectra the two agree to ~1e-4 relative.
    R = 0.5 + 0.4 * np.sin(WL5 / 40.0)
    sd = colour.SpectralDistribution(R, WL5)
    ref = colour.sd_to_XYZ(sd, method="Integration", illuminant=colour.SDS_ILLUMINANTS["D65"]) / 100
    ours = rc.sd_to_XYZ(R, WL5, illuminant="D65")
    np.testing.assert_allclose(ours, ref, rtol=2e-3)


def test_sd_to_XYZ_perfect_reflector_has_Y_one():
    for ill in ["A", "D50", "D65", "FL2"]:
        wl = np.arange(380.0, 781.0, 5.0)
        XYZ = rc.sd_to_XYZ(np.ones(wl.size), wl, illuminant=ill)
        assert abs(float(XYZ[1]) - 1.0) < 1e-14


def test_sd_to_XYZ_d65_chromaticity_thesis_table():
    # D65 at 1 nm (CIE: linear interpolation of the 5 nm table), emissive; thesis table 2.1.
    d65 = rc.get_illuminant("D65")
    S = np.interp(WL1, np.asarray(d65.wavelengths_nm), np.asarray(d65.values))
    xy = rc.XYZ_to_xy(rc.sd_to_XYZ(S, WL1))
    np.testing.assert_allclose(xy, [0.3127, 0.3290], atol=5e-5)
    a = rc.get_illuminant("A")
    S = np.interp(WL1, np.asarray(a.wavelengths_nm), np.asarray(a.values))
    np.testing.assert_allclose(rc.XYZ_to_xy(rc.sd_to_XYZ(S, WL1)), [0.4476, 0.4075], atol=1e-4)


def test_sd_to_XYZ_emissive_luminance_units():
    # A flat 1 W sr^-1 m^-2 nm^-1 spectrum: Y = K_m * integral of ybar (~106.86 nm).
    Y = rc.sd_to_XYZ(np.ones(WL1.size), WL1)[1]
    ybar = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].values[:, 1]
    np.testing.assert_allclose(Y, K_M * ybar.sum(), rtol=1e-14)


def test_tristimulus_weights_fast_path():
    rng = np.random.default_rng(2)
    R = rng.uniform(size=(11, WL5.size))
    for ill in [None, "D65"]:
        W = rc.tristimulus_weights(WL5, ill)
        assert W.shape == (WL5.size, 3)
        np.testing.assert_allclose(R @ np.asarray(W), rc.sd_to_XYZ(R, WL5, ill), rtol=1e-13)


def test_sd_to_XYZ_batched_illuminant():
    rng = np.random.default_rng(3)
    R = rng.uniform(size=(4, WL5.size))
    S = rng.uniform(0.5, 1.5, size=(4, WL5.size))
    out = rc.sd_to_XYZ(R, WL5, illuminant=S)
    loop = np.stack([rc.sd_to_XYZ(R[i], WL5, illuminant=S[i]) for i in range(4)])
    np.testing.assert_allclose(out, loop, rtol=1e-13)


def test_sd_to_XYZ_batch_shapes_jit_vmap_grad():
    rng = np.random.default_rng(4)
    R = jnp.asarray(rng.uniform(size=(2, 3, WL5.size)))
    eager = rc.sd_to_XYZ(R, WL5, "D65")
    assert eager.shape == (2, 3, 3)
    jitted = jax.jit(lambda r, w: rc.sd_to_XYZ(r, w, "D65"))(R, jnp.asarray(WL5))
    np.testing.assert_allclose(jitted, eager, rtol=1e-14)
    vm = jax.vmap(lambda r: rc.sd_to_XYZ(r, WL5, "D65"))(R.reshape(6, -1))
    np.testing.assert_allclose(vm.reshape(2, 3, 3), eager, rtol=1e-14)
    check_grads(
        jax.jit(lambda r: rc.sd_to_XYZ(r, WL5, "D65")), (R[0, 0],), order=2, modes=["fwd", "rev"]
    )
    check_grads(
        jax.jit(lambda s: rc.sd_to_XYZ(R[0, 0], WL5, s)),
        (jnp.asarray(rng.uniform(0.5, 1, WL5.size)),),
        order=1,
    )


def test_sd_to_XYZ_float32():
    R = jnp.asarray(np.random.default_rng(5).uniform(size=(3, WL5.size)), dtype=jnp.float32)
    out = rc.sd_to_XYZ(R, jnp.asarray(WL5, dtype=jnp.float32), "D65")
    assert out.dtype == jnp.float32
    np.testing.assert_allclose(out, rc.sd_to_XYZ(np.asarray(R, np.float64), WL5, "D65"), rtol=1e-5)


def test_sd_to_XYZ_bad_input():
    with pytest.raises(ValueError, match="values"):
        rc.sd_to_XYZ(np.ones(10), WL5)
    with pytest.raises(ValueError, match="illuminant"):
        rc.sd_to_XYZ(np.ones(WL5.size), WL5, illuminant=np.ones(3))
    with pytest.raises(ValueError, match="CIE 1964 10 Degree Standard Observer"):
        rc.sd_to_XYZ(np.ones(WL5.size), WL5, observer="CIE 1931 3 Degree")
    with pytest.raises(ValueError, match="observer"):
        rc.sd_to_XYZ(np.ones(WL5.size), WL5, observer="Wright & Guild 1931 2 Degree RGB CMFs")
    with pytest.raises(ValueError, match="'D65'"):
        rc.sd_to_XYZ(np.ones(WL5.size), WL5, illuminant="D66")
    with pytest.raises(TypeError):
        rc.sd_to_XYZ(np.ones(WL5.size, dtype=np.int64), WL5)
    with pytest.raises(TypeError):
        rc.sd_to_XYZ(np.ones(WL5.size), np.arange(360, 831, 5))
    with pytest.raises(ValueError, match="increasing"):
        rc.sd_to_XYZ(np.ones(WL5.size), WL5[::-1].copy())


def test_sd_to_XYZ_nan_propagates_per_spectrum():
    R = np.ones((3, WL5.size))
    R[1, 10] = np.nan
    R[2, 20] = np.inf
    out = np.asarray(rc.sd_to_XYZ(R, WL5, "D65"))
    assert np.all(np.isfinite(out[0]))
    assert np.all(np.isnan(out[1]))
    assert not np.all(np.isfinite(out[2]))


def test_xyY_roundtrips_and_colour():
    rng = np.random.default_rng(6)
    XYZ = rng.uniform(0.01, 1, (50, 3))
    np.testing.assert_allclose(rc.XYZ_to_xyY(XYZ), colour.XYZ_to_xyY(XYZ), rtol=1e-14)
    np.testing.assert_allclose(rc.XYZ_to_xy(XYZ), colour.XYZ_to_xy(XYZ), rtol=1e-14)
    np.testing.assert_allclose(rc.xyY_to_XYZ(rc.XYZ_to_xyY(XYZ)), XYZ, rtol=1e-14)
    xy = rc.XYZ_to_xy(XYZ)
    np.testing.assert_allclose(rc.xy_to_XYZ(xy), colour.xy_to_XYZ(np.asarray(xy)), rtol=1e-14)
    np.testing.assert_allclose(rc.xyY_to_xy(rc.xy_to_xyY(xy, 0.3)), xy)


def test_xyY_black_is_finite_with_finite_gradient():
    assert np.all(np.asarray(rc.XYZ_to_xyY(np.zeros(3))) == 0)
    g = jax.grad(lambda v: rc.XYZ_to_xy(v).sum())(jnp.zeros(3))
    assert np.all(np.isfinite(g))
    check_grads(jax.jit(rc.XYZ_to_xyY), (jnp.array([0.3, 0.4, 0.5]),), order=2)


def test_xyY_error_on_wrong_channel_count():
    # ValueError from the library; jaxtyping's TypeCheckError first when pytest enables it.
    with pytest.raises((ValueError, TypeError), match="3"):
        rc.XYZ_to_xy(np.ones((4, 2)))


def test_sd_to_XYZ_under_eqx_filter_jit():
    f = eqx.filter_jit(rc.sd_to_XYZ)
    R = jnp.ones(WL5.size)
    np.testing.assert_allclose(f(R, WL5), rc.sd_to_XYZ(R, WL5), rtol=1e-14)


# --- CIE 1931 RGB (thesis eq. 2.6-2.10) ------------------------------------------------------

WL_RGB = np.arange(380.0, 781.0, 5.0)  # the grid of the Wright & Guild table: no interpolation


def _colour_sd_to_CIE_RGB(R, wl, illuminant, k):
    """colour's "Integration" with the Wright & Guild r̄ḡb̄ as CMFs and an explicit k."""
    shape = colour.SpectralShape(wl[0], wl[-1], wl[1] - wl[0])
    cmfs = colour.MSDS_CMFS["Wright & Guild 1931 2 Degree RGB CMFs"]
    ill = (
        colour.sd_ones(shape) if illuminant is None else colour.SpectralDistribution(illuminant, wl)
    )
    # colour divides by 100 when k is given.
    return colour.colorimetry.sd_to_XYZ_integration(R, cmfs, ill, k=k, shape=shape) * 100.0


def test_sd_to_CIE_RGB_matches_colour():
    # colour-science's Wright & Guild 1931 2 degree RGB CMFs (Broadbent 2009, via CVRL): the
    # same table that radiometria packages, used through colour's own integration code.
    rng = np.random.default_rng(6)
    L = rng.uniform(0, 0.01, (5, WL_RGB.size))  # W sr^-1 m^-2 nm^-1
    np.testing.assert_allclose(
        rc.sd_to_CIE_RGB(L, WL_RGB), _colour_sd_to_CIE_RGB(L, WL_RGB, None, K_M), rtol=1e-12
    )
    # Reflective: normalised by the luminance of the illuminant, Y_RGB = R + 4.5907 G + 0.0601 B.
    R = rng.uniform(0, 1, (5, WL_RGB.size))
    S = np.asarray(rc.daylight_spd(5003.0, jnp.asarray(WL_RGB)))
    rgb_bar = colour.MSDS_CMFS["Wright & Guild 1931 2 Degree RGB CMFs"].values
    k = 1.0 / np.sum(S * (rgb_bar @ [1.0, 4.5907, 0.0601]) * 5.0)
    np.testing.assert_allclose(
        rc.sd_to_CIE_RGB(R, WL_RGB, illuminant=S),
        _colour_sd_to_CIE_RGB(R, WL_RGB, S, k),
        rtol=1e-12,
    )


def test_sd_to_CIE_RGB_agrees_with_sd_to_XYZ_through_eq_2_11():
    # Eq. 2.11 maps the RGB tristimulus values onto XYZ; the two CIE tabulations agree to
    # about 1e-3 of their peaks, so broadband spectra agree to about that relative accuracy.
    wl = WL_RGB
    spectra = np.stack(
        [
            np.asarray(rc.get_illuminant("D65")(jnp.asarray(wl))) * 1e-3,
            np.asarray(rc.get_illuminant("A")(jnp.asarray(wl))) * 1e-3,
            1e-3 * (1.0 + np.sin(wl / 30.0)),
        ]
    )
    rgb = rc.sd_to_CIE_RGB(spectra, wl)
    XYZ = rc.sd_to_XYZ(spectra, wl)
    np.testing.assert_allclose(rc.CIE_RGB_to_XYZ(rgb), XYZ, rtol=2e-3)
    # Eq. 2.10: the luminance of R, G, B is the Y of the same spectrum, in cd m^-2.
    np.testing.assert_allclose(rc.CIE_RGB_luminance(rgb), XYZ[:, 1], rtol=1e-3)
    np.testing.assert_allclose(rc.CIE_RGB_luminance(rgb), rc.CIE_RGB_to_XYZ(rgb)[:, 1], rtol=1e-14)
    # A perfect reflector has luminance factor exactly 1.
    for ill in ("D65", "A"):
        white = rc.sd_to_CIE_RGB(np.ones(wl.size), wl, illuminant=ill)
        assert float(rc.CIE_RGB_luminance(white)) == pytest.approx(1.0, abs=1e-14)


def test_CIE_RGB_luminance_thesis_eq_2_10():
    np.testing.assert_allclose(rc.CIE_RGB_luminance(np.eye(3)), [1.0, 4.5907, 0.0601])
    # The equal-energy spectrum E has R = G = B in the CIE 1931 RGB system (its white point),
    # so its luminance is (1 + 4.5907 + 0.0601) R.
    rgb = rc.sd_to_CIE_RGB(np.ones(WL_RGB.size), WL_RGB)
    np.testing.assert_allclose(rgb / rgb[0], 1.0, rtol=5e-4)
    # ValueError from the library, or jaxtyping's TypeCheckError (a TypeError) under pytest.
    with pytest.raises((ValueError, TypeError), match="RGB"):
        rc.CIE_RGB_luminance(np.ones(2))


def test_sd_to_CIE_RGB_spectral_colours_have_negative_lobes():
    # A narrow band at 500 nm lies outside the triangle of the 1931 primaries: R < 0.
    L = np.exp(-0.5 * ((WL_RGB - 500.0) / 5.0) ** 2)
    R, G, B = np.asarray(rc.sd_to_CIE_RGB(L, WL_RGB))
    assert R < 0 < G and B > 0


def test_sd_to_CIE_RGB_jit_vmap_grad_batched_illuminant():
    rng = np.random.default_rng(7)
    R = jnp.asarray(rng.uniform(size=(2, WL_RGB.size)))
    S = jnp.asarray(rng.uniform(0.5, 1.5, size=(2, WL_RGB.size)))
    eager = rc.sd_to_CIE_RGB(R, WL_RGB, illuminant=S)
    loop = np.stack([rc.sd_to_CIE_RGB(R[i], WL_RGB, illuminant=S[i]) for i in range(2)])
    np.testing.assert_allclose(eager, loop, rtol=1e-13)
    np.testing.assert_allclose(
        jax.jit(lambda r, s: rc.sd_to_CIE_RGB(r, WL_RGB, s))(R, S), eager, rtol=1e-14
    )
    np.testing.assert_allclose(
        jax.vmap(lambda r, s: rc.sd_to_CIE_RGB(r, WL_RGB, s))(R, S), eager, rtol=1e-14
    )
    # Linear in the spectrum: the Jacobian is the weight matrix; a finite-difference check in
    # the illuminant, where the normalisation makes it non-linear.
    J = jax.jacrev(lambda r: rc.sd_to_CIE_RGB(r, WL_RGB))(R[0])
    np.testing.assert_allclose(J, rc.sd_to_CIE_RGB(np.eye(WL_RGB.size), WL_RGB).T, rtol=1e-14)
    check_grads(lambda s: rc.sd_to_CIE_RGB(R[0], WL_RGB, s), (S[0],), order=1, modes="rev")


def test_sd_to_XYZ_points_rgb_observer_to_sd_to_CIE_RGB():
    with pytest.raises(ValueError, match="sd_to_CIE_RGB"):
        rc.sd_to_XYZ(np.ones(WL5.size), WL5, observer="CIE 1931 RGB")
    with pytest.raises(ValueError, match="values"):
        rc.sd_to_CIE_RGB(np.ones(10), WL_RGB)
