"""Private vectorised math helpers of the colour-difference path agree with jnp / NumPy."""

from fractions import Fraction

import jax
import jax.numpy as jnp
import numpy as np
from jax.test_util import check_grads

from radiometria.colorimetry._fastmath import atan2_degrees, cbrt_positive, sin_small


def test_cbrt_positive_float64_within_one_ulp_exactly():
    # Exact rational arithmetic: the true root lies strictly between y - ulp and y + ulp.
    # (NumPy's / glibc's cbrt is itself up to 3 ulp off, so it cannot be the reference.)
    t = np.geomspace(1e-300, 1e300, 20001)
    y = np.asarray(cbrt_positive(jnp.asarray(t)))
    ulp = np.spacing(y)
    for ti, yi, ui in zip(t.tolist(), y.tolist(), ulp.tolist(), strict=True):
        lo, hi = Fraction(yi) - Fraction(ui), Fraction(yi) + Fraction(ui)
        assert lo**3 < Fraction(ti) < hi**3, ti


def test_cbrt_positive_float32():
    t32 = np.geomspace(1e-37, 1e37, 20001).astype(np.float32)
    out = cbrt_positive(jnp.asarray(t32))
    assert out.dtype == jnp.float32
    np.testing.assert_allclose(out, np.cbrt(t32.astype(np.float64)), rtol=3e-7)
    check_grads(cbrt_positive, (jnp.array([0.008, 1.0, 27.0]),), order=2, eps=1e-6)


def test_atan2_degrees():
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=(2, 20001))
    ref = np.degrees(np.arctan2(y, x)) % 360.0
    np.testing.assert_allclose(atan2_degrees(jnp.asarray(y), jnp.asarray(x)), ref, atol=1e-12)
    edge = atan2_degrees(
        jnp.array([0.0, 0.0, 1.0, -1.0, 1.0]), jnp.array([0.0, -1.0, 0.0, 0.0, 1.0])
    )
    np.testing.assert_allclose(edge, [0.0, 180.0, 90.0, 270.0, 45.0], atol=1e-13)
    g = jax.grad(lambda v: atan2_degrees(v[1], v[0]))(jnp.array([0.3, 0.4]))
    np.testing.assert_allclose(g, np.degrees([-0.4 / 0.25, 0.3 / 0.25]), rtol=1e-12)


def test_sin_small():
    x = np.linspace(-np.pi / 2, np.pi / 2, 20001)
    np.testing.assert_allclose(sin_small(jnp.asarray(x)), np.sin(x), atol=5e-16)
