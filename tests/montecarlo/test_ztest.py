"""`pixel_z_test` on synthetic Gaussian images whose truth is known (NumPy, fixed seeds).

The p-values are checked against SciPy's normal survival function, the level against the
Sidak formula; the verdicts against images that are unbiased or biased by construction.
"""

import numpy as np
import pytest
from scipy import stats

from radiometria.montecarlo import pixel_z_test

SHAPE = (32, 32, 3)
SIGMA = 0.5  # per-sample standard deviation [arbitrary radiance unit]


def _truth(seed=0):
    return np.random.default_rng(seed).uniform(0.5, 1.0, SHAPE)


def _estimate(truth, spp, seed):
    """The mean of `spp` samples of variance SIGMA^2 around `truth`: Normal(truth, SIGMA^2/spp)."""
    return truth + np.random.default_rng(seed).normal(0.0, SIGMA / np.sqrt(spp), truth.shape)


@pytest.mark.parametrize("reference_spp", [None, 65536])
def test_two_unbiased_estimates_pass(reference_spp):
    truth = _truth()
    var = np.full(SHAPE, SIGMA**2)
    for seed in range(1, 6):
        ours = _estimate(truth, 4096, seed)
        ref = _estimate(truth, 65536, seed + 100)
        res = pixel_z_test(ours, ref, var, 4096, reference_spp)
        assert res.passed, res.message


def test_five_percent_bias_fails():
    truth = _truth()
    var = np.full(SHAPE, SIGMA**2)
    ours = _estimate(1.05 * truth, 4096, 1)
    res = pixel_z_test(ours, _estimate(truth, 65536, 2), var, 4096, 65536)
    assert not res.passed, res.message
    assert "FAILED" in res.message
    # the worst pixels are listed with their values, the smallest p first
    ps = [w[-1] for w in res.worst]
    assert len(ps) == 5 and ps == sorted(ps) and ps[0] == res.p_values.min()


def test_bias_in_one_percent_of_the_pixels_fails():
    """A local defect (a 3 x 3 block off by 50 %) is found although the image mean barely moves."""
    truth = _truth()
    var = np.full(SHAPE, SIGMA**2)
    biased = truth.copy()
    biased[10:13, 20:23] *= 1.5
    ours = _estimate(biased, 1024, 3)
    res = pixel_z_test(ours, _estimate(truth, 65536, 4), var, 1024, 65536)
    assert not res.passed, res.message
    assert {w[0][:2] for w in res.worst} <= {(i, j) for i in range(10, 13) for j in range(20, 23)}


def test_two_sample_test_for_an_image_noisier_than_its_reference():
    """An unbiased image with 20x the reference's per-sample variance (another sampling
    strategy) fails Mitsuba's one-sample test, which assumes equal noise, and passes the
    two-sample test given its own variance, estimated from 16 independent renders as a
    renderer would; the same image 5 % too bright fails the two-sample test too."""
    truth = _truth()
    ref_var = np.full(SHAPE, SIGMA**2)
    ref = _estimate(truth, 65536, 7)
    noisy = 20.0 * SIGMA**2  # the image's per-sample variance
    renders = np.stack([
        truth + np.random.default_rng(50 + k).normal(0.0, np.sqrt(noisy / 256), SHAPE)
        for k in range(16)
    ])  # fmt: skip
    ours, own = renders.mean(axis=0), 256 * renders.var(axis=0, ddof=1)
    spp = 16 * 256
    assert not pixel_z_test(ours, ref, ref_var, spp, 65536).passed
    res = pixel_z_test(ours, ref, ref_var, spp, 65536, image_variance=own)
    assert res.passed and res.message.startswith("two-sample"), res.message
    expected = np.sqrt(own / spp + ref_var / 65536)
    np.testing.assert_allclose(res.z, np.abs(ours - ref) / expected, rtol=1e-12)
    biased = pixel_z_test(1.05 * ours, ref, ref_var, spp, 65536, image_variance=own)
    assert not biased.passed, biased.message


def test_p_values_and_level_match_scipy():
    rng = np.random.default_rng(5)
    ours, ref = rng.uniform(0, 1, (2, 8, 8, 3))
    var = rng.uniform(0, 0.5, (8, 8, 3))
    var[0, 0, 0] = 0.0  # floored to 1e-4
    spp, ref_spp = 16, 1000
    res = pixel_z_test(ours, ref, var, spp, ref_spp)
    z = np.abs(ours - ref) / np.sqrt(np.maximum(var, 1e-4) * (1 / spp + 1 / ref_spp))
    np.testing.assert_allclose(res.z, z, rtol=1e-12)
    np.testing.assert_allclose(res.p_values, 2 * stats.norm.sf(z), rtol=1e-10, atol=1e-300)
    assert res.alpha == pytest.approx(1 - 0.99 ** (1 / 64), rel=1e-12)
    assert res.fraction_passed == pytest.approx(np.mean(2 * stats.norm.sf(z) > res.alpha))
    # Mitsuba's form: no reference spp term
    res = pixel_z_test(ours, ref, var, spp)
    np.testing.assert_allclose(res.z, np.abs(ours - ref) * np.sqrt(spp / np.maximum(var, 1e-4)))


def test_nan_pixels_fail_and_grey_images_work():
    truth = _truth()[..., 0]  # (H, W): one channel
    var = np.full(truth.shape, SIGMA**2)
    ours = _estimate(truth, 256, 6)
    assert pixel_z_test(ours, truth, var, 256).passed
    ours[:4] = np.nan  # 12.5 % of the pixels
    res = pixel_z_test(ours, truth, var, 256)
    assert not res.passed and res.p_values[0, 0] == 0.0


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"reference": np.zeros((4, 4, 2))}, ValueError, "one shape"),
        ({"reference_variance": -np.ones((4, 4, 3))}, ValueError, "reference_variance"),
        ({"reference": np.full((4, 4, 3), np.inf)}, ValueError, "non-finite"),
        ({"spp": 1.5}, TypeError, "spp"),
        ({"spp": 0}, ValueError, "spp"),
        ({"significance_level": 1.0}, ValueError, "significance_level"),
        ({"image": np.zeros(4)}, ValueError, "image"),
        ({"image_variance": np.ones((4, 4, 2))}, ValueError, "image_variance"),
        ({"image_variance": np.ones((4, 4, 3))}, ValueError, "needs `reference_spp`"),
    ],
)
def test_bad_input_is_named(kwargs, error, match):
    args = {
        "image": np.zeros((4, 4, 3)),
        "reference": np.zeros((4, 4, 3)),
        "reference_variance": np.ones((4, 4, 3)),
        "spp": 4,
    }
    args.update(kwargs)
    with pytest.raises(error, match=match):
        pixel_z_test(**args)
