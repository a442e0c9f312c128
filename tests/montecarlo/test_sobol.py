"""Sobol and Halton points: equality with SciPy, net properties of the scrambles, bad input."""

import hashlib
import itertools
import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.stats import qmc

import radiometria.montecarlo as mc
from radiometria.montecarlo import _halton, _make_data, _sobol


def t_value(points: np.ndarray, m: int) -> int:
    """Smallest t such that the 2^m points form a (t, m, s)-net in base 2."""
    s = points.shape[1]
    ints = np.floor(points * 2.0**m).astype(np.int64)  # digits, exact for dyadic points
    for t in range(m + 1):
        ok = True
        for ks in itertools.product(range(m - t + 1), repeat=s):
            if sum(ks) != m - t:
                continue
            box = np.zeros(len(points), dtype=np.int64)
            for j, k in enumerate(ks):
                box = (box << k) | (ints[:, j] >> (m - k))
            counts = np.bincount(box, minlength=1 << (m - t))
            if not np.all(counts == 1 << t):
                ok = False
                break
        if ok:
            return t
    return m


def test_packaged_direction_numbers_match_scipy_file():
    with np.load(_make_data.scipy_direction_file()) as z:
        compact = _make_data.compact_from_scipy(z["poly"], z["vinit"])
    with np.load(_sobol.DATA) as z:
        for name, arr in compact.items():
            np.testing.assert_array_equal(z[name], arr)
    prov = json.loads((_sobol.DATA.parent / "provenance.json").read_text())[_sobol.DATA.name]
    assert prov["sha256"] == hashlib.sha256(_sobol.DATA.read_bytes()).hexdigest()
    assert "Joe" in prov["primary_source"] and "BSD" in prov["licence"]


def test_sobol_unscrambled_equals_scipy_2p14_by_64():
    x = np.asarray(mc.sobol(2**14, 64))
    np.testing.assert_array_equal(x, qmc.Sobol(64, scramble=False).random(2**14))


def test_sobol_unscrambled_equals_scipy_last_dimensions():
    x = np.asarray(mc.sobol(2**10, 21201))[:, 21189:]
    ref = qmc.Sobol(21201, scramble=False).random(2**10)[:, 21189:]
    np.testing.assert_array_equal(x, ref)


def test_sobol_skip_equals_scipy_fast_forward():
    ref = qmc.Sobol(7, scramble=False)
    ref.fast_forward(1000)
    x = mc.sobol(512, 7, skip=1000)
    np.testing.assert_array_equal(np.asarray(x), ref.random(512))


@pytest.mark.parametrize("scramble", ["owen", "lms", "shift"])
def test_sobol_scramble_keeps_net_property(scramble):
    m = 10
    plain = np.asarray(mc.sobol(2**m, 40))
    x = np.asarray(mc.sobol(2**m, 40, scramble=scramble, key=jax.random.key(0)))
    assert t_value(x[:, :2], m) == 0  # the first two dimensions form a (0, m, 2)-net
    for dims in ([0, 1, 2], [3, 17, 39]):
        assert t_value(x[:, dims], m) == t_value(plain[:, dims], m)


def test_sobol_owen_elementary_intervals_each_hold_one_point():
    m = 8
    x = np.asarray(mc.sobol(2**m, 2, scramble="owen", key=jax.random.key(3)))
    for k in range(m + 1):
        ix = np.floor(x[:, 0] * 2**k).astype(int)
        iy = np.floor(x[:, 1] * 2 ** (m - k)).astype(int)
        assert np.all(np.bincount(ix * 2 ** (m - k) + iy, minlength=2**m) == 1)


def test_sobol_owen_is_random_and_deterministic():
    a = mc.sobol(1024, 8, scramble="owen", key=jax.random.key(1))
    b = mc.sobol(1024, 8, scramble="owen", key=jax.random.key(1))
    c = mc.sobol(1024, 8, scramble="owen", key=jax.random.key(2))
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    # Owen-scrambled points are uniform: the mean of each coordinate is 1/2 within the
    # (tiny) RQMC standard deviation.
    means = np.stack(
        [
            np.asarray(mc.sobol(256, 4, scramble="owen", key=k)).mean(0)
            for k in jax.random.split(jax.random.key(5), 64)
        ]
    )
    assert abs(means.mean() - 0.5) < 0.002
    assert np.all((np.asarray(a) >= 0) & (np.asarray(a) < 1))


def test_sobol_float32_stays_below_one():
    x = mc.sobol(2**12, 3, scramble="owen", key=jax.random.key(0), dtype=jnp.float32)
    assert x.dtype == jnp.float32
    assert float(x.max()) < 1.0
    xs = mc.sobol(2**12, 3, dtype=jnp.float32)
    np.testing.assert_array_equal(xs, np.asarray(mc.sobol(2**12, 3)).astype(np.float32))


def test_sobol_under_jit_with_traced_key():
    f = jax.jit(lambda k: mc.sobol(256, 3, scramble="owen", key=k))
    np.testing.assert_array_equal(
        f(jax.random.key(4)), mc.sobol(256, 3, scramble="owen", key=jax.random.key(4))
    )


def test_sobol_bad_input():
    with pytest.raises(ValueError, match="`n` must be >= 1"):
        mc.sobol(0, 2)
    with pytest.raises(ValueError, match="`d` must be >= 1"):
        mc.sobol(4, 0)
    with pytest.raises(ValueError, match="21201"):
        mc.sobol(4, 21202)
    with pytest.raises(ValueError, match="power of two"):
        mc.sobol(1000, 2)
    assert mc.sobol(1000, 2, allow_unbalanced=True).shape == (1000, 2)
    with pytest.raises(ValueError, match="needs a `key`"):
        mc.sobol(16, 2, scramble="owen")
    with pytest.raises(ValueError, match="scramble"):
        mc.sobol(16, 2, key=jax.random.key(0))
    with pytest.raises(ValueError, match="valid values"):
        mc.sobol(16, 2, scramble="nested", key=jax.random.key(0))
    with pytest.raises(TypeError):
        mc.sobol(16.0, 2)


def test_halton_unscrambled_equals_scipy_2p14_by_64():
    x = np.asarray(mc.halton(2**14, 64))
    np.testing.assert_array_equal(x, qmc.Halton(64, scramble=False).random(2**14))


def test_halton_skip_equals_scipy_fast_forward():
    ref = qmc.Halton(5, scramble=False)
    ref.fast_forward(777)
    np.testing.assert_array_equal(np.asarray(mc.halton(300, 5, skip=777)), ref.random(300))


@pytest.mark.parametrize("scramble", ["permutation", "owen"])
def test_halton_scrambles_keep_van_der_corput_stratification(scramble):
    x = np.asarray(mc.halton(3**6, 3, scramble=scramble, key=jax.random.key(0)))
    assert np.all((x >= 0) & (x < 1))
    # 3^6 consecutive points: base-3 coordinate has one point in each 3^-6 interval; the base-2
    # coordinate one in each 2^-9 interval at most (512 < 729 < 1024).
    assert np.all(np.bincount((x[:, 1] * 3**6).astype(int), minlength=3**6) == 1)
    assert np.bincount((x[:, 0] * 2**9).astype(int), minlength=2**9).max() <= 2
    # A different key gives different points, the same key the same.
    y = np.asarray(mc.halton(3**6, 3, scramble=scramble, key=jax.random.key(1)))
    assert not np.allclose(x, y)
    np.testing.assert_array_equal(x, mc.halton(3**6, 3, scramble=scramble, key=jax.random.key(0)))


@pytest.mark.parametrize("scramble", ["permutation", "owen"])
def test_halton_scrambled_skip_is_consistent(scramble):
    k = jax.random.key(2)
    a = np.asarray(mc.halton(1000, 4, scramble=scramble, key=k))
    b = np.asarray(mc.halton(400, 4, scramble=scramble, key=k, skip=600))
    np.testing.assert_allclose(a[600:], b, rtol=0, atol=1e-15)


def test_halton_scrambled_is_uniform_on_average():
    means = np.stack(
        [
            np.asarray(mc.halton(100, 5, scramble="permutation", key=k)).mean(0)
            for k in jax.random.split(jax.random.key(7), 50)
        ]
    )
    assert np.all(np.abs(means.mean(0) - 0.5) < 0.01)


def test_first_primes():
    assert _halton.first_primes(10).tolist() == [2, 3, 5, 7, 11, 13, 17, 19, 23, 29]
    assert _halton.first_primes(1000)[-1] == 7919


def test_permutation_element_is_a_permutation():
    for n, seed in [(2, 1), (7, 12345), (131, 99), (1000, 7)]:
        i = jnp.arange(n, dtype=jnp.uint32)
        p = np.asarray(jax.jit(_halton.permutation_element)(i, jnp.uint32(n), jnp.uint32(seed)))
        assert sorted(p.tolist()) == list(range(n))


def test_halton_bad_input():
    with pytest.raises(ValueError, match="`n` must be >= 1"):
        mc.halton(0, 2)
    with pytest.raises(ValueError, match="`d` must be >= 1"):
        mc.halton(4, -1)
    with pytest.raises(ValueError, match="needs a `key`"):
        mc.halton(16, 2, scramble="owen")
    with pytest.raises(ValueError, match="valid values"):
        mc.halton(16, 2, scramble="lms", key=jax.random.key(0))
