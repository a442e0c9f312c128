"""Reconstruction filters: normalisation, shapes against Mitsuba, chi-square of the samplers,
filter importance sampling (thesis eq. 2.35) against splatting (eq. 2.34)."""

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.camera as cam
from radiometria.montecarlo import chi2_test

FILTERS = {
    "box": cam.BoxFilter(),
    "tent": cam.TentFilter(),
    "gaussian": cam.GaussianFilter(),
    "mitchell": cam.MitchellFilter(),
    "lanczos": cam.LanczosFilter(),
}
N = 200_000  # one sample count throughout, so that compiled samplers are reused
_sample = eqx.filter_jit(lambda f, u: f.sample(u))
_pdf = eqx.filter_jit(lambda f, p: f.pdf(p))


@functools.cache
def _samples(name):
    """(offsets, weights) of N filter importance samples, computed once per filter."""
    return _sample(FILTERS[name], jax.random.uniform(jax.random.key(11), (N, 2)))


def _chi2(sample_fn, pdf_fn, radius, *, n_samples=N, seed=7):
    """radiometria.montecarlo.chi2_test on the square [-r, r]^2 (32 x 32 cells).

    12 quadrature points per cell and axis land exactly on the tabulated filters' cells
    (4 or 6 table cells per chi-square cell), so the expected counts are exact for them.
    """
    return chi2_test(
        sample_fn,
        pdf_fn,
        domain="square",
        bounds=((-radius, radius), (-radius, radius)),
        resolution=32,
        quadrature=12,
        n_samples=n_samples,
        u_dim=2,
        key=jax.random.key(seed),
        alpha=1e-4,
        n_tests=len(FILTERS),
    )


@pytest.mark.parametrize("name", list(FILTERS))
def test_filter_integrates_to_one(name):
    f = FILTERS[name]
    r = f.radius
    n = 800  # 2D midpoint rule on the full support, not the separable shortcut
    x = -r + (np.arange(n) + 0.5) * (2 * r / n)
    xx, yy = np.meshgrid(x, x)
    vals = np.asarray(f.evaluate(jnp.stack([jnp.asarray(xx), jnp.asarray(yy)], axis=-1)))
    assert vals.sum() * (2 * r / n) ** 2 == pytest.approx(1.0, abs=2e-5)
    # zero outside the support, symmetric
    assert float(f.evaluate(jnp.asarray([r + 1e-9, 0.0]))) == 0.0
    np.testing.assert_allclose(vals, vals[::-1, ::-1], atol=1e-12)


def test_filter_shapes_match_mitsuba():
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    xs = np.linspace(-3.2, 3.2, 129) + 1e-3  # off the support boundaries (measure zero)
    for name, f in FILTERS.items():
        ref_filter = mi.load_dict({"type": name})
        assert ref_filter.radius() == pytest.approx(f.radius)
        ref = np.array([ref_filter.eval(float(x)) for x in xs])
        ours = np.asarray(f.evaluate_1d(jnp.asarray(xs)))
        # Mitsuba's filters are not normalised: compare shapes f(x) / f(0).
        ours0 = float(f.evaluate_1d(jnp.asarray(0.0)))
        # Mitsuba evaluates its Gaussian with a fast exp approximation (~1e-3 absolute).
        atol = 2e-3 if name == "gaussian" else 2e-6
        ref0 = ref_filter.eval(0.0)
        np.testing.assert_allclose(ours / ours0, ref / ref0, atol=atol, err_msg=name)


@pytest.mark.parametrize("name", list(FILTERS))
def test_filter_sample_chi2(name):
    f = FILTERS[name]
    res = _chi2(lambda u: _sample(f, u)[0], lambda p: _pdf(f, p), f.radius)
    assert res.passed, res.message
    # The weight is f / p at the sampled offset.
    offset, weight = (np.asarray(a) for a in _samples(name))
    assert np.all(np.abs(offset) <= f.radius)
    ratio = np.asarray(f.evaluate(offset[:1000]) / _pdf(f, offset[:1000]))
    np.testing.assert_allclose(weight[:1000], ratio, rtol=1e-10)


def test_chi2_detects_a_wrong_density():
    """The chi-square check has power: Mitchell samples judged against the Gaussian's density."""
    mitchell, gaussian = FILTERS["mitchell"], FILTERS["gaussian"]
    res = _chi2(lambda u: _sample(mitchell, u)[0], lambda p: _pdf(gaussian, p), 2.0)
    assert not res.passed and res.p_value < 1e-12


@pytest.mark.parametrize("name", list(FILTERS))
def test_filter_weights_average_to_one(name):
    """E[w] = E[f/p] = integral of f = 1 (the estimator of eq. 2.35 is unbiased)."""
    w = np.asarray(_samples(name)[1])
    se = float(np.std(w)) / np.sqrt(N)
    assert abs(float(np.mean(w)) - 1.0) < 5 * se + 1e-12
    if name in ("box", "tent"):
        np.testing.assert_allclose(w, 1.0)
    if name == "gaussian":  # only the subtracted tail makes f differ from the sampled Gaussian
        assert float(np.median(np.abs(w - 1.0))) < 3e-3
    if name in ("mitchell", "lanczos"):  # negative lobes: some weights are negative
        assert np.any(w < 0)
    # Eq. 2.35 normalises by the weight sum: a constant image is reproduced exactly.
    assert float(np.sum(w * 0.7) / np.sum(w)) == pytest.approx(0.7, rel=1e-12)


def _image_function(xy):
    """A smooth test 'radiance' over the film plane (raster units), positive."""
    x, y = xy[..., 0], xy[..., 1]
    return 1.0 + 0.5 * jnp.sin(0.9 * x) * jnp.cos(0.6 * y) + 0.05 * x


def _exact_filtered(f, centre):
    r = f.radius
    n = 600
    t = -r + (np.arange(n) + 0.5) * (2 * r / n)
    xx, yy = np.meshgrid(t, t)
    off = jnp.stack([jnp.asarray(xx), jnp.asarray(yy)], axis=-1)
    w = f.evaluate(off)
    vals = _image_function(off + jnp.asarray(centre)[None, None, :])
    return float(jnp.sum(w * vals) / jnp.sum(w))


@pytest.mark.parametrize("name", ["tent", "gaussian", "mitchell", "lanczos"])
def test_filter_importance_sampling_agrees_with_splatting(name):
    """Both estimators converge to the filtered image r_f (eq. 2.31) at a pixel centre."""
    f = FILTERS[name]
    width = height = 12
    pixel = np.array([5, 6])
    centre = pixel + 0.5
    exact = _exact_filtered(f, centre)

    # Filter importance sampling (eq. 2.35 and its unweighted form): samples around the centre.
    n = N
    offset, w = _samples(name)
    vals = _image_function(jnp.asarray(centre)[None, :] + offset)
    unbiased = w * vals  # (1/n) sum w r: unbiased because E[w r] = integral f r and integral f = 1
    est_plain = float(jnp.mean(unbiased))
    se_plain = float(jnp.std(unbiased)) / np.sqrt(n)
    assert abs(est_plain - exact) < 5 * se_plain + 1e-4
    est_ratio = float(jnp.sum(unbiased) / jnp.sum(w))
    assert abs(est_ratio - exact) < 5 * se_plain + 1e-4

    # Splatting (eq. 2.34): uniform samples over the film, each splatted to its footprint.
    film = cam.Film(width, height, cmfs=_flat_cmfs())
    m, batch = 150_000, 30_000
    xy = jax.random.uniform(jax.random.key(4), (m, 2)) * jnp.asarray(
        [[float(width), float(height)]]
    )
    rv = _image_function(xy)
    xyz = jnp.stack([rv, rv, rv], axis=-1)
    splat = jax.jit(cam.splat_samples)
    for i in range(0, m, batch):  # bounded memory: samples x footprint per batch
        film = splat(film, xy[i : i + batch], xyz[i : i + batch], f)
    est_splat = float(cam.film_develop(film, "XYZ")[pixel[1], pixel[0], 1])
    # Standard error of the ratio estimator, from the per-sample filter weights at this pixel.
    fw = np.asarray(f.evaluate(jnp.asarray(centre)[None, :] - xy))
    resid = fw * (np.asarray(rv) - est_splat)
    se_splat = np.sqrt(np.sum(resid**2)) / abs(np.sum(fw))
    assert abs(est_splat - exact) < 5 * se_splat + 1e-4
    assert abs(est_splat - est_plain) < 5 * np.hypot(se_splat, se_plain) + 1e-4


def _flat_cmfs():
    wl = np.array([360.0, 830.0])
    return wl, np.ones((2, 3))


@pytest.mark.parametrize("name", ["gaussian", "mitchell"])
def test_filter_sample_eager_matches_jit_and_float32(name):
    f = FILTERS[name]
    u = jax.random.uniform(jax.random.key(11), (N, 2))[:256]
    o_jit, w_jit = (np.asarray(a)[:256] for a in _samples(name))
    o1, w1 = f.sample(u)
    np.testing.assert_allclose(o1, o_jit, atol=1e-12)
    np.testing.assert_allclose(w1, w_jit, rtol=1e-10, atol=1e-12)
    o32, w32 = f.sample(u.astype(jnp.float32))
    assert o32.dtype == jnp.float32 and w32.dtype == jnp.float32
    np.testing.assert_allclose(o32, o1, atol=1e-4)


def test_filters_reject_bad_parameters():
    with pytest.raises(ValueError, match="stddev"):
        cam.GaussianFilter(stddev=-0.5)
    with pytest.raises(ValueError, match="radius"):
        cam.GaussianFilter(radius=0.0)
    with pytest.raises(ValueError, match="radius"):
        cam.BoxFilter(radius=-1.0)
    with pytest.raises(ValueError, match="radius"):
        cam.TentFilter(radius=float("inf"))
    with pytest.raises(ValueError, match="tau"):
        cam.LanczosFilter(tau=0.0)
    with pytest.raises(ValueError, match="B"):
        cam.MitchellFilter(B=float("nan"))
    with pytest.raises(TypeError, match="radius"):
        cam.MitchellFilter(radius="2")
    f = cam.TentFilter()
    with pytest.raises(ValueError, match="`u`"):
        f.sample(jnp.zeros((4, 3)))
    with pytest.raises(Exception, match="u"):
        f.sample(jnp.full((4, 2), 1.5))
    with pytest.raises(ValueError, match="offset"):
        f.evaluate(jnp.zeros((4,)))
