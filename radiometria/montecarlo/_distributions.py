"""Tabulated distributions: discrete, 1D and 2D piecewise-constant (thesis ch. 5-6).

These sample spectra (1D, over wavelength) and environment maps (2D, over the image plane) in
proportion to tabulated values; pbrt-v4's `PiecewiseConstant1D/2D` (`Pharr2023` §A.4.1,
§A.5.6) written as immutable `equinox.Module`s, vectorised over samples.
"""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from .._checks import as_float_array, check_last_axis, check_unit_interval
from .._types import Float, FloatLike, Int


def _check_table(f: Array, name: str) -> Array:
    """Reject negative, non-finite or all-zero tables: at once if concrete, else at run time."""
    if not isinstance(f, jax.core.Tracer):
        a = np.asarray(f)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"`{name}` must be finite; got NaN or inf.")
        if np.any(a < 0):
            raise ValueError(
                f"`{name}` must be non-negative; got min {a.min()!r} "
                "(take the absolute value first if a signed function is meant)."
            )
        if not np.any(a > 0):
            raise ValueError(f"`{name}` must have at least one positive entry; got all zeros.")
        return f
    f = eqx.error_if(f, ~jnp.isfinite(f), f"`{name}` must be finite; got NaN or inf.")
    f = eqx.error_if(f, f < 0, f"`{name}` must be non-negative; got a negative entry.")
    return eqx.error_if(
        f, ~jnp.any(f > 0), f"`{name}` must have at least one positive entry; got all zeros."
    )


def _check_bounds(low, high, name: str):
    low = as_float_array(low, f"{name} low")
    high = as_float_array(high, f"{name} high")
    if low.ndim or high.ndim:
        raise ValueError(f"`{name}` bounds must be scalars, got shapes {low.shape}, {high.shape}.")
    if not isinstance(low, jax.core.Tracer) and not isinstance(high, jax.core.Tracer):
        if not float(high) > float(low):
            raise ValueError(f"`{name}` needs low < high, got [{float(low)}, {float(high)}].")
    return low, high


def _find_interval(
    cdf: Array, u: Array, row: Array | None = None, guide: "_Guide | None" = None
) -> Array:
    """Largest `i` in [0, n-1] with `cdf[row, i] <= u`, for `cdf` of shape (rows, n+1).

    A fixed-length binary search (pbrt's `FindInterval`) so that it vectorises and jits; with a
    `guide` (`_guide_tables`) the search starts from the guide's bracket `[lo, hi]` of `u`.
    A bracket of at most `_SPAN_COUNTED` cells is finished without a search: one gather
    reads the `span` CDF values after `lo` and the answer is `lo` plus how many of those
    within the bracket are `<= u` (the CDF is non-decreasing). Chained searches (a 2D
    distribution's row, then its column) compiled as dependent gathers cost XLA:CPU far more
    than their arithmetic: a `PiecewiseConstant2D.sample` of the `envmap` benchmark's sky
    measured 128-150 ns per sample (2048 samples, float32) with a guided binary search and
    52 ns with the counted bracket. Wider brackets take the guide's `steps` halvings.
    """
    n = cdf.shape[-1] - 1
    flat = cdf.reshape(-1)
    base = jnp.zeros(u.shape, jnp.int32) if row is None else row.astype(jnp.int32) * (n + 1)
    if guide is None:
        lo = jnp.zeros(u.shape, jnp.int32)
        hi = jnp.full(u.shape, n - 1, jnp.int32)
        steps = max(1, math.ceil(math.log2(n + 1)) + 1)
    else:
        m = guide.lower.shape[-1] - 1
        j = jnp.clip(jnp.floor(u * m).astype(jnp.int32), 0, m - 1)
        g = j if row is None else row.astype(jnp.int32) * (m + 1) + j
        lo = guide.lower.reshape(-1)[g].astype(jnp.int32)
        hi = guide.upper.reshape(-1)[g + 1].astype(jnp.int32)
        steps = guide.steps
        if guide.span <= _SPAN_COUNTED:
            if guide.span == 0:
                return lo
            k = jnp.arange(guide.span, dtype=jnp.int32).reshape((1,) * u.ndim + (-1,))
            # cdf[lo + 1 + k] for k < span (clipped at the table's end; masked past `hi`).
            after = jnp.take(flat, (base + lo + 1)[..., None] + k, mode="clip")
            inside = k < (hi - lo)[..., None]
            count = jnp.sum(inside & (after <= u[..., None]), axis=-1, dtype=jnp.int32)
            return lo + count
    for _ in range(steps):
        mid = (lo + hi + 1) // 2
        ok = flat[base + mid] <= u
        lo = jnp.where(ok, mid, lo)
        hi = jnp.where(ok, hi, mid - 1)
        hi = jnp.maximum(hi, lo)
    return lo


_GUIDE_SLACK = 1.0e-6  # > the float32 rounding of u * m and of the CDF's values
_SPAN_COUNTED = 8  # guide brackets up to this many cells are counted, not searched
_GUIDE_BYTES = 32 * 2**20  # the most a distribution's guide tables take


class _Guide(eqx.Module):
    """Guide tables of a CDF (`_guide_tables`): `lower[r, k]` (`upper[r, k]`) is the largest
    `i` with `cdf[r, i] <= k/m - slack` (`+ slack`), so that the interval of any `u` in
    `[j/m, (j+1)/m)` lies in `[lower[r, j], upper[r, j+1]]`, at most `span` cells wider than
    one and `steps` halvings close."""

    lower: Int[Array, "rows cuts"]  # int16 or int32; cuts = m + 1
    upper: Int[Array, "rows cuts"]
    span: int = eqx.field(static=True)

    @property
    def steps(self) -> int:
        """Halvings that close the widest bracket."""
        return math.ceil(math.log2(self.span + 1))


def _guide_tables(cdf) -> "_Guide | None":
    """The cutpoint (guide) tables of a concrete CDF `(rows, n+1)` (`Chen1974`; `Devroye1986`
    §III.2.4): `u` first picks its cutpoint interval, where the search is short unless the
    density varies a lot within a few cells. `m = 4n` cutpoints per row (fewer where the
    tables would pass `_GUIDE_BYTES`, never fewer than `n`), int16 indices where they fit.
    Measured on the `envmap` benchmark's sky (128 x 256, a sun 200x its surroundings): 2 and 3
    search steps with `m = 4n`, 4 and 4 with `m = n`, against 9 and 10 without; the map's
    sampling of 2048 paths took 47, 57 and 89 us. `None` for a traced CDF (built under `jit`):
    the full binary search serves it."""
    if isinstance(cdf, jax.core.Tracer):
        return None
    c = np.asarray(cdf, np.float64)
    rows, n = c.shape[0], c.shape[-1] - 1
    index = np.int16 if n <= np.iinfo(np.int16).max else np.int32
    per_cutpoint = 2 * rows * np.dtype(index).itemsize
    m = max(n, min(4 * n, _GUIDE_BYTES // per_cutpoint - 1))
    k = np.arange(m + 1) / m

    def largest(threshold):
        idx = np.stack([np.searchsorted(row, threshold, side="right") - 1 for row in c])
        return np.clip(idx, 0, n - 1).astype(index)

    lower, upper = largest(k - _GUIDE_SLACK), largest(k + _GUIDE_SLACK)
    widest = int(np.max(upper[:, 1:].astype(np.int64) - lower[:, :-1]))
    return _Guide(jnp.asarray(lower), jnp.asarray(upper), widest)


def _unit_clip(x: Array) -> Array:
    return jnp.clip(x, 0.0, 1.0 - jnp.finfo(x.dtype).epsneg)


def sample_discrete(
    u: FloatLike, weights: FloatLike, *, check: bool = True
) -> tuple[Array, Array, Array]:
    """Pick an index with probability proportional to `weights` and remap `u` for reuse.

    **Arguments:**

    - `u`: uniform variates, any shape, in [0, 1). [dimensionless]
    - `weights`: non-negative weights, shape `(k,)`, not all 0. [dimensionless]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]

    **Returns:**

    `(index, pmf, u_remapped)`: int32 indices, their probabilities, and `u` rescaled to [0, 1)
    within the chosen slot so it can drive a further decision (pbrt's `SampleDiscrete`).
    [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.1 (`SampleDiscrete`).
        Thesis ch. 5.
    """
    w = as_float_array(weights, "weights")
    if w.ndim != 1 or w.shape[0] == 0:
        raise ValueError(f"`weights` must be a non-empty 1D array, got shape {w.shape}.")
    w = _check_table(w, "weights")  # before jit, so that concrete tables fail with ValueError
    return _sample_discrete(as_float_array(u, "u"), w, check)


@eqx.filter_jit
def _sample_discrete(u: Array, w: Array, check: bool) -> tuple[Array, Array, Array]:
    u = check_unit_interval(u) if check else u
    total = jnp.sum(w)
    cdf = jnp.concatenate([jnp.zeros((1,), w.dtype), jnp.cumsum(w) / total]).astype(u.dtype)
    idx = _find_interval(cdf[None, :], u)
    lo, hi = cdf[idx], cdf[idx + 1]
    pmf = w[idx] / total
    width = hi - lo
    u_new = jnp.where(width > 0, (u - lo) / jnp.where(width > 0, width, 1.0), 0.0)
    return idx, pmf, _unit_clip(u_new)


# The tables' arithmetic as compiled programs: built eagerly (a scene's setup), the
# operations would each compile and dispatch on their own (six to eight small XLA programs
# per table, about 0.2 s on a first run); under an outer `jit` they inline.
@jax.jit
def _cdf_1d(f: Array, low: Array, high: Array) -> tuple[Array, Array]:
    """(integral over [low, high], normalised CDF `(n+1,)`) of the bin values `f` `(n,)`."""
    csum = jnp.concatenate([jnp.zeros((1,), f.dtype), jnp.cumsum(f)])
    return csum[-1] * (high - low) / f.shape[0], csum / csum[-1]


@jax.jit
def _conditional_cdfs_2d(f, x0, x1, y0, y1) -> tuple[Array, Array, Array, Array]:
    """(row CDFs `(nv, nu+1)`, row integrals `(nv,)`, x bounds, y bounds) of `f` `(nv, nu)`."""
    nv, nu = f.shape
    csum = jnp.concatenate([jnp.zeros((nv, 1), f.dtype), jnp.cumsum(f, axis=1)], axis=1)
    row_total = csum[:, -1]
    pos = row_total > 0
    # Rows that are all zero are never sampled; give them a uniform CDF (pbrt does too).
    uniform = jnp.broadcast_to(jnp.linspace(0.0, 1.0, nu + 1, dtype=f.dtype), csum.shape)
    cdf = jnp.where(pos[:, None], csum / jnp.where(pos, row_total, 1.0)[:, None], uniform)
    return cdf, row_total * (x1 - x0) / nu, jnp.stack([x0, x1]), jnp.stack([y0, y1])


class PiecewiseConstant1D(eqx.Module):
    """A piecewise-constant density on `[low, high]` proportional to tabulated values.

    Build it with `PiecewiseConstant1D(values, low, high)`; `values` are the function's values
    on `n` equal bins. `sample(u)` inverts the CDF, `pdf(x)` evaluates the density and
    `invert(x)` maps a point back to its variate (pbrt's Sample / PDF / Invert triad).

    **Arguments:**

    - `values`: non-negative bin values `(n,)`, not all 0 (e.g. a spectrum). [any unit]
    - `low`, `high`: the domain, `low < high`. [unit of x, e.g. nm]

    Built from concrete values, it keeps a cutpoint (guide) table of its CDF: `sample` looks
    up the bracket of `u` there and finishes with a few steps of binary search instead of
    log2(n) + 1 (same result; `Chen1974`).

    ??? cite "References"
        `Pharr2023` §A.4.1 (`PiecewiseConstant1D`); `Chen1974`, `Devroye1986` §III.2.4
        (guide tables).
        Thesis ch. 5.
    """

    func: Float[Array, " n"]
    cdf: Float[Array, " n+1"]
    integral: Float[Array, ""]
    low: Float[Array, ""]
    high: Float[Array, ""]
    guide: _Guide | None

    def __init__(self, values: FloatLike, low: FloatLike = 0.0, high: FloatLike = 1.0):
        f = as_float_array(values, "values")
        if f.ndim != 1 or f.shape[0] == 0:
            raise ValueError(f"`values` must be a non-empty 1D array, got shape {f.shape}.")
        f = _check_table(f, "values")
        low, high = _check_bounds(low, high, "PiecewiseConstant1D")
        self.func = f
        self.integral, self.cdf = _cdf_1d(f, low, high)
        self.guide = _guide_tables(self.cdf[None, :])
        self.low = low
        self.high = high

    @property
    def size(self) -> int:
        """Number of bins."""
        return self.func.shape[0]

    @eqx.filter_jit
    def sample(self, u: FloatLike, *, check: bool = True) -> tuple[Array, Array, Array]:
        """Sample `x` by inverting the CDF.

        **Arguments:**

        - `u`: uniform variates, any shape, in [0, 1). [dimensionless]
        - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
            callers that validated already, such as the renderer's inner loop. [bool]

        **Returns:**

        `(x, pdf, offset)`: the samples [unit of x], their density [1/unit of x], and the int32
        bin index.
        """
        u = as_float_array(u, "u")
        u = check_unit_interval(u) if check else u
        cdf = self.cdf.astype(u.dtype)
        o = _find_interval(cdf[None, :], u, guide=self.guide)
        c0, c1 = cdf[o], cdf[o + 1]
        width = c1 - c0
        du = jnp.where(width > 0, (u - c0) / jnp.where(width > 0, width, 1.0), 0.0)
        t = (o.astype(u.dtype) + du) / self.size
        x = self.low + t * (self.high - self.low)
        pdf = self.func[o] / self.integral
        return x, pdf, o

    @eqx.filter_jit
    def pdf(self, x: FloatLike) -> Array:
        """Density at `x` [1/unit of x]; 0 outside `[low, high]`.

        **Arguments:**

        - `x`: points. [unit of x]
        """
        x = as_float_array(x, "x")
        t = (x - self.low) / (self.high - self.low)
        o = jnp.clip(jnp.floor(t * self.size), 0, self.size - 1).astype(jnp.int32)
        inside = (t >= 0) & (t <= 1)
        return jnp.where(inside, self.func[o] / self.integral, 0.0)

    @eqx.filter_jit
    def invert(self, x: FloatLike) -> Array:
        """The variate `u` in [0, 1) that `sample` maps to `x` [dimensionless].

        **Arguments:**

        - `x`: points in `[low, high]`. [unit of x]
        """
        x = as_float_array(x, "x")
        t = (x - self.low) / (self.high - self.low)
        ft = t * self.size
        o = jnp.clip(jnp.floor(ft), 0, self.size - 1).astype(jnp.int32)
        delta = ft - o.astype(x.dtype)
        cdf = self.cdf.astype(x.dtype)
        return _unit_clip(cdf[o] + delta * (cdf[o + 1] - cdf[o]))


class PiecewiseConstant2D(eqx.Module):
    """A piecewise-constant density on a rectangle, proportional to a tabulated image.

    `values[v, u]` holds row `v` (the second coordinate) and column `u` (the first). Sampling
    draws the row from the marginal density with `u[..., 1]` and the column from that row's
    conditional density with `u[..., 0]`, as for environment-map importance sampling.

    **Arguments:**

    - `values`: non-negative table `(nv, nu)`, not all 0 (e.g. luminance x sin(theta)).
        [any unit]
    - `bounds`: `((x0, x1), (y0, y1))`, the domain; the unit square by default. [unit of x, y]

    Built from concrete values, the marginal and every row's conditional CDF keep cutpoint
    (guide) tables, so a sample takes a few search steps per dimension instead of log2(n) + 1
    (same result; `Chen1974`). On `benchmarks/bench_render.py --scene envmap` the binary
    searches of the map's sampling had cost a quarter of the render.

    ??? cite "References"
        `Pharr2023` §A.5.6 (`PiecewiseConstant2D`); `Chen1974`, `Devroye1986` §III.2.4
        (guide tables).
        Thesis ch. 5.
    """

    func: Float[Array, "nv nu"]
    conditional_cdf: Float[Array, "nv nu+1"]
    conditional_guide: _Guide | None
    conditional_integral: Float[Array, " nv"]
    marginal: PiecewiseConstant1D
    x_bounds: Float[Array, "2"]
    y_bounds: Float[Array, "2"]

    def __init__(self, values: FloatLike, bounds=((0.0, 1.0), (0.0, 1.0))):
        f = as_float_array(values, "values")
        if f.ndim != 2 or 0 in f.shape:
            raise ValueError(f"`values` must be a non-empty 2D array (nv, nu), got {f.shape}.")
        f = _check_table(f, "values")
        try:
            (x0, x1), (y0, y1) = bounds
        except (TypeError, ValueError):
            raise ValueError(f"`bounds` must be ((x0, x1), (y0, y1)), got {bounds!r}.") from None
        x0, x1 = _check_bounds(x0, x1, "PiecewiseConstant2D x")
        y0, y1 = _check_bounds(y0, y1, "PiecewiseConstant2D y")
        cdf, self.conditional_integral, self.x_bounds, self.y_bounds = _conditional_cdfs_2d(
            f, x0, x1, y0, y1
        )
        self.func = f
        self.conditional_cdf = cdf
        self.conditional_guide = _guide_tables(cdf)
        self.marginal = PiecewiseConstant1D(self.conditional_integral, y0, y1)

    @property
    def integral(self) -> Array:
        """Integral of the tabulated function over the domain. [unit of values x area]"""
        return self.marginal.integral

    def sample(
        self, u: FloatLike, *, check: bool = True
    ) -> tuple[Float[Array, "*batch 2"], Array, Int[Array, "*batch 2"]]:
        """Sample a point by the marginal-then-conditional inversion.

        **Arguments:**

        - `u`: uniform variates `(..., 2)` in [0, 1). [dimensionless]
        - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
            callers that validated already, such as the renderer's inner loop. [bool]

        **Returns:**

        `(p, pdf, offset)`: points `(..., 2)` [unit of x, y], density [1/area], and the int32
        `(column, row)` cell indices `(..., 2)`.
        """
        u = check_last_axis(as_float_array(u, "u"), "u", 2)
        u = check_unit_interval(u) if check else u
        y, pdf_y, iv = self.marginal.sample(u[..., 1], check=False)
        cdf = self.conditional_cdf.astype(u.dtype)
        nu = self.func.shape[1]
        u0 = u[..., 0]
        iu = _find_interval(cdf, u0, iv, self.conditional_guide)
        c0 = cdf.reshape(-1)[iv * (nu + 1) + iu]
        c1 = cdf.reshape(-1)[iv * (nu + 1) + iu + 1]
        width = c1 - c0
        du = jnp.where(width > 0, (u0 - c0) / jnp.where(width > 0, width, 1.0), 0.0)
        x0, x1 = self.x_bounds[0], self.x_bounds[1]
        x = x0 + (iu.astype(u.dtype) + du) / nu * (x1 - x0)
        pdf_x = self.func[iv, iu] / self.conditional_integral[iv]
        return jnp.stack([x, y], axis=-1), pdf_x * pdf_y, jnp.stack([iu, iv], axis=-1)

    @eqx.filter_jit
    def pdf(self, p: FloatLike) -> Array:
        """Density at points `p` `(..., 2)` [1/area]; 0 outside the domain.

        **Arguments:**

        - `p`: points `(..., 2)`. [unit of x, y]
        """
        p = check_last_axis(as_float_array(p, "p"), "p", 2)
        nv, nu = self.func.shape
        tx = (p[..., 0] - self.x_bounds[0]) / (self.x_bounds[1] - self.x_bounds[0])
        ty = (p[..., 1] - self.y_bounds[0]) / (self.y_bounds[1] - self.y_bounds[0])
        iu = jnp.clip(jnp.floor(tx * nu), 0, nu - 1).astype(jnp.int32)
        iv = jnp.clip(jnp.floor(ty * nv), 0, nv - 1).astype(jnp.int32)
        inside = (tx >= 0) & (tx <= 1) & (ty >= 0) & (ty <= 1)
        return jnp.where(inside, self.func[iv, iu] / self.integral, 0.0)

    @eqx.filter_jit
    def invert(self, p: FloatLike) -> Float[Array, "*batch 2"]:
        """The variates `u` `(..., 2)` in [0, 1) that `sample` maps to `p` [dimensionless].

        **Arguments:**

        - `p`: points `(..., 2)` in the domain. [unit of x, y]
        """
        p = check_last_axis(as_float_array(p, "p"), "p", 2)
        nu = self.func.shape[1]
        u1 = self.marginal.invert(p[..., 1])
        ty = (p[..., 1] - self.y_bounds[0]) / (self.y_bounds[1] - self.y_bounds[0])
        nv = self.func.shape[0]
        iv = jnp.clip(jnp.floor(ty * nv), 0, nv - 1).astype(jnp.int32)
        tx = (p[..., 0] - self.x_bounds[0]) / (self.x_bounds[1] - self.x_bounds[0])
        ft = tx * nu
        iu = jnp.clip(jnp.floor(ft), 0, nu - 1).astype(jnp.int32)
        delta = ft - iu.astype(p.dtype)
        cdf = self.conditional_cdf.astype(p.dtype).reshape(-1)
        c0 = cdf[iv * (nu + 1) + iu]
        c1 = cdf[iv * (nu + 1) + iu + 1]
        u0 = _unit_clip(c0 + delta * (c1 - c0))
        return jnp.stack([u0, u1], axis=-1)
