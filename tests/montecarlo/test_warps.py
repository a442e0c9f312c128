"""Warps: chi-square fits, pdf normalisation, Sample/Invert round trips, transforms, bad input."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.montecarlo as mc

N_CHI2 = 100_000
# Spherical triangle: vertices seen from the origin (an oblique, non-symmetric triangle).
TA = np.array([0.2, 0.1, 1.0])
TB = np.array([0.9, -0.3, 0.6])
TC = np.array([0.1, 0.8, 0.5])
COS_MAX = 0.875  # a cell boundary of the 64-row cos(theta) grid: no cut cells

# name: (sample(u), pdf(x), invert(x), chi2 domain, chi2 bounds, extra chi2 kwargs)
WARPS = {
    "disk_polar": (
        mc.sample_uniform_disk_polar,
        mc.uniform_disk_pdf,
        mc.invert_uniform_disk_polar_sample,
        "square",
        ((-1, 1), (-1, 1)),
        {},
    ),
    "disk_concentric": (
        mc.sample_uniform_disk_concentric,
        mc.uniform_disk_pdf,
        mc.invert_uniform_disk_concentric_sample,
        "square",
        ((-1, 1), (-1, 1)),
        {},
    ),
    "cosine_hemisphere": (
        mc.sample_cosine_hemisphere,
        lambda w: mc.cosine_hemisphere_pdf(w[..., 2]),
        mc.invert_cosine_hemisphere_sample,
        "sphere",
        None,
        {},
    ),
    "uniform_hemisphere": (
        mc.sample_uniform_hemisphere,
        mc.uniform_hemisphere_pdf,
        mc.invert_uniform_hemisphere_sample,
        "sphere",
        None,
        {},
    ),
    "uniform_sphere": (
        mc.sample_uniform_sphere,
        mc.uniform_sphere_pdf,
        mc.invert_uniform_sphere_sample,
        "sphere",
        None,
        {},
    ),
    "uniform_cone": (
        lambda u: mc.sample_uniform_cone(u, COS_MAX),
        lambda w: mc.uniform_cone_pdf(COS_MAX, w),
        lambda w: mc.invert_uniform_cone_sample(w, COS_MAX),
        "sphere",
        None,
        {"resolution": (64, 32)},
    ),
    "uniform_triangle": (
        lambda u: mc.sample_uniform_triangle(u)[..., :2],
        mc.uniform_triangle_pdf,
        mc.invert_uniform_triangle_sample,
        "square",
        None,
        {"resolution": (20, 21)},  # the diagonal must not run through the quadrature points
    ),
    "spherical_triangle": (
        lambda u: mc.sample_spherical_triangle(u, TA, TB, TC),
        lambda w: mc.spherical_triangle_pdf(TA, TB, TC, w),
        lambda w: mc.invert_spherical_triangle_sample(w, TA, TB, TC),
        "sphere",
        None,
        {"resolution": (64, 128)},
    ),
}

WARPS_1D = {
    "linear": (
        lambda u: mc.sample_linear(u, 1.0, 3.0),
        lambda x: mc.linear_pdf(x, 1.0, 3.0),
        lambda x: mc.invert_linear_sample(x, 1.0, 3.0),
        (0.0, 1.0),
    ),
    "tent": (
        lambda u: mc.sample_tent(u, 1.5),
        lambda x: mc.tent_pdf(x, 1.5),
        lambda x: mc.invert_tent_sample(x, 1.5),
        (-1.5, 1.5),
    ),
    "exponential": (
        lambda u: mc.sample_exponential(u, 2.0),
        lambda x: mc.exponential_pdf(x, 2.0),
        lambda x: mc.invert_exponential_sample(x, 2.0),
        (0.0, 15.0),
    ),
    "visible_wavelengths": (
        mc.sample_visible_wavelengths,
        mc.visible_wavelengths_pdf,
        mc.invert_visible_wavelengths_sample,
        (360.0, 830.0),
    ),
}


@pytest.mark.parametrize("name", sorted(WARPS))
def test_warp_chi2(name):
    sample, pdf, _, domain, bounds, kw = WARPS[name]
    res = mc.chi2_test(
        sample,
        pdf,
        domain=domain,
        bounds=bounds,
        n_samples=N_CHI2,
        u_dim=2,
        key=jax.random.key(1),
        n_tests=len(WARPS),
        **kw,
    )
    assert res.passed, res.message
    assert abs(res.pdf_integral - 1) < 2e-3


@pytest.mark.parametrize("name", sorted(WARPS_1D))
def test_warp_1d_chi2(name):
    sample, pdf, _, bounds = WARPS_1D[name]
    res = mc.chi2_test(
        lambda u: sample(u[:, 0]),
        pdf,
        domain="interval",
        bounds=bounds,
        n_samples=N_CHI2,
        u_dim=1,
        key=jax.random.key(2),
        n_tests=len(WARPS_1D),
    )
    assert res.passed, res.message


@pytest.mark.parametrize("name", sorted(WARPS_1D))
def test_warp_1d_pdf_integrates_to_one(name):
    _, pdf, _, (a, b) = WARPS_1D[name]
    x = np.linspace(a, b, 400_001)
    integral = np.trapezoid(np.asarray(pdf(jnp.asarray(x))), x)
    assert integral == pytest.approx(1.0, abs=1e-6)


def _interior_u(key, n, k):
    # Keep away from the seams where inverse maps are discontinuous (wedges, phi = 0).
    return 0.001 + 0.998 * jax.random.uniform(key, (n, k))


@pytest.mark.parametrize("name", sorted(WARPS))
def test_warp_invert_roundtrip(name):
    sample, _, invert, *_ = WARPS[name]
    u = _interior_u(jax.random.key(3), 4096, 2)
    if name == "spherical_triangle":
        # Within 0.1 degree of vertex a, pbrt's inverse snaps u0 to 0 (float32 robustness).
        u = 0.01 + 0.98 * u
    back = invert(sample(u))
    np.testing.assert_allclose(back, u, atol=2e-6 if name == "spherical_triangle" else 1e-9)


@pytest.mark.parametrize("name", sorted(WARPS_1D))
def test_warp_1d_invert_roundtrip(name):
    sample, _, invert, _ = WARPS_1D[name]
    u = _interior_u(jax.random.key(4), 4096, 1)[:, 0]
    np.testing.assert_allclose(invert(sample(u)), u, atol=1e-9)


def test_sample_cosine_hemisphere_pdf_matches_pbrt_values():
    # pbrt-v4: SampleUniformDiskConcentric((0.5, 0.5)) = (0, 0) -> w = (0, 0, 1), pdf = 1/pi.
    w = mc.sample_cosine_hemisphere(jnp.array([0.5, 0.5]))
    np.testing.assert_allclose(w, [0.0, 0.0, 1.0], atol=1e-15)
    assert mc.cosine_hemisphere_pdf(w[2]) == pytest.approx(1 / math.pi)
    assert mc.cosine_hemisphere_pdf(-0.3) == 0.0
    # Unit length everywhere.
    u = jax.random.uniform(jax.random.key(5), (1000, 2))
    for fn in (mc.sample_cosine_hemisphere, mc.sample_uniform_hemisphere, mc.sample_uniform_sphere):
        np.testing.assert_allclose(jnp.linalg.norm(fn(u), axis=-1), 1.0, atol=1e-12)


def test_concentric_disk_reference_points():
    # The four wedge centres map to the axes (Shirley & Chiu 1997).
    u = jnp.array([[1.0 - 1e-12, 0.5], [0.5, 1.0 - 1e-12], [0.0, 0.5], [0.5, 0.0]])
    np.testing.assert_allclose(
        mc.sample_uniform_disk_concentric(u), [[1, 0], [0, 1], [-1, 0], [0, -1]], atol=1e-9
    )


def test_concentric_disk_matches_trigonometric_form_in_float32_and_float64():
    # Shirley & Chiu's map written with NumPy's float64 cos/sin (pbrt's form), against the
    # polynomial sines and cosines the warp uses, in both precisions.
    g = (np.arange(256) + 0.5) / 256  # no variate at 1/2: the map divides by 2 u - 1
    u = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
    o = 2.0 * u - 1.0
    x_major = np.abs(o[:, 0]) > np.abs(o[:, 1])
    r = np.where(x_major, o[:, 0], o[:, 1])
    theta = np.where(
        x_major, np.pi / 4 * o[:, 1] / o[:, 0], np.pi / 2 - np.pi / 4 * o[:, 0] / o[:, 1]
    )
    expected = np.stack([r * np.cos(theta), r * np.sin(theta)], -1)
    np.testing.assert_allclose(mc.sample_uniform_disk_concentric(u), expected, atol=1e-10)
    got32 = mc.sample_uniform_disk_concentric(jnp.asarray(u, jnp.float32))
    assert got32.dtype == jnp.float32
    np.testing.assert_allclose(np.asarray(got32, np.float64), expected, atol=4e-7)


def test_uniform_triangle_barycentrics():
    b = mc.sample_uniform_triangle(jax.random.uniform(jax.random.key(6), (1000, 2)))
    assert jnp.all(b >= 0)
    np.testing.assert_allclose(b.sum(-1), 1.0, atol=1e-15)


def test_spherical_triangle_area_octant():
    # The octant triangle (x, y, z axes) covers 1/8 of the sphere: 4 pi / 8.
    area = mc.spherical_triangle_area(jnp.eye(3)[0], jnp.eye(3)[1], jnp.eye(3)[2])
    assert area == pytest.approx(math.pi / 2, rel=1e-12)
    w = mc.sample_spherical_triangle(
        jax.random.uniform(jax.random.key(7), (1000, 2)),
        jnp.eye(3)[0],
        jnp.eye(3)[1],
        jnp.eye(3)[2],
    )
    assert jnp.all(w >= -1e-12)


def test_visible_wavelengths_match_pbrt_constants():
    # pbrt-v4 SampleVisibleWavelengths / VisibleWavelengthsPDF, rounded constants.
    u = jnp.linspace(0.0, 0.999, 101)
    lam_pbrt = 538 - 138.888889 * jnp.arctanh(0.85691062 - 1.82750197 * u)
    np.testing.assert_allclose(mc.sample_visible_wavelengths(u), lam_pbrt, rtol=2e-7)
    lam = jnp.linspace(360.0, 830.0, 48)
    pdf_pbrt = 0.0039398042 / jnp.cosh(0.0072 * (lam - 538)) ** 2
    np.testing.assert_allclose(mc.visible_wavelengths_pdf(lam), pdf_pbrt, rtol=1e-7)
    assert mc.sample_visible_wavelengths(0.0) == pytest.approx(360.0, abs=1e-9)
    assert float(mc.visible_wavelengths_pdf(359.9)) == 0.0
    assert float(mc.visible_wavelengths_pdf(830.1)) == 0.0


def test_visible_wavelengths_with_pdf_equal_the_two_functions():
    # One inversion gives the sample and its density through 1 / cosh^2(atanh t) = 1 - t^2:
    # equal to sample_visible_wavelengths and visible_wavelengths_pdf evaluated at it.
    u = jnp.concatenate([jnp.asarray([0.0, 0.5, 1.0 - 2**-40]), jnp.linspace(0.0, 1.0, 997)[:-1]])
    lam, pdf = mc.sample_visible_wavelengths_with_pdf(u)
    np.testing.assert_array_equal(np.asarray(lam), np.asarray(mc.sample_visible_wavelengths(u)))
    np.testing.assert_allclose(pdf, mc.visible_wavelengths_pdf(lam), rtol=1e-12, atol=0)
    lam32, pdf32 = mc.sample_visible_wavelengths_with_pdf(u[3:].astype(jnp.float32))
    assert lam32.dtype == pdf32.dtype == jnp.float32
    np.testing.assert_allclose(pdf32, mc.visible_wavelengths_pdf(lam[3:]), rtol=2e-5)
    with pytest.raises(Exception, match="u"):
        mc.sample_visible_wavelengths_with_pdf(jnp.asarray([1.5]))


def test_heuristics_values_and_edges():
    assert mc.balance_heuristic(1, 2.0, 1, 2.0) == pytest.approx(0.5)
    assert mc.power_heuristic(1, 3.0, 1, 1.0) == pytest.approx(0.9)
    assert mc.power_heuristic(2, 1.0, 1, 1.0) == pytest.approx(0.8)
    assert mc.power_heuristic(1, jnp.inf, 1, 1.0) == 1.0
    assert mc.power_heuristic(1, 0.0, 1, 0.0) == 0.0
    assert mc.balance_heuristic(1, 0.0, 1, 0.0) == 0.0
    # The weights of the two strategies sum to one wherever either has density.
    f, g = jax.random.uniform(jax.random.key(8), (2, 100))
    np.testing.assert_allclose(mc.power_heuristic(1, f, 3, g) + mc.power_heuristic(3, g, 1, f), 1.0)
    w = mc.mis_weights(jnp.stack([f, g], -1), jnp.array([1.0, 3.0]), beta=2.0)
    np.testing.assert_allclose(w[:, 0], mc.power_heuristic(1, f, 3, g), rtol=1e-12)
    np.testing.assert_allclose(w.sum(-1), 1.0)


def test_heuristic_grad_finite_at_zero():
    g = jax.grad(lambda f: mc.power_heuristic(1, f, 1, 0.0))(0.0)
    assert jnp.isfinite(g)


def test_warps_jit_vmap_grad():
    u = jax.random.uniform(jax.random.key(9), (64, 2))
    for fn in (mc.sample_cosine_hemisphere,):
        np.testing.assert_allclose(jax.jit(fn)(u), fn(u), rtol=1e-12)
        np.testing.assert_allclose(jax.vmap(fn)(u), fn(u), rtol=1e-12)
        grad = jax.grad(lambda u, fn=fn: jnp.sum(fn(u)[..., 0] + 2 * fn(u)[..., 1]))(u)
        assert jnp.all(jnp.isfinite(grad))
    # Batch shapes broadcast.
    assert mc.sample_cosine_hemisphere(jnp.zeros((3, 4, 2)) + 0.3).shape == (3, 4, 3)
    g = jax.grad(lambda lam: mc.visible_wavelengths_pdf(lam))(500.0)
    assert jnp.isfinite(g)


def test_warps_reject_u_outside_unit_interval():
    with pytest.raises(eqx.EquinoxRuntimeError, match="u"):
        mc.sample_cosine_hemisphere(jnp.array([1.0, 0.5]))
    with pytest.raises(eqx.EquinoxRuntimeError, match="u"):
        eqx.filter_jit(mc.sample_uniform_sphere)(jnp.array([-0.1, 0.5]))
    with pytest.raises(eqx.EquinoxRuntimeError, match="u"):
        mc.sample_visible_wavelengths(jnp.array([1.5]))


# Every sampling warp: (function, length of the last axis of `u` or None, extra arguments).
CHECKED_WARPS = {
    "disk_polar": (mc.sample_uniform_disk_polar, 2, ()),
    "disk_concentric": (mc.sample_uniform_disk_concentric, 2, ()),
    "cosine_hemisphere": (mc.sample_cosine_hemisphere, 2, ()),
    "uniform_hemisphere": (mc.sample_uniform_hemisphere, 2, ()),
    "uniform_sphere": (mc.sample_uniform_sphere, 2, ()),
    "uniform_cone": (mc.sample_uniform_cone, 2, (COS_MAX,)),
    "uniform_triangle": (mc.sample_uniform_triangle, 2, ()),
    "spherical_triangle": (mc.sample_spherical_triangle, 2, (TA, TB, TC)),
    "linear": (mc.sample_linear, None, (1.0, 3.0)),
    "tent": (mc.sample_tent, None, (1.5,)),
    "exponential": (mc.sample_exponential, None, (2.0,)),
    "visible_wavelengths": (mc.sample_visible_wavelengths, None, ()),
}


@pytest.mark.parametrize("name", sorted(CHECKED_WARPS))
def test_warp_check_false_identical_and_check_true_raises_under_jit(name):
    fn, k, args = CHECKED_WARPS[name]
    u = jax.random.uniform(jax.random.key(31), (257, k) if k else (257,))
    checked = jax.jit(lambda u: fn(u, *args))(u)
    unchecked = jax.jit(lambda u: fn(u, *args, check=False))(u)
    np.testing.assert_array_equal(np.asarray(unchecked), np.asarray(checked))
    eager = fn(u, *args)  # (eager and jitted differ by constant folding of `args`, not `check`)
    np.testing.assert_array_equal(np.asarray(fn(u, *args, check=False)), np.asarray(eager))
    bad = u.at[3].set(1.0)
    with pytest.raises(eqx.EquinoxRuntimeError, match="u"):
        jax.block_until_ready(eqx.filter_jit(lambda u: fn(u, *args))(bad))
    with pytest.raises(eqx.EquinoxRuntimeError, match="u"):
        jax.block_until_ready(
            eqx.filter_jit(lambda u: fn(u, *args, check=True))(u.at[5].set(-0.25))
        )
    # check=False leaves validation to the caller: no error, whatever comes out.
    jax.block_until_ready(jax.jit(lambda u: fn(u, *args, check=False))(bad))


def test_warps_reject_wrong_shapes_and_dtypes():
    with pytest.raises(ValueError, match="last axis of length 2"):
        mc.sample_uniform_disk_concentric(jnp.zeros((4, 3)))
    with pytest.raises(ValueError, match="last axis of length 3"):
        mc.invert_cosine_hemisphere_sample(jnp.zeros((4, 2)))
    with pytest.raises(TypeError):  # jaxtyping (in tests) or `as_float_array` refuses ints
        mc.sample_uniform_sphere(np.zeros((4, 2), dtype=np.int32))


@pytest.mark.parametrize("dtype", [jnp.float32, jnp.float64])
def test_warps_dtype_follows_input(dtype):
    u = jnp.full((5, 2), 0.3, dtype=dtype)
    assert mc.sample_cosine_hemisphere(u).dtype == dtype
    assert mc.sample_uniform_triangle(u).dtype == dtype
    assert mc.sample_visible_wavelengths(u[:, 0]).dtype == dtype


def test_uniform_cone_stays_accurate_when_narrow_in_float32():
    """A cone a milliradian wide (a distant sphere light's): with 1 - cos(theta_max) given
    without cancellation, float32 samples fill it uniformly in solid angle (theta^2 uniform
    on [0, theta_max^2], mean theta_max^2 / 2 within 1 %); from the rounded float32
    cos(theta_max) alone the cone's size is off by about 10 %."""
    theta_max = 1e-3
    omc = np.float32(2 * np.sin(theta_max / 2) ** 2)  # 1 - cos, exact to float32 rounding
    u = jax.random.uniform(jax.random.key(3), (200_000, 2), jnp.float32)
    w = mc.sample_uniform_cone(u, jnp.float32(1) - omc, one_minus_cos_theta_max=omc)
    assert w.dtype == jnp.float32
    w = np.asarray(w, np.float64)
    theta2 = np.arctan2(np.hypot(w[:, 0], w[:, 1]), w[:, 2]) ** 2
    assert theta2.max() <= theta_max**2 * (1 + 1e-3)
    assert abs(theta2.mean() / (theta_max**2 / 2) - 1) < 0.01
    rounded = np.asarray(mc.sample_uniform_cone(u, jnp.float32(np.cos(theta_max))), np.float64)
    theta2_rounded = np.arctan2(np.hypot(rounded[:, 0], rounded[:, 1]), rounded[:, 2]) ** 2
    assert abs(theta2_rounded.mean() / (theta_max**2 / 2) - 1) > 0.03
