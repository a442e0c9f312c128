"""Colour differences: Sharma, Wu & Dalal (2005) CIEDE2000 test data, colour-science, gradients."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads

import radiometria.colorimetry as rc

colour = pytest.importorskip("colour")

# Sharma, G., Wu, W., Dalal, E. N. (2005). The CIEDE2000 color-difference formula:
# Implementation notes, supplementary test data, and mathematical observations. Color Res.
# Appl. 30(1), 21-30, doi:10.1002/col.20070, Table 1: pairs 1-34 (L1 a1 b1, L2 a2 b2, dE00).
SHARMA_2005 = np.array(
    [
        [50.0000, 2.6772, -79.7751, 50.0000, 0.0000, -82.7485, 2.0425],
        [50.0000, 3.1571, -77.2803, 50.0000, 0.0000, -82.7485, 2.8615],
        [50.0000, 2.8361, -74.0200, 50.0000, 0.0000, -82.7485, 3.4412],
        [50.0000, -1.3802, -84.2814, 50.0000, 0.0000, -82.7485, 1.0000],
        [50.0000, -1.1848, -84.8006, 50.0000, 0.0000, -82.7485, 1.0000],
        [50.0000, -0.9009, -85.5211, 50.0000, 0.0000, -82.7485, 1.0000],
        [50.0000, 0.0000, 0.0000, 50.0000, -1.0000, 2.0000, 2.3669],
        [50.0000, -1.0000, 2.0000, 50.0000, 0.0000, 0.0000, 2.3669],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0009, 7.1792],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0010, 7.1792],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0011, 7.2195],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0012, 7.2195],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0009, -2.4900, 4.8045],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0010, -2.4900, 4.8045],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0011, -2.4900, 4.7461],
        [50.0000, 2.5000, 0.0000, 50.0000, 0.0000, -2.5000, 4.3065],
        [50.0000, 2.5000, 0.0000, 73.0000, 25.0000, -18.0000, 27.1492],
        [50.0000, 2.5000, 0.0000, 61.0000, -5.0000, 29.0000, 22.8977],
        [50.0000, 2.5000, 0.0000, 56.0000, -27.0000, -3.0000, 31.9030],
        [50.0000, 2.5000, 0.0000, 58.0000, 24.0000, 15.0000, 19.4535],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.1736, 0.5854, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.2972, 0.0000, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 1.8634, 0.5757, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.2592, 0.3350, 1.0000],
        [60.2574, -34.0099, 36.2677, 60.4626, -34.1751, 39.4387, 1.2644],
        [63.0109, -31.0961, -5.8663, 62.8187, -29.7946, -4.0864, 1.2630],
        [61.2901, 3.7196, -5.3901, 61.4292, 2.2480, -4.9620, 1.8731],
        [35.0831, -44.1164, 3.7933, 35.0232, -40.0716, 1.5901, 1.8645],
        [22.7233, 20.0904, -46.6940, 23.0331, 14.9730, -42.5619, 2.0373],
        [36.4612, 47.8580, 18.3852, 36.2715, 50.5065, 21.2231, 1.4146],
        [90.8027, -2.0831, 1.4410, 91.1528, -1.6435, 0.0447, 1.4441],
        [90.9257, -0.5406, -0.9208, 88.6381, -0.8985, -0.7239, 1.5381],
        [6.7747, -0.2908, -2.4247, 5.8714, -0.0985, -2.2286, 0.6377],
        [2.0776, 0.0795, -1.1350, 0.9033, -0.0636, -0.5514, 0.9082],
    ]
)
# Pair 14 has a hue difference of exactly 180 degrees, where CIEDE2000 is discontinuous; the
# published 4.8045 follows Sharma's "<= 180" branch in exact arithmetic. colour-science excludes
# it from its own test because np.arctan2 rounding picks the other branch (4.7461) on Linux.
_AMBIGUOUS_ROWS = {13}


def test_delta_E_CIE2000_sharma_2005_table():
    Lab_1, Lab_2, ref = SHARMA_2005[:, :3], SHARMA_2005[:, 3:6], SHARMA_2005[:, 6]
    ours = np.asarray(rc.delta_E_CIE2000(Lab_1, Lab_2))
    np.testing.assert_allclose(ours, ref, atol=1e-4)
    # The formula is symmetric: swapping the pair gives the same table.
    np.testing.assert_allclose(rc.delta_E_CIE2000(Lab_2, Lab_1), ref, atol=1e-4)


def test_colour_science_agrees_with_sharma_table():
    Lab_1, Lab_2, ref = SHARMA_2005[:, :3], SHARMA_2005[:, 3:6], SHARMA_2005[:, 6]
    col = colour.difference.delta_E_CIE2000(Lab_1, Lab_2)
    ok = [i for i in range(34) if i not in _AMBIGUOUS_ROWS]
    np.testing.assert_allclose(col[ok], ref[ok], atol=1e-4)


@pytest.mark.parametrize("textiles", [False, True])
def test_delta_E_matches_colour_random(textiles):
    rng = np.random.default_rng(0)
    Lab_1 = rng.uniform([0, -100, -100], [100, 100, 100], (500, 3))
    Lab_2 = Lab_1 + rng.normal(0, 10, (500, 3))
    np.testing.assert_allclose(
        rc.delta_E_CIE2000(Lab_1, Lab_2, textiles),
        colour.difference.delta_E_CIE2000(Lab_1, Lab_2, textiles),
        rtol=1e-10,
    )
    np.testing.assert_allclose(
        rc.delta_E_CIE1994(Lab_1, Lab_2, textiles),
        colour.difference.delta_E_CIE1994(Lab_1, Lab_2, textiles),
        rtol=1e-10,
    )
    np.testing.assert_allclose(
        rc.delta_E_CIE1976(Lab_1, Lab_2),
        colour.difference.delta_E_CIE1976(Lab_1, Lab_2),
        rtol=1e-12,
    )


def test_delta_E_broadcast_jit_vmap():
    rng = np.random.default_rng(1)
    Lab_1 = jnp.asarray(rng.uniform([0, -50, -50], [100, 50, 50], (4, 5, 3)))
    ref = jnp.asarray([50.0, 10.0, -10.0])
    for f in (rc.delta_E_CIE1976, rc.delta_E_CIE1994, rc.delta_E_CIE2000):
        eager = f(Lab_1, ref)
        assert eager.shape == (4, 5)
        np.testing.assert_allclose(jax.jit(f)(Lab_1, ref), eager, rtol=1e-13)
        np.testing.assert_allclose(jax.vmap(f, in_axes=(0, None))(Lab_1, ref), eager, rtol=1e-13)


def test_delta_E_grads_finite_and_match_finite_differences():
    a = jnp.array([52.0, 20.0, -31.0])
    b = jnp.array([48.0, 23.0, -27.0])
    for f in (rc.delta_E_CIE1976, rc.delta_E_CIE1994, rc.delta_E_CIE2000):
        check_grads(jax.jit(f), (a, b), order=1, modes=["fwd", "rev"])
        # Identical colours and neutral colours: finite (zero) gradients, no NaN.
        g = jax.grad(f)(a, a)
        assert np.all(np.isfinite(g))
        g = jax.grad(f)(jnp.array([50.0, 0.0, 0.0]), jnp.array([40.0, 0.0, 0.0]))
        assert np.all(np.isfinite(g))


def test_delta_E_bad_input():
    with pytest.raises((ValueError, TypeError)):
        rc.delta_E_CIE2000(np.ones((2, 3)), np.ones((3, 3)))
    with pytest.raises(TypeError):
        rc.delta_E_CIE2000(np.ones(3, dtype=int), np.ones(3))
    assert np.isnan(float(rc.delta_E_CIE2000(np.array([np.nan, 0, 0]), np.ones(3))))
