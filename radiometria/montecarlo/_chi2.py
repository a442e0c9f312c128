"""Pearson chi-square goodness-of-fit test of a sampler against its density (thesis ch. 5, app. A).

The recipe of Mitsuba 3's `chi2.py` (`Jakob2022`): histogram the samples on a grid over the
domain, integrate the claimed density over every grid cell numerically (sub-cell midpoint
quadrature), pool cells whose expected count is low, and compare with Pearson's statistic. The
p-value comes from the regularised upper incomplete gamma function (`jax.scipy`), so the library
needs no SciPy. Many tests at once share a significance level through the Sidak correction.

This is a testing tool: it runs eagerly (not under `jit`), returns a plain result object, and is
public so that every subpackage's tests can check its own samplers with it.
"""

import math
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import check_choice, check_positive_int
from .._types import Key

_DOMAINS = ("sphere", "square", "interval")


class Chi2Result(eqx.Module):
    """Outcome of `chi2_test`.

    **Fields:**

    - `statistic`: Pearson's chi-square statistic after pooling. [dimensionless]
    - `dof`: degrees of freedom (pooled cells - 1). [dimensionless]
    - `p_value`: probability of a statistic at least this large if the sampler matches the pdf.
    - `threshold`: the Sidak-corrected significance level the p-value is compared with.
    - `passed`: `p_value > threshold`, no invalid samples, no samples where the pdf is 0, and the
        pdf integrates to 1 within `pdf_tolerance`.
    - `pdf_integral`: the numerical integral of the pdf over the domain (should be 1).
    - `n_invalid`: samples that are NaN, outside the domain bounds or not unit vectors.
    - `n_outside_support`: samples that fell in cells where the pdf integrates to 0.
    - `observed`, `expected`: the histograms `(resolution)` as NumPy arrays, for plotting.
    - `message`: a one-paragraph summary, suitable for `assert result.passed, result.message`.

    ??? cite "References"
        `Jakob2022` (`mitsuba.chi2`).
        Thesis app. A.
    """

    statistic: float
    dof: int
    p_value: float
    threshold: float
    passed: bool
    pdf_integral: float
    n_invalid: int
    n_outside_support: int
    observed: np.ndarray
    expected: np.ndarray
    message: str


def _default_resolution(domain: str, n_samples: int) -> tuple[int, ...]:
    if domain == "interval":
        return (int(np.clip(n_samples // 200, 8, 256)),)
    r = int(np.clip(math.sqrt(n_samples / 200), 4, 64))
    return (r, 2 * r) if domain == "sphere" else (r, r)


def _default_bounds(domain: str):
    if domain == "interval":
        return ((0.0, 1.0),)
    if domain == "square":
        return ((0.0, 1.0), (0.0, 1.0))
    return ((-1.0, 1.0), (0.0, 2 * math.pi))  # (cos theta, phi): an equal-area parametrisation


def _to_points(domain: str, coords: np.ndarray) -> np.ndarray:
    """Grid coordinates (m, k) -> the points the pdf takes."""
    if domain == "interval":
        return coords[:, 0]
    if domain == "square":
        return coords
    z, phi = coords[:, 0], coords[:, 1]
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def _to_coords(domain: str, samples: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Samples -> grid coordinates (n, k) and a validity mask."""
    if domain == "interval":
        s = samples.reshape(n, -1)
        if s.shape[1] != 1:
            raise ValueError(
                f"domain 'interval' needs samples of shape (n,) or (n, 1), got {samples.shape}."
            )
        return s, np.all(np.isfinite(s), axis=1)
    if domain == "square":
        if samples.shape != (n, 2):
            raise ValueError(
                f"domain 'square' needs samples of shape ({n}, 2), got {samples.shape}."
            )
        return samples, np.all(np.isfinite(samples), axis=1)
    if samples.shape != (n, 3):
        raise ValueError(
            f"domain 'sphere' needs unit vectors of shape ({n}, 3), got {samples.shape}."
        )
    norm = np.linalg.norm(samples, axis=1)
    valid = np.all(np.isfinite(samples), axis=1) & (np.abs(norm - 1.0) < 1e-3)
    w = samples / np.where(norm > 0, norm, 1.0)[:, None]
    z = np.clip(w[:, 2], -1.0, 1.0)
    phi = np.arctan2(w[:, 1], w[:, 0])
    phi = np.where(phi < 0, phi + 2 * math.pi, phi)
    return np.stack([z, phi], axis=-1), valid


_TRACE_ERRORS = (
    jax.errors.ConcretizationTypeError,
    jax.errors.TracerArrayConversionError,
    jax.errors.TracerBoolConversionError,
    jax.errors.TracerIntegerConversionError,
)


def _call(fn, x):
    """`equinox.filter_jit(fn)(x)`, or `fn(x)` eagerly when `fn` cannot be traced (NumPy code, say).

    Jitting is only a speed-up here: one compilation instead of one per primitive.
    """
    try:
        return eqx.filter_jit(fn)(x)
    except _TRACE_ERRORS:
        return fn(x)


def _cell_integrals(pdf_fn, domain, bounds, res, cells: np.ndarray, q: int, dtype) -> np.ndarray:
    """Integral of the pdf over the given cells (flat indices), by q^k-point midpoint rules."""
    k = len(res)
    lo = np.array([b[0] for b in bounds])
    width = np.array([(b[1] - b[0]) / r for b, r in zip(bounds, res, strict=True)])
    idx = np.stack(np.unravel_index(cells, res), axis=-1)  # (c, k)
    sub = (np.arange(q) + 0.5) / q
    offs = np.stack(np.meshgrid(*([sub] * k), indexing="ij"), axis=-1).reshape(-1, k)  # (q^k, k)
    out = np.empty(len(cells))
    chunk = max(1, 2_000_000 // len(offs))
    chunk = min(chunk, len(cells))
    for s in range(0, len(cells), chunk):
        ci = idx[s : s + chunk]
        m = len(ci)
        if m < chunk:  # pad the last chunk so that the jitted pdf compiles once
            ci = np.concatenate([ci, np.repeat(ci[-1:], chunk - m, axis=0)])
        coords = lo + (ci[:, None, :] + offs[None, :, :]) * width  # (c, q^k, k)
        pts = _to_points(domain, coords.reshape(-1, k))
        vals = np.asarray(_call(pdf_fn, jnp.asarray(pts, dtype=dtype)), dtype=np.float64)
        if vals.size != coords.shape[0] * coords.shape[1]:
            raise ValueError(
                f"`pdf_fn` must return one density per point: got shape {vals.shape} for "
                f"{coords.shape[0] * coords.shape[1]} points."
            )
        vals = np.where(np.isfinite(vals), vals, np.nan).reshape(coords.shape[:2])
        out[s : s + m] = vals[:m].mean(axis=1) * np.prod(width)
    return out


def chi2_test(
    sample_fn: Callable,
    pdf_fn: Callable,
    *,
    domain: str,
    n_samples: int,
    key: Key,
    resolution: int | tuple[int, ...] | None = None,
    bounds=None,
    u_dim: int | None = None,
    quadrature: int = 8,
    min_expected: float = 5.0,
    alpha: float = 0.01,
    n_tests: int = 1,
    pdf_tolerance: float = 1e-2,
) -> Chi2Result:
    r"""Chi-square goodness-of-fit test of `sample_fn` against the density `pdf_fn`.

    Signature and contract:

    ```python
    chi2_test(sample_fn, pdf_fn, *, domain, n_samples, key, resolution=None, bounds=None,
              u_dim=None, quadrature=8, min_expected=5.0, alpha=0.01, n_tests=1,
              pdf_tolerance=1e-2) -> Chi2Result
    ```

    - `sample_fn(key) -> samples`, called once with `key`; or, when `u_dim` is given,
      `sample_fn(u) -> samples` with `u = jax.random.uniform(key, (n_samples, u_dim))`.
      It must return `n_samples` samples:
        - `domain="sphere"`: unit vectors `(n, 3)`; `pdf_fn` is per steradian. The grid is over
          `(cos theta, phi)` in `[-1, 1] x [0, 2 pi)` (equal-area cells), `resolution=(n_cos,
          n_phi)`; an int `r` means `(r, 2r)`. Hemispheres and cones are fine: cells where the pdf
          integrates to 0 are dropped (samples there fail the test).
        - `domain="square"`: points `(n, 2)` in `bounds = ((x0, x1), (y0, y1))` (unit square by
          default, e.g. `((-1, 1), (-1, 1))` for disks); `pdf_fn` is per unit area.
        - `domain="interval"`: scalars `(n,)` in `bounds = (a, b)` ((0, 1) by default);
          `pdf_fn` is per unit length.
    - `pdf_fn(points) -> densities`: vectorised over a batch of points shaped as the samples
      (`(m, 3)`, `(m, 2)` or `(m,)`), returning `(m,)` densities. It is evaluated on a
      `quadrature`^k midpoint rule inside every grid cell to get the expected counts.

    Cells are sorted by expected count and the smallest are pooled until each pooled cell
    expects at least `min_expected` samples (Mitsuba's rule). The test passes when the p-value
    exceeds the Sidak-corrected level `1 - (1 - alpha)^(1 / n_tests)` (use `n_tests` when one
    test function runs many chi-square tests), no sample is invalid or lands where the pdf
    integrates to 0, and the pdf integrates to 1 within `pdf_tolerance`.

    **Arguments:**

    - `sample_fn`: the sampler under test, as above.
    - `pdf_fn`: its claimed density, as above. [1/measure of the domain: sr^-1, area^-1, length^-1]
    - `domain`: `"sphere"`, `"square"` or `"interval"`.
    - `n_samples`: number of samples, e.g. 1e5. [dimensionless]
    - `key`: a `jax.random` key.
    - `resolution`: grid cells per axis; by default about 200 samples per cell. [dimensionless]
    - `bounds`: the domain's box for `"square"` / `"interval"` (see above). [unit of samples]
    - `u_dim`: pass uniform variates of this many dimensions instead of a key. [dimensionless]
    - `quadrature`: midpoint points per cell and axis. [dimensionless]
    - `min_expected`: pooling threshold on expected counts. [dimensionless]
    - `alpha`, `n_tests`: significance level and number of tests for the Sidak correction.
        [dimensionless]
    - `pdf_tolerance`: allowed `|integral(pdf) - 1|`. [dimensionless]

    **Returns:**

    A `Chi2Result`; `result.passed` is the verdict and `result.message` explains it.

    ```python
    res = chi2_test(lambda u: sample_cosine_hemisphere(u),
                    lambda w: cosine_hemisphere_pdf(w[:, 2]),
                    domain="sphere", n_samples=100_000, u_dim=2, key=jax.random.key(0))
    assert res.passed, res.message
    ```

    ??? cite "References"
        `Jakob2022` (`mitsuba.chi2`); `Owen2013` ch. 2.
        Thesis app. A.
    """
    check_choice(domain, "domain", _DOMAINS)
    n = check_positive_int(n_samples, "n_samples")
    quadrature = check_positive_int(quadrature, "quadrature")
    n_tests = check_positive_int(n_tests, "n_tests")
    if not 0 < alpha < 1:
        raise ValueError(f"`alpha` must lie in (0, 1), got {alpha!r}.")
    k = 1 if domain == "interval" else 2
    if resolution is None:
        res = _default_resolution(domain, n)
    elif isinstance(resolution, int | np.integer):
        r = check_positive_int(resolution, "resolution")
        res = (r,) if k == 1 else ((r, 2 * r) if domain == "sphere" else (r, r))
    else:
        res = tuple(check_positive_int(r, "resolution") for r in resolution)
    if len(res) != k:
        raise ValueError(f"`resolution` for domain {domain!r} needs {k} entries, got {res}.")
    if domain == "sphere":
        if bounds is not None:
            raise ValueError("domain 'sphere' takes no `bounds`.")
        bnds = _default_bounds(domain)
    elif bounds is None:
        bnds = _default_bounds(domain)
    else:
        bnds = (tuple(bounds),) if domain == "interval" else tuple(tuple(b) for b in bounds)
        if len(bnds) != k or any(len(b) != 2 or not b[1] > b[0] for b in bnds):
            raise ValueError(
                f"`bounds` for domain {domain!r} must be {k} pairs (lo < hi), got {bounds!r}."
            )

    dtype = jnp.result_type(float)
    if u_dim is not None:
        u_dim = check_positive_int(u_dim, "u_dim")
        samples = _call(sample_fn, jax.random.uniform(key, (n, u_dim), dtype=dtype))
    else:
        samples = _call(sample_fn, key)
    samples = np.asarray(samples, dtype=np.float64)
    coords, valid = _to_coords(domain, samples, n)

    lo = np.array([b[0] for b in bnds])
    hi = np.array([b[1] for b in bnds])
    t = (coords - lo) / (hi - lo)
    inside = valid & np.all((t >= 0) & (t <= 1), axis=1)
    cell = np.clip(np.floor(t[inside] * np.array(res)), 0, np.array(res) - 1).astype(np.int64)
    flat = np.ravel_multi_index(tuple(cell.T), res)
    n_cells = int(np.prod(res))
    observed = np.bincount(flat, minlength=n_cells).astype(np.float64)
    n_invalid = int(n - inside.sum())

    integrals = _cell_integrals(pdf_fn, domain, bnds, res, np.arange(n_cells), quadrature, dtype)
    if np.any(np.isnan(integrals)):
        raise ValueError("`pdf_fn` returned NaN or inf inside the domain.")
    # Cells that the quadrature sees as empty but that received samples: refine before failing,
    # since the support of a discontinuous pdf may clip a cell between quadrature points.
    suspect = np.flatnonzero((integrals <= 0) & (observed > 0))
    if suspect.size:
        integrals[suspect] = _cell_integrals(
            pdf_fn, domain, bnds, res, suspect, quadrature * 8, dtype
        )
    pdf_integral = float(integrals.sum())
    expected = integrals * n
    n_outside = int(observed[expected <= 0].sum())

    order = np.argsort(expected, kind="stable")
    obs_s, exp_s = observed[order], expected[order]
    keep = exp_s > 0
    obs_s, exp_s = obs_s[keep], exp_s[keep]
    stat, dof, pool_obs, pool_exp = 0.0, 0, 0.0, 0.0
    for o, e in zip(obs_s, exp_s, strict=True):
        if e < min_expected or pool_exp < min_expected and pool_exp > 0:
            pool_obs += o
            pool_exp += e
        else:
            stat += (o - e) ** 2 / e
            dof += 1
    if pool_exp > 0:
        stat += (pool_obs - pool_exp) ** 2 / pool_exp
        dof += 1
    dof -= 1
    if dof < 1:
        raise ValueError(
            f"Too few cells with enough expected samples (dof = {dof}): raise `n_samples` or "
            f"`resolution` (now {res})."
        )
    p_value = float(jax.scipy.special.gammaincc(jnp.asarray(dof / 2), jnp.asarray(stat / 2)))
    threshold = 1.0 - (1.0 - alpha) ** (1.0 / n_tests)
    ok_int = abs(pdf_integral - 1.0) <= pdf_tolerance
    passed = bool(p_value > threshold and n_invalid == 0 and n_outside == 0 and ok_int)
    problems = []
    if p_value <= threshold:
        problems.append(f"p-value {p_value:.3g} <= {threshold:.3g}: samples do not follow the pdf")
    if n_invalid:
        problems.append(f"{n_invalid} samples are NaN, off the domain or not unit vectors")
    if n_outside:
        problems.append(f"{n_outside} samples fell where the pdf integrates to 0")
    if not ok_int:
        problems.append(f"the pdf integrates to {pdf_integral:.6g}, not 1")
    message = (
        f"chi2 test on {domain!r} ({n} samples, grid {res}): statistic {stat:.4g}, dof {dof}, "
        f"p = {p_value:.4g}, pdf integral {pdf_integral:.6g}: "
        + ("passed" if passed else "FAILED: " + "; ".join(problems))
    )
    return Chi2Result(
        statistic=float(stat),
        dof=int(dof),
        p_value=p_value,
        threshold=float(threshold),
        passed=passed,
        pdf_integral=pdf_integral,
        n_invalid=n_invalid,
        n_outside_support=n_outside,
        observed=observed.reshape(res),
        expected=expected.reshape(res),
        message=message,
    )
