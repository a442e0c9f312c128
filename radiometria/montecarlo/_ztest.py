"""Per-pixel z-test of a Monte Carlo image against a reference (thesis ch. 6, app. A).

Mitsuba 3's render test suite (`Jakob2022`, `src/render/tests/test_renders.py`) compares a
renderer's image with a reference rendered at many samples per pixel together with its
per-pixel sample variance (the `moment` integrator's second moment minus the squared mean).
Every pixel channel is one two-sided z-test of "same expected value"; the per-test level is
Sidak-corrected for the number of pixels, and the image passes when at least 99.75 % of the
pixel channels pass. A biased renderer fails at moderate spp because its error does not shrink
like `1 / sqrt(spp)` while the test's tolerance does.

This is a testing tool: it runs eagerly on NumPy arrays and returns a plain result object.
"""

import math

import equinox as eqx
import jax.numpy as jnp
import jax.scipy.special as jsp
import numpy as np

from .._checks import check_positive_int


class ZTestResult(eqx.Module):
    """Outcome of `pixel_z_test`.

    **Fields:**

    - `p_values`: two-sided p-value of every pixel channel, shaped as the image (NaN pixels of
        the image under test get p = 0).
    - `z`: the z statistic of every pixel channel, shaped as the image. [dimensionless]
    - `alpha`: the Sidak-corrected per-test significance level `1 - (1 - level)^(1/pixels)`.
    - `fraction_passed`: the fraction of pixel channels with `p > alpha`.
    - `required_fraction`: the fraction needed to pass (0.9975 by default, as Mitsuba).
    - `passed`: `fraction_passed >= required_fraction`.
    - `worst`: up to `n_worst` tuples `(index, ours, reference, variance, p)` of the pixel
        channels with the smallest p-values, `index` a tuple into the image.
    - `message`: a one-paragraph summary, suitable for `assert result.passed, result.message`.

    ??? cite "References"
        `Jakob2022` (`test_renders.py`).
        Thesis app. A.
    """

    p_values: np.ndarray
    z: np.ndarray
    alpha: float
    fraction_passed: float
    required_fraction: float
    passed: bool
    worst: tuple
    message: str


def pixel_z_test(
    image,
    reference,
    reference_variance,
    spp: int,
    reference_spp: int | None = None,
    *,
    significance_level: float = 0.01,
    required_fraction: float = 0.9975,
    variance_floor: float = 1e-4,
    n_worst: int = 5,
    image_variance=None,
) -> ZTestResult:
    r"""Per-pixel two-sided z-test of `image` (an `spp`-sample estimate) against `reference`.

    For every pixel channel,

    $$z = \frac{|I - I_\mathrm{ref}|}{\sqrt{\max(\sigma^2, \sigma^2_\mathrm{floor})\,
        (1/n + 1/n_\mathrm{ref})}},\qquad p = 2\,(1 - \Phi(z)) = \operatorname{erfc}(z/\sqrt2),$$

    where $\sigma^2$ is the reference's per-sample variance (the variance of one sample's
    radiance, not of the mean), $n$ = `spp` and $1/n_\mathrm{ref}$ is dropped when
    `reference_spp` is None (Mitsuba's form: its references use 32000 spp). The variance of the
    image under test is taken to be the reference's per-sample variance, so both renderers must
    estimate the same quantity with comparable noise. Where they do not (another light
    sampling strategy, say), give `image_variance`, the image's own per-sample variance
    $\sigma^2_\mathrm{img}$: the test becomes the two-sample (Welch) z-test,
    $z = |I - I_\mathrm{ref}| / \sqrt{\max(\sigma^2_\mathrm{img}, \sigma^2_\mathrm{floor})/n
    + \max(\sigma^2, \sigma^2_\mathrm{floor})/n_\mathrm{ref}}$. Pixel channel passes when
    $p > \alpha$, $\alpha = 1 - (1 - \text{level})^{1/N_\mathrm{pixels}}$ (the Sidak correction for
    $N_\mathrm{pixels}$ tests), and the image passes when at least `required_fraction` of its
    pixel channels pass.

    **Arguments:**

    - `image`: the image under test, `(H, W)` or `(H, W, C)`. [any radiometric unit]
    - `reference`: the reference's mean image, same shape and unit.
    - `reference_variance`: the reference's per-sample variance, same shape. [unit^2]
    - `spp`: samples per pixel of `image`. [count]
    - `reference_spp`: samples per pixel of the reference, to include the reference mean's own
        variance; None ignores it. [count]
    - `significance_level`: the image-wide level before the Sidak correction.
    - `required_fraction`: fraction of pixel channels that must pass.
    - `variance_floor`: lower bound on the variance (noise-free pixels would otherwise demand
        exact equality). [unit^2]
    - `n_worst`: how many of the worst pixel channels to report.
    - `image_variance`: the image's own per-sample variance, same shape (e.g. `spp` times the
        variance of the means of independent renders), for the two-sample test; needs
        `reference_spp`. None (default): Mitsuba's test. [unit^2]

    **Returns:**

    A `ZTestResult`; `result.passed` is the verdict and `result.message` explains it.

    **Raises:**

    `ValueError` for mismatched shapes, a non-finite reference, a negative or non-finite
    variance, or levels outside (0, 1); `TypeError` for a non-integer `spp`.

    ??? cite "References"
        `Jakob2022` (`src/render/tests/test_renders.py`, `z_test`); `Sidak1967` for the
        correction. Thesis app. A.
    """
    spp = check_positive_int(spp, "spp")
    if reference_spp is not None:
        reference_spp = check_positive_int(reference_spp, "reference_spp")
    n_worst = check_positive_int(n_worst, "n_worst", minimum=0)
    for name, value in (
        ("significance_level", significance_level),
        ("required_fraction", required_fraction),
    ):
        if not 0.0 < float(value) <= 1.0 or (name == "significance_level" and value >= 1.0):
            raise ValueError(f"`{name}` must lie in (0, 1), got {value!r}.")
    if not float(variance_floor) >= 0.0 or not math.isfinite(variance_floor):
        raise ValueError(f"`variance_floor` must be finite and >= 0, got {variance_floor!r}.")
    ours = np.asarray(image, np.float64)
    ref = np.asarray(reference, np.float64)
    var = np.asarray(reference_variance, np.float64)
    if ours.ndim not in (2, 3):
        raise ValueError(f"`image` must be (H, W) or (H, W, C), got shape {ours.shape}.")
    if ref.shape != ours.shape or var.shape != ours.shape:
        raise ValueError(
            f"`image`, `reference` and `reference_variance` must have one shape; got "
            f"{ours.shape}, {ref.shape} and {var.shape}."
        )
    if not np.all(np.isfinite(ref)):
        raise ValueError(f"`reference` has {int(np.sum(~np.isfinite(ref)))} non-finite values.")
    bad = ~np.isfinite(var) | (var < 0)
    if np.any(bad):
        raise ValueError(
            f"`reference_variance` must be finite and >= 0; {int(bad.sum())} values are not "
            f"(first: {var[bad].ravel()[0]!r})."
        )

    n_pixels = ours.shape[0] * ours.shape[1]
    if image_variance is None:
        inv_n = 1.0 / spp + (0.0 if reference_spp is None else 1.0 / reference_spp)
        sigma_mean = np.sqrt(np.maximum(var, variance_floor) * inv_n)
    else:
        own = np.asarray(image_variance, np.float64)
        if own.shape != ours.shape or not np.all(np.isfinite(own) & (own >= 0)):
            raise ValueError(
                f"`image_variance` must be finite, >= 0 and of the image's shape {ours.shape}; "
                f"got shape {own.shape}."
            )
        if reference_spp is None:
            raise ValueError("`image_variance` (the two-sample test) needs `reference_spp`.")
        sigma_mean = np.sqrt(
            np.maximum(own, variance_floor) / spp + np.maximum(var, variance_floor) / reference_spp
        )
    z = np.abs(ours - ref) / sigma_mean
    # erfc keeps tiny p-values accurate where 1 - Phi(z) would round to 0.
    p = np.asarray(jsp.erfc(jnp.asarray(z / math.sqrt(2.0))), np.float64)
    p = np.where(np.isfinite(z), p, 0.0)
    alpha = 1.0 - (1.0 - float(significance_level)) ** (1.0 / n_pixels)
    ok = p > alpha
    fraction = float(np.mean(ok))
    passed = fraction >= required_fraction

    order = np.argsort(p, axis=None, kind="stable")[:n_worst]
    worst = tuple(
        (
            tuple(int(i) for i in np.unravel_index(k, p.shape)),
            float(ours.flat[k]),
            float(ref.flat[k]),
            float(var.flat[k]),
            float(p.flat[k]),
        )
        for k in order
    )
    lines = ", ".join(
        f"{idx}: ours {o:.6g} ref {r:.6g} var {v:.3g} p {pv:.3g}" for idx, o, r, v, pv in worst
    )
    message = (
        f"{'two-sample ' if image_variance is not None else ''}pixel z-test "
        f"{'passed' if passed else 'FAILED'}: {fraction:.4%} of {ok.size} pixel "
        f"channels have p > alpha = {alpha:.3g} (Sidak, level {significance_level} over "
        f"{n_pixels} pixels; need {required_fraction:.2%}); spp {spp}, reference spp "
        f"{reference_spp}; mean signed difference {float(np.nanmean(ours - ref)):.4g}. "
        f"Worst: {lines}."
    )
    return ZTestResult(
        p_values=p,
        z=z,
        alpha=alpha,
        fraction_passed=fraction,
        required_fraction=float(required_fraction),
        passed=bool(passed),
        worst=worst,
        message=message,
    )
