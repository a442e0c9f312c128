"""Planckian locus and CCT: colour-science (Ohno 2013, Robertson 1968, McCamy 1992), thesis
table 2.1, round trips, jit / vmap / grad, bad input."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads

import radiometria.colorimetry as rc
from radiometria.constants import C2

colour = pytest.importorskip("colour")

CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]  # colour's defaults trim to 780 nm
C2_CIE = 1.4388e-2  # m K, CIE 15 / colour-science convention
RNG = np.random.default_rng(0)
T_REF = RNG.uniform(1500.0, 20000.0, 100)
DUV_REF = RNG.uniform(-0.03, 0.03, 100)


def test_planckian_table_matches_colour():
    ours = rc.planckian_table(c2=C2_CIE)
    ref = colour.temperature.ohno2013.planckian_table(CMFS, 1000, 100000, 1.001)
    np.testing.assert_array_equal(ours[:, 0], ref[:, 0])
    np.testing.assert_allclose(ours[:, 1:], ref[:, 1:], rtol=1e-13)


def test_uv_to_CCT_ohno_matches_colour():
    uv = colour.temperature.CCT_to_uv_Ohno2013(np.stack([T_REF, DUV_REF], -1), cmfs=CMFS)
    ours = np.asarray(rc.uv_to_CCT(uv, c2=C2_CIE))
    ref = colour.temperature.uv_to_CCT_Ohno2013(uv, cmfs=CMFS)
    # Same table and formulas; our parabola is written in T - T_i (better conditioned).
    np.testing.assert_allclose(ours[:, 0], ref[:, 0], rtol=1e-9)
    np.testing.assert_allclose(ours[:, 1], ref[:, 1], atol=1e-10)
    # Default c2 (exact SI): the same locus at T * c2_SI / c2_CIE, up to Ohno's interpolation
    # error (~2e-7 relative; the table nodes sit at other points of the locus).
    si = np.asarray(rc.uv_to_CCT(uv))
    np.testing.assert_allclose(si[:, 0], ref[:, 0] * C2 / C2_CIE, rtol=5e-7)


def test_CCT_to_uv_matches_colour_and_roundtrips():
    uv = np.asarray(rc.CCT_to_uv(T_REF, DUV_REF, c2=C2_CIE))
    ref = colour.temperature.CCT_to_uv_Ohno2013(np.stack([T_REF, DUV_REF], -1), cmfs=CMFS)
    # colour takes the locus normal from a 0.01 K finite difference; we differentiate exactly.
    np.testing.assert_allclose(uv, ref, atol=1e-7)
    back = np.asarray(rc.uv_to_CCT(uv, c2=C2_CIE))
    np.testing.assert_allclose(back[:, 0], T_REF, rtol=1e-5)
    np.testing.assert_allclose(back[:, 1], DUV_REF, atol=1e-7)


def test_robertson_and_mccamy_match_colour():
    uv = colour.temperature.CCT_to_uv_Ohno2013(np.stack([T_REF, DUV_REF], -1), cmfs=CMFS)
    np.testing.assert_allclose(
        rc.uv_to_CCT(uv, "Robertson 1968"),
        colour.temperature.uv_to_CCT_Robertson1968(uv),
        rtol=1e-12,
        atol=1e-14,
    )
    xy = colour.UCS_uv_to_xy(uv)
    np.testing.assert_allclose(
        rc.xy_to_CCT(xy, "McCamy 1992"), colour.temperature.xy_to_CCT_McCamy1992(xy), rtol=1e-12
    )
    np.testing.assert_allclose(
        rc.xy_to_CCT(xy, "Robertson 1968"), rc.uv_to_CCT(uv, "Robertson 1968"), rtol=1e-12
    )


@pytest.mark.parametrize(
    "name, xy, cct",
    [  # Thesis table 2.1 (CIE 1931 2 deg xy, nominal CCT).
        ("A", (0.4476, 0.4075), 2856.0),
        ("D50", (0.3457, 0.3585), 5003.0),
        ("E", (1 / 3, 1 / 3), 5454.0),
        ("D55", (0.3324, 0.3474), 5503.0),
        ("D65", (0.3127, 0.3290), 6504.0),
    ],
)
def test_xy_to_CCT_thesis_table(name, xy, cct):
    # The printed xy are rounded to 4 decimals and the nominal D-series CCTs are 5000 K etc.
    # times 1.4388/1.4380, so the computed CCTs agree to a few K.
    for method in ["Ohno 2013", "Robertson 1968"]:
        T = float(rc.xy_to_CCT(np.asarray(xy), method, c2=C2_CIE)[0])
        assert abs(T - cct) < 3.0, (name, method, T)


def test_CCT_of_A_and_D65_from_their_spectra():
    for name, cct in [("A", 2856.0), ("D65", 6504.0)]:
        s = rc.get_illuminant(name)
        wl, v = np.asarray(s.wavelengths_nm), np.asarray(s.values)
        keep = wl >= 360.0
        xy = rc.XYZ_to_xy(rc.sd_to_XYZ(v[keep], wl[keep]))
        T, duv = np.asarray(rc.xy_to_CCT(xy, c2=C2_CIE))
        assert abs(T - cct) < 1.5, (name, T)
        if name == "A":
            assert abs(duv) < 1e-5  # A is a Planckian radiator


def test_CCT_to_xy_loci():
    T = np.array([4000.0, 6504.0, 10000.0, 25000.0])
    np.testing.assert_allclose(
        rc.CCT_to_xy(T, "daylight"), colour.temperature.CCT_to_xy_CIE_D(T), rtol=1e-13
    )
    xy = rc.CCT_to_xy(T, c2=C2_CIE)
    ref = colour.UCS_uv_to_xy(colour.temperature.CCT_to_uv_Planck1900(T, CMFS))
    np.testing.assert_allclose(xy, ref, rtol=1e-12)
    np.testing.assert_allclose(rc.xy_to_CCT(xy, c2=C2_CIE)[:, 0], T, rtol=1e-5)


def test_CCT_jit_vmap_grad():
    uv = jnp.asarray(rc.CCT_to_uv(T_REF[:6], DUV_REF[:6]))
    eager = rc.uv_to_CCT(uv)
    np.testing.assert_allclose(jax.jit(rc.uv_to_CCT)(uv), eager, rtol=1e-14)
    np.testing.assert_allclose(jax.vmap(rc.uv_to_CCT)(uv), eager, rtol=1e-14)
    assert rc.uv_to_CCT(uv.reshape(2, 3, 2)).shape == (2, 3, 2)
    # Gradients flow through the triangular and parabolic formulas; compare with finite
    # differences on a step smaller than one table row.
    for duv in (0.0005, 0.01):
        p = rc.CCT_to_uv(jnp.array(5000.0), jnp.array(duv))
        check_grads(jax.jit(rc.uv_to_CCT), (p,), order=1, modes=["fwd", "rev"], eps=1e-8, rtol=1e-3)
    check_grads(jax.jit(rc.planckian_locus_uv), (jnp.array([3000.0, 9000.0]),), order=1, eps=1e-3)
    check_grads(jax.jit(lambda t: rc.CCT_to_xy(t, "daylight")), (jnp.array([5000.0]),), order=1)


def test_CCT_bad_input():
    with pytest.raises(ValueError, match="'Ohno 2013'"):
        rc.xy_to_CCT(np.array([0.3, 0.3]), "Ohno 2014")
    with pytest.raises(ValueError, match="'daylight'"):
        rc.CCT_to_xy(np.array(5000.0), "blackbody")
    with pytest.raises(eqx.EquinoxRuntimeError, match="temperature"):
        rc.planckian_locus_uv(np.array([-5.0]))
    with pytest.raises(eqx.EquinoxRuntimeError, match="temperature"):
        eqx.filter_jit(rc.planckian_locus_uv)(jnp.array([0.0]))
    with pytest.raises(TypeError):
        rc.xy_to_CCT(np.array([1, 1]))
    out = np.asarray(rc.uv_to_CCT(np.array([np.nan, 0.3])))
    assert np.all(np.isnan(out))
