"""Reconstruction filters: normalisation, shapes against Mitsuba, chi-square of the samplers,
filter importance sampling (thesis eq. 2.35) against splatting (eq. 2.34)."""

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


def _chi2(sample_fn, pdf_fn, radius, *, n_samples=200_000, seed=7):
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
    res = _chi2(lambda u: f.sample(u)[0], f.pdf, f.radius)
    assert res.passed, res.message
    # The weight is f / p at the sampled offset.
    offset, weight = f.sample(jax.random.uniform(jax.random.key(1), (1000, 2)))
    assert np.all(np.abs(np.asarray(offset)) <= f.radius)
    np.testing.assert_allclose(weight, f.evaluate(offset) / f.pdf(offset), rtol=1e-10)


def test_chi2_detects_a_wrong_density():
    """The chi-square check has power: Mitchell samples judged against the tent density fail."""
    mitchell, tent = cam.MitchellFilter(radius=1.0), cam.TentFilter()
    res = _chi2(lambda u: mitchell.sample(u)[0], tent.pdf, 1.0, n_samples=50_000)
    assert not res.passed and res.p_value < 1e-12


@pytest.mark.parametrize("name", list(FILTERS))
def test_filter_weights_average_to_one(name):
    """E[w] = E[f/p] = integral of f = 1 (the estimator of eq. 2.35 is unbiased)."""
    f = FILTERS[name]
    n = 200_000
    _, w = f.sample(jax.random.uniform(jax.random.key(11), (n, 2)))
    se = float(jnp.std(w)) / np.sqrt(n)
    assert abs(float(jnp.mean(w)) - 1.0) < 5 * se + 1e-12
    if name in ("box", "tent"):
        np.testing.assert_allclose(w, 1.0)
    if name == "gaussian":  # only the subtracted tail makes f differ from the sampled Gaussian
        assert float(jnp.median(jnp.abs(w - 1.0))) < 3e-3


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
    n = 200_000
    u = jax.random.uniform(jax.random.key(3), (n, 2))
    offset, w = f.sample(u)
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


def test_fis_ratio_estimator_is_exact_for_constant_image():
    """Eq. 2.35 normalises by the weight sum: a constant image is reproduced exactly."""
    f = FILTERS["mitchell"]
    _, w = f.sample(jax.random.uniform(jax.random.key(0), (64, 2)))
    vals = jnp.full((64,), 0.7)
    assert float(jnp.sum(w * vals) / jnp.sum(w)) == pytest.approx(0.7, rel=1e-12)


def test_filter_sample_jit_and_float32():
    u = jax.random.uniform(jax.random.key(0), (1000, 2))
    for f in FILTERS.values():
        o1, w1 = f.sample(u)
        o2, w2 = eqx.filter_jit(lambda filt, uu: filt.sample(uu))(f, u)
        np.testing.assert_allclose(o2, o1, atol=1e-12)
        np.testing.assert_allclose(w2, w1, rtol=1e-10, atol=1e-12)
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
