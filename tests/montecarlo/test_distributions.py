"""Tabulated distributions, simple samplers and the chi-square harness itself."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.montecarlo as mc

TABLE_1D = jnp.array([0.0, 1.0, 3.0, 0.5, 0.0, 2.0, 4.0, 1.0])
TABLE_2D = jnp.abs(jnp.sin(jnp.arange(48.0).reshape(6, 8))) * jnp.arange(1.0, 9.0)[None, :]


def test_piecewise_constant_1d_chi2_and_roundtrip():
    dist = mc.PiecewiseConstant1D(TABLE_1D, 360.0, 830.0)
    res = mc.chi2_test(
        lambda u: dist.sample(u[:, 0])[0],
        dist.pdf,
        domain="interval",
        bounds=(360.0, 830.0),
        resolution=47,
        n_samples=100_000,
        u_dim=1,
        key=jax.random.key(0),
    )
    assert res.passed, res.message
    u = jax.random.uniform(jax.random.key(1), (2000,))
    x, pdf, off = dist.sample(u)
    np.testing.assert_allclose(dist.invert(x), u, atol=1e-12)
    np.testing.assert_allclose(pdf, dist.pdf(x))
    assert jnp.all(TABLE_1D[off] > 0)  # zero bins are never sampled
    assert float(dist.integral) == pytest.approx(float(TABLE_1D.sum()) * 470 / 8)


def test_piecewise_constant_2d_chi2_and_roundtrip():
    dist = mc.PiecewiseConstant2D(TABLE_2D, bounds=((0.0, 2.0), (-1.0, 1.0)))
    res = mc.chi2_test(
        lambda u: dist.sample(u)[0],
        dist.pdf,
        domain="square",
        bounds=((0.0, 2.0), (-1.0, 1.0)),
        resolution=(16, 12),
        n_samples=100_000,
        u_dim=2,
        key=jax.random.key(2),
    )
    assert res.passed, res.message
    u = jax.random.uniform(jax.random.key(3), (2000, 2))
    p, pdf, _ = dist.sample(u)
    np.testing.assert_allclose(dist.invert(p), u, atol=1e-12)
    np.testing.assert_allclose(pdf, dist.pdf(p), rtol=1e-12)


def _hostile_variates(cdf: np.ndarray, dtype, m: int) -> np.ndarray:
    """Variates at and beside every CDF value and every cutpoint k/m, the ends, and random."""
    points = np.concatenate([cdf, np.arange(m + 1) / m]).astype(dtype)
    near = [points, np.nextafter(points, dtype(0)), np.nextafter(points, dtype(1))]
    rand = np.random.default_rng(7).uniform(size=4000).astype(dtype)
    u = np.concatenate(near + [rand, np.array([0.0, 1.0 - np.finfo(dtype).epsneg], dtype)])
    return u[(u >= 0) & (u < 1)]


@pytest.mark.parametrize("counted", [0, 10**6], ids=["searched", "counted"])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize(
    "table",
    [
        np.r_[np.zeros(40), 1.0, np.zeros(40)],  # one positive cell among zeros
        np.r_[np.full(200, 1e-8), 1.0, 2.0, np.full(53, 1e-8)],  # a sun: 1e8 contrast
        np.abs(np.sin(np.arange(257.0))) ** 6,  # many near-zero cells and ties at zero
        np.ones(1),
    ],
    ids=["spike", "sun", "ripples", "one-cell"],
)
def test_guided_search_finds_what_a_plain_search_finds(table, dtype, counted, monkeypatch):
    """The cutpoint tables change the work, never the answer: for every variate (also at,
    just below and just above each CDF value and cutpoint) the interval is NumPy's
    `searchsorted` on the same CDF, in 1D and in each row of 2D, whether the guide's bracket
    is finished by halvings or by counting its CDF values (`counted`: the widest bracket
    counted)."""
    from radiometria.montecarlo import _distributions
    from radiometria.montecarlo._distributions import _find_interval

    monkeypatch.setattr(_distributions, "_SPAN_COUNTED", counted)

    dist1 = mc.PiecewiseConstant1D(jnp.asarray(table, dtype))
    dist2 = mc.PiecewiseConstant2D(jnp.asarray(np.stack([table, table[::-1]]), dtype))
    n = table.shape[0]
    for cdf, guide, rows in (
        (dist1.cdf[None, :], dist1.guide, [0]),
        (dist2.conditional_cdf, dist2.conditional_guide, [0, 1]),
    ):
        assert guide is not None and guide.steps <= max(1, int(np.ceil(np.log2(n + 1))))
        m = guide.lower.shape[-1] - 1
        for r in rows:
            c = np.asarray(cdf[r])
            u = _hostile_variates(c, dtype, m)
            row = jnp.full(u.shape, r, jnp.int32)
            got = _find_interval(cdf, jnp.asarray(u), row, guide)
            expected = np.clip(np.searchsorted(c, u, side="right") - 1, 0, n - 1)
            np.testing.assert_array_equal(np.asarray(got), expected)
            np.testing.assert_array_equal(np.asarray(_find_interval(cdf, jnp.asarray(u), row)),
                                          expected)  # fmt: skip


def test_guides_are_left_out_for_traced_tables_and_kept_small():
    """Under `jit` (traced values) there is no guide and the full search serves; a large
    table's guides stay within the budget (int16 indices, fewer cutpoints)."""
    from radiometria.montecarlo import _distributions as dists

    guides = []

    def build(v):
        guides.append(mc.PiecewiseConstant1D(v).guide)
        return v

    jax.jit(build)(TABLE_1D)
    assert guides == [None]
    big = dists._guide_tables(np.linspace(0.0, 1.0, 8193)[None, :].repeat(600, axis=0))
    assert big.lower.dtype == jnp.int16 and big.steps <= 1
    assert big.lower.nbytes + big.upper.nbytes <= dists._GUIDE_BYTES
    assert big.lower.shape[-1] - 1 >= 8192  # never fewer cutpoints than cells


def test_sample_discrete():
    w = jnp.array([1.0, 0.0, 3.0])
    idx, pmf, u2 = mc.sample_discrete(jax.random.uniform(jax.random.key(4), (100_000,)), w)
    counts = np.bincount(np.asarray(idx), minlength=3) / 100_000
    np.testing.assert_allclose(counts, [0.25, 0.0, 0.75], atol=0.005)
    np.testing.assert_allclose(pmf, np.asarray(w / 4)[np.asarray(idx)])
    assert jnp.all((u2 >= 0) & (u2 < 1))
    assert abs(float(jnp.mean(u2)) - 0.5) < 0.005  # the remapped variate is uniform again


def test_tables_under_jit_and_vmap():
    dist = mc.PiecewiseConstant1D(TABLE_1D)
    u = jnp.linspace(0.0, 0.99, 7)
    np.testing.assert_allclose(jax.jit(lambda d, u: d.sample(u)[0])(dist, u), dist.sample(u)[0])
    np.testing.assert_allclose(jax.vmap(lambda u: dist.sample(u)[0])(u), dist.sample(u)[0])
    built = jax.jit(lambda v: mc.PiecewiseConstant1D(v).sample(u)[0])(TABLE_1D)
    np.testing.assert_allclose(built, dist.sample(u)[0])


def test_tables_reject_bad_input():
    with pytest.raises(ValueError, match="non-negative"):
        mc.PiecewiseConstant1D(jnp.array([1.0, -0.5]))
    with pytest.raises(ValueError, match="all zeros"):
        mc.PiecewiseConstant1D(jnp.zeros(4))
    with pytest.raises(ValueError, match="all zeros"):
        mc.PiecewiseConstant2D(jnp.zeros((3, 4)))
    with pytest.raises(ValueError, match="finite"):
        mc.PiecewiseConstant2D(jnp.array([[1.0, jnp.nan]]))
    with pytest.raises(ValueError, match="1D"):
        mc.PiecewiseConstant1D(jnp.ones((2, 2)))
    with pytest.raises(ValueError, match="2D"):
        mc.PiecewiseConstant2D(jnp.ones(3))
    with pytest.raises(ValueError, match="low < high"):
        mc.PiecewiseConstant1D(jnp.ones(3), 1.0, 0.0)
    with pytest.raises(ValueError, match="non-negative"):
        mc.sample_discrete(jnp.array([0.5]), jnp.array([1.0, -1.0]))
    # Traced tables are checked at run time.
    with pytest.raises(eqx.EquinoxRuntimeError, match="non-negative"):
        eqx.filter_jit(lambda v: mc.PiecewiseConstant1D(v).func)(jnp.array([1.0, -0.5]))
    with pytest.raises(eqx.EquinoxRuntimeError, match="u"):
        mc.PiecewiseConstant1D(TABLE_1D).sample(jnp.array([1.2]))


def test_tables_check_false_identical_and_check_true_raises_under_jit():
    d1 = mc.PiecewiseConstant1D(TABLE_1D, 360.0, 830.0)
    d2 = mc.PiecewiseConstant2D(TABLE_2D, bounds=((0.0, 2.0), (-1.0, 1.0)))
    w = jnp.array([1.0, 0.0, 3.0])
    u1 = jax.random.uniform(jax.random.key(32), (257,))
    u2 = jax.random.uniform(jax.random.key(33), (257, 2))
    cases = [
        (lambda u, check: d1.sample(u, check=check), u1),
        (lambda u, check: d2.sample(u, check=check), u2),
        (lambda u, check: mc.sample_discrete(u, w, check=check), u1),
    ]
    for fn, u in cases:
        checked = jax.jit(lambda u, fn=fn: fn(u, True))(u)
        unchecked = jax.jit(lambda u, fn=fn: fn(u, False))(u)
        for a, b in zip(unchecked, checked, strict=True):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
        bad = u.at[3].set(1.0)
        with pytest.raises(eqx.EquinoxRuntimeError, match="u"):
            jax.block_until_ready(eqx.filter_jit(lambda u, fn=fn: fn(u, True))(bad))
        jax.block_until_ready(jax.jit(lambda u, fn=fn: fn(u, False))(bad))


def test_stratified_one_point_per_cell():
    x = np.asarray(mc.stratified((4, 5, 3), key=jax.random.key(5)))
    assert x.shape == (60, 3)
    cells = np.floor(x * np.array([4, 5, 3])).astype(int)
    assert len({tuple(c) for c in cells}) == 60
    centres = np.asarray(mc.stratified(4, key=jax.random.key(0), jitter=False))
    np.testing.assert_allclose(centres[:, 0], [0.125, 0.375, 0.625, 0.875])


def test_latin_hypercube_projections():
    x = np.asarray(mc.latin_hypercube(50, 4, key=jax.random.key(6)))
    for j in range(4):
        assert sorted(np.floor(x[:, j] * 50).astype(int).tolist()) == list(range(50))


def test_kronecker_and_lattice():
    x = np.asarray(mc.kronecker(1000, 2))
    phi2 = 1.32471795724474602596  # plastic number
    np.testing.assert_allclose(x[7], np.mod(7 * np.array([1 / phi2, 1 / phi2**2]), 1), atol=1e-9)
    shifted = np.asarray(mc.kronecker(1000, 2, key=jax.random.key(7)))
    d = np.mod(shifted - x, 1.0)
    np.testing.assert_allclose(d, np.broadcast_to(d[0], d.shape), atol=1e-9)
    fib = np.asarray(mc.rank1_lattice(89, 2))
    np.testing.assert_allclose(fib[1], [1 / 89, 55 / 89], atol=1e-12)
    lat = np.asarray(mc.rank1_lattice(64, 3, generating_vector=np.array([1, 19, 27])))
    np.testing.assert_allclose(lat[5], np.mod(5 * np.array([1, 19, 27]) / 64, 1), atol=1e-12)
    # A lattice integrates trigonometric polynomials with small frequencies exactly.
    v = np.cos(2 * np.pi * fib[:, 0]) * np.cos(2 * np.pi * fib[:, 1])
    assert abs(v.mean()) < 1e-12


def test_samplers_bad_input():
    with pytest.raises(ValueError):
        mc.latin_hypercube(0, 2, key=jax.random.key(0))
    with pytest.raises(ValueError, match="alpha"):
        mc.kronecker(4, 2, alpha=[0.5, 1.5])
    with pytest.raises(ValueError, match="generating_vector"):
        mc.rank1_lattice(8, 2, generating_vector=[1, 2, 3])
    with pytest.raises(ValueError, match="strata"):
        mc.stratified((), key=jax.random.key(0))


def test_chi2_detects_wrong_pdf_and_bad_samples():
    bad = mc.chi2_test(
        mc.sample_uniform_hemisphere,
        lambda w: mc.cosine_hemisphere_pdf(w[:, 2]),
        domain="sphere",
        n_samples=50_000,
        u_dim=2,
        key=jax.random.key(8),
    )
    assert not bad.passed and bad.p_value < 1e-10
    # A pdf that does not integrate to one.
    half = mc.chi2_test(
        mc.sample_uniform_sphere,
        lambda w: 0.5 * mc.uniform_sphere_pdf(w),
        domain="sphere",
        n_samples=50_000,
        u_dim=2,
        key=jax.random.key(9),
    )
    assert not half.passed and "integrates" in half.message
    # Samples where the pdf is zero.
    out = mc.chi2_test(
        mc.sample_uniform_sphere,
        mc.uniform_hemisphere_pdf,
        domain="sphere",
        n_samples=20_000,
        u_dim=2,
        key=jax.random.key(10),
        pdf_tolerance=0.6,
    )
    assert not out.passed and out.n_outside_support > 0
    # NaN and off-domain samples.
    nan = mc.chi2_test(
        lambda u: jnp.where(u[:, 0] < 0.01, jnp.nan, u[:, 0]),
        lambda x: jnp.ones_like(x),
        domain="interval",
        n_samples=20_000,
        u_dim=1,
        key=jax.random.key(11),
    )
    assert not nan.passed and nan.n_invalid > 0


def test_chi2_sidak_threshold_and_bad_arguments():
    ok = mc.chi2_test(
        lambda k: jax.random.uniform(k, (20_000, 2)),
        lambda x: jnp.ones(x.shape[0]),
        domain="square",
        n_samples=20_000,
        key=jax.random.key(12),
        n_tests=10,
    )
    assert ok.passed
    assert ok.threshold == pytest.approx(1 - 0.99 ** (1 / 10))
    with pytest.raises(ValueError, match="valid values"):
        mc.chi2_test(
            lambda k: None, lambda x: x, domain="disk", n_samples=10, key=jax.random.key(0)
        )
    with pytest.raises(ValueError, match="shape"):
        mc.chi2_test(
            lambda k: jnp.zeros((10, 3)),
            lambda x: x,
            domain="square",
            n_samples=10,
            key=jax.random.key(0),
        )
    with pytest.raises(ValueError, match="bounds"):
        mc.chi2_test(
            lambda k: jnp.zeros(10),
            lambda x: x,
            domain="interval",
            bounds=(1.0, 0.0),
            n_samples=10,
            key=jax.random.key(0),
        )


@pytest.mark.parametrize("generator", ["threefry", "hash"])
def test_independent_generators_are_uniform(generator):
    res = mc.chi2_test(
        lambda k: mc.independent(100_000, 2, key=k, generator=generator),
        lambda x: jnp.ones(x.shape[0]),
        domain="square",
        n_samples=100_000,
        key=jax.random.key(13),
    )
    assert res.passed, res.message
    x = np.asarray(mc.independent(100_000, 4, key=jax.random.key(14), generator=generator))
    c = np.corrcoef(x.T)
    assert np.all(np.abs(c - np.eye(4)) < 0.02)  # 5 sigma for 1e5 samples is 0.016
    with pytest.raises(ValueError, match="generator"):
        mc.independent(4, 2, key=jax.random.key(0), generator="pcg")
