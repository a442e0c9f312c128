"""CIE D-series daylight: colour-science's sd_CIE_illuminant_D_series, packaged D65, grads."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads

import radiometria.colorimetry as rc

colour = pytest.importorskip("colour")


@pytest.mark.parametrize("rounding", [True, False])
def test_daylight_spd_matches_colour(rounding):
    wl = np.arange(300.0, 831.0, 5.0)
    for T in [4000.0, 5003.0, 6504.0, 9000.0, 25000.0]:
        ref = colour.sd_CIE_illuminant_D_series(
            colour.temperature.CCT_to_xy_CIE_D(T), M1_M2_rounding=rounding
        )
        np.testing.assert_allclose(ref.wavelengths, wl)
        np.testing.assert_allclose(
            rc.daylight_spd(T, wl, rounding=rounding), ref.values, rtol=1e-12, atol=1e-12
        )


def test_daylight_locus_matches_colour():
    T = np.linspace(4000.0, 25000.0, 50)
    np.testing.assert_allclose(
        rc.daylight_locus_xy(T), colour.temperature.CCT_to_xy_CIE_D(T), rtol=1e-13
    )


def test_daylight_spd_reproduces_packaged_D65():
    # D65 is the D series at 6500 K x 1.4388/1.4380, tabulated to 4-5 significant digits.
    wl = np.asarray(rc.get_illuminant("D65").wavelengths_nm)
    S = rc.daylight_spd(6500.0 * 1.4388 / 1.4380, wl)
    np.testing.assert_allclose(S, rc.get_illuminant("D65").values, atol=1e-3)


def test_daylight_spd_batch_interpolation_and_grad():
    wl = jnp.arange(380.0, 781.0, 1.0)
    T = jnp.array([[5000.0, 6500.0], [7500.0, 9000.0]])
    S = rc.daylight_spd(T, wl)
    assert S.shape == (2, 2, wl.size)
    np.testing.assert_allclose(S[0, 1], rc.daylight_spd(6500.0, wl), rtol=1e-14)
    # 1 nm values are linear interpolation of the 5 nm basis (CIE 15).
    S5 = rc.daylight_spd(6500.0, jnp.arange(380.0, 781.0, 5.0))
    np.testing.assert_allclose(S[0, 1, 2], 0.6 * S5[0] + 0.4 * S5[1], rtol=1e-13)
    np.testing.assert_allclose(jax.jit(rc.daylight_spd)(T, wl), S, rtol=1e-14)
    check_grads(
        jax.jit(lambda t: rc.daylight_spd(t, wl[::40], rounding=False)),
        (jnp.array(6000.0),),
        order=1,
    )


def test_daylight_bad_input():
    # ValueError from the library (jaxtyping's TypeCheckError first under pytest).
    with pytest.raises((ValueError, TypeError), match="wavelengths_nm"):
        rc.daylight_spd(6500.0, np.ones((2, 3)))
    with pytest.raises(Exception, match="cct"):
        rc.daylight_spd(-1.0, np.arange(400.0, 500.0))
