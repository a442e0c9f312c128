r"""Pixel reconstruction filters and filter importance sampling (thesis section 2.3.2).

Every filter is separable, $f(x, y) = f_1(x) f_1(y)$, supported on $[-r, r]^2$ (radius $r$ in
pixels), and normalised so that $\iint f \,\mathrm{d}x\,\mathrm{d}y = 1$. `evaluate(offset)`
gives $f$; `sample(u)` draws offsets with density $p \propto |f|$ (exactly for box, tent and
Gaussian, through a tabulated piecewise-constant density otherwise) and returns the sample
weight $w = f / p$ of thesis eq. 2.35 (constant 1 where $p = f$; carrying the sign of $f$ on
negative lobes); `pdf(offset)` gives $p$.

The tabulated sampler is `radiometria.montecarlo.PiecewiseConstant2D` over the filter's
support, with cell values the exact cell integrals of $|f|$ (pbrt-v4's `FilterSampler` does the
same with point values), 32 cells per pixel and axis.
"""

import abc
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import as_float_array, check_last_axis, check_unit_interval
from .._types import Array, ArrayLike, Float
from ..montecarlo import PiecewiseConstant2D

# Gauss-Legendre rule for the normalisation and cell integrals (exact for cubic pieces).
_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)
_CELLS_PER_PIXEL = 32  # resolution of the tabulated sampler (pbrt-v4 uses 32 per pixel too)


def _check_param(value, name: str, *, positive: bool = True) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise TypeError(
            f"Filter parameter `{name}` must be a real number, got {type(value).__name__}."
        )
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"Filter parameter `{name}` must be finite, got {value}.")
    if positive and value <= 0.0:
        raise ValueError(f"Filter parameter `{name}` must be > 0 [px], got {value}.")
    return value


def _integrate_cells(fn, edges: np.ndarray) -> np.ndarray:
    """Integral of NumPy `fn` over each cell [edges[i], edges[i+1]] (Gauss-Legendre)."""
    a, b = edges[:-1, None], edges[1:, None]
    x = 0.5 * (b - a) * _GL_X[None, :] + 0.5 * (a + b)
    return (0.5 * (b - a)[:, 0]) * (fn(x) @ _GL_W)


def _integral(fn, radius: float, n_cells: int = 512) -> float:
    return float(_integrate_cells(fn, np.linspace(-radius, radius, n_cells + 1)).sum())


def _offsets(xy: ArrayLike, name: str = "offset") -> Array:
    return check_last_axis(as_float_array(xy, name), name, 2)


def _uniforms(u: ArrayLike) -> Array:
    u = check_last_axis(as_float_array(u, "u"), "u", 2)
    return check_unit_interval(u, "u")


class AbstractFilter(eqx.Module):
    r"""A separable pixel reconstruction filter with importance sampling (thesis eq. 2.31-2.35).

    Subclasses define the normalised 1D profile `evaluate_1d`; `evaluate` is its product over
    the two axes. `sample` draws offsets with density `pdf` $\propto |f|$ and returns the
    weight $f/p$.

    !!! note "Thesis"
        Thesis section 2.3.2, eq. 2.31-2.35.

    ??? cite "References"
        `Pharr2023` §8.8; `Ernst2006`.
    """

    radius: eqx.AbstractVar[float]

    @abc.abstractmethod
    def evaluate_1d(self, x: Array) -> Array:
        """Normalised 1D profile $f_1(x)$, unit integral, 0 for $|x| \\ge r$ (`x` [px]). [px^-1]"""

    @abc.abstractmethod
    def sample(self, u: ArrayLike) -> tuple[Float[Array, "*batch 2"], Float[Array, "*batch"]]:
        r"""Filter importance sampling: an offset with density $p \propto |f|$ and weight $f / p$.

        **Arguments:**

        - `u`: uniform variates in $[0, 1)^2$, shape (..., 2). [dimensionless]

        **Returns:**

        `(offset, weight)`: offsets (..., 2) in $[-r, r]^2$ [px] and weights $w = f/p$ (...)
        [dimensionless]. $E[w] = \iint f = 1$; $w \equiv 1$ for box and tent, within about
        $2 \cdot 10^{-3}$ of 1 for the Gaussian away from its radius; $w < 0$ on negative
        lobes (Mitchell, Lanczos). Used as in thesis eq. 2.35,
        $r_f \approx \sum w_i r_i / \sum w_i$.

        !!! note "Thesis"
            Eq. 2.35, section 2.3.2.

        ??? cite "References"
            `Ernst2006`; `Pharr2023` §8.8.
        """

    @abc.abstractmethod
    def pdf(self, offset: ArrayLike) -> Float[Array, "*batch"]:
        """Density of the offsets drawn by `sample`, at `offset` (..., 2) [px]; in [px^-2].

        !!! note "Thesis"
            Eq. 2.35 ($p$).
        """

    def evaluate(self, offset: ArrayLike) -> Float[Array, "*batch"]:
        r"""Filter value $f(x, y) = f_1(x) f_1(y)$ at offsets from the pixel centre.

        **Arguments:**

        - `offset`: offsets $(x, y)$ (..., 2) from the pixel centre. [px]

        **Returns:**

        $f$ (...), normalised to unit integral over the plane; 0 outside $[-r, r]^2$. [px^-2]

        !!! note "Thesis"
            Eq. 2.31 (the filter $f$).
        """
        xy = _offsets(offset)
        return self.evaluate_1d(xy[..., 0]) * self.evaluate_1d(xy[..., 1])


class _AbstractAnalyticFilter(AbstractFilter):
    """A filter sampled per axis by an analytic inverse CDF (`_sample_1d`, `_pdf_1d`)."""

    @abc.abstractmethod
    def _sample_1d(self, u: Array) -> tuple[Array, Array]:
        """Offsets `x` with density `_pdf_1d` and their weights `f_1(x) / p(x)`. [px]"""

    @abc.abstractmethod
    def _pdf_1d(self, x: Array) -> Array:
        """Density of `_sample_1d`. [px^-1]"""

    def sample(self, u):
        u = _uniforms(u)
        x, wx = self._sample_1d(u[..., 0])
        y, wy = self._sample_1d(u[..., 1])
        return jnp.stack([x, y], axis=-1), wx * wy

    def pdf(self, offset):
        xy = _offsets(offset)
        return self._pdf_1d(xy[..., 0]) * self._pdf_1d(xy[..., 1])


class BoxFilter(_AbstractAnalyticFilter):
    r"""Box filter: $f_1(x) = 1 / (2r)$ for $|x| < r$ (default $r = 1/2$: Mitsuba's `box`).

    Sampled exactly (uniform offsets), so every weight is 1.

    **Arguments:**

    - `radius`: half-width, > 0. [px]

    !!! note "Thesis"
        Thesis section 2.3.2.

    ??? cite "References"
        `Pharr2023` §8.8.1.
    """

    radius: float = eqx.field(static=True)

    def __init__(self, radius: float = 0.5):
        self.radius = _check_param(radius, "radius")

    def evaluate_1d(self, x):
        return jnp.where(jnp.abs(x) < self.radius, 1.0 / (2.0 * self.radius), 0.0).astype(x.dtype)

    def _sample_1d(self, u):
        return (2.0 * u - 1.0) * self.radius, jnp.ones_like(u)

    def _pdf_1d(self, x):
        return self.evaluate_1d(x)


class TentFilter(_AbstractAnalyticFilter):
    r"""Tent (triangle) filter: $f_1(x) = (r - |x|)/r^2$ for $|x| < r$ (default $r = 1$).

    Mitsuba's `tent`.

    Sampled exactly by inverting its CDF, so every weight is 1.

    **Arguments:**

    - `radius`: half-width, > 0. [px]

    !!! note "Thesis"
        Thesis section 2.3.2.

    ??? cite "References"
        `Pharr2023` §8.8.2.
    """

    radius: float = eqx.field(static=True)

    def __init__(self, radius: float = 1.0):
        self.radius = _check_param(radius, "radius")

    def evaluate_1d(self, x):
        r = self.radius
        return jnp.maximum(r - jnp.abs(x), 0.0) / r**2

    def _sample_1d(self, u):
        # Inverse CDF of the tent: each half is a linear density.
        r = self.radius
        left = u < 0.5
        s = jnp.sqrt(jnp.where(left, 2.0 * u, 2.0 - 2.0 * u))
        x = jnp.where(left, -r + r * s, r - r * s)
        return x, jnp.ones_like(u)

    def _pdf_1d(self, x):
        return self.evaluate_1d(x)


class GaussianFilter(_AbstractAnalyticFilter):
    r"""Gaussian filter with the tail subtracted (Mitsuba 3's `gaussian`, as pbrt-v4's).

    $$f_1(x) \propto \max\!\left(0,\ e^{-x^2/(2\sigma^2)} - e^{-r^2/(2\sigma^2)}\right),
    \quad |x| < r,$$

    with $\sigma = 0.5$ px and $r = 4\sigma = 2$ px by default (the Cornell box film: stddev
    0.5, radius 2.0). Both Mitsuba 3 and pbrt-v4 subtract the value at the radius so that the
    filter reaches 0 continuously; Mitsuba fixes $r = 4\sigma$, here `radius` may be given.
    Sampled from the truncated Gaussian on $[-r, r]$ by the inverse error function; the
    per-axis weight $f_1/p_1 = \bigl(1 - e^{-(r^2 - x^2)/(2\sigma^2)}\bigr) Z_g / Z_f$ (ratio
    of the two normalisations, $1 + 1.1 \cdot 10^{-3}$ by default) stays within about
    $10^{-3}$ of 1 except close to the radius, where it falls to 0.

    **Arguments:**

    - `stddev`: standard deviation $\sigma$, > 0. [px]
    - `radius`: support half-width, > 0; `None` for $4\sigma$. [px]

    !!! note "Thesis"
        Thesis section 2.3.2.

    ??? cite "References"
        `Jakob2022` (`gaussian` rfilter); `Pharr2023` §8.8.3.
    """

    stddev: float = eqx.field(static=True)
    radius: float = eqx.field(static=True)
    _norm: float = eqx.field(static=True)  # integral of the unnormalised 1D profile
    _trunc: float = eqx.field(static=True)  # erf(r / (sigma sqrt 2))

    def __init__(self, stddev: float = 0.5, radius: float | None = None):
        self.stddev = _check_param(stddev, "stddev")
        self.radius = 4.0 * self.stddev if radius is None else _check_param(radius, "radius")
        s, r = self.stddev, self.radius
        self._trunc = math.erf(r / (s * math.sqrt(2.0)))
        bias = math.exp(-(r**2) / (2 * s**2))
        self._norm = s * math.sqrt(2 * math.pi) * self._trunc - 2 * r * bias

    def evaluate_1d(self, x):
        s, r = self.stddev, self.radius
        g = jnp.exp(-(x**2) / (2 * s**2)) - math.exp(-(r**2) / (2 * s**2))
        return jnp.where(jnp.abs(x) < r, jnp.maximum(g, 0.0), 0.0) / self._norm

    def _sample_1d(self, u):
        s = self.stddev
        x = s * math.sqrt(2.0) * jax.scipy.special.erfinv((2.0 * u - 1.0) * self._trunc)
        x = jnp.clip(x, -self.radius, self.radius)
        p = self._pdf_1d(x)
        w = self.evaluate_1d(x) / jnp.where(p > 0, p, 1.0)
        return x, jnp.where(p > 0, w, 0.0)

    def _pdf_1d(self, x):
        s, r = self.stddev, self.radius
        z = s * math.sqrt(2 * math.pi) * self._trunc
        return jnp.where(jnp.abs(x) <= r, jnp.exp(-(x**2) / (2 * s**2)) / z, 0.0)


class _AbstractTabulatedFilter(AbstractFilter):
    """A filter sampled from a tabulated 2D piecewise-constant density proportional to |f|."""

    _distribution: eqx.AbstractVar[PiecewiseConstant2D]

    @abc.abstractmethod
    def _profile_np(self, x: np.ndarray) -> np.ndarray:
        """Unnormalised 1D profile in NumPy (float64), used to build the table."""

    def _build(self) -> tuple[PiecewiseConstant2D, float]:
        """The sampling table (cell integrals of |f|) and the 1D normalisation integral."""
        r = self.radius
        n = max(16, int(math.ceil(_CELLS_PER_PIXEL * 2 * r)))
        edges = np.linspace(-r, r, n + 1)
        mass = _integrate_cells(lambda x: np.abs(self._profile_np(x)), edges)
        table = np.outer(mass, mass)  # |f_1(x) f_1(y)| is separable: products of 1D integrals
        dist = PiecewiseConstant2D(table / table.max(), bounds=((-r, r), (-r, r)))
        return dist, _integral(self._profile_np, r)

    def _table(self, dtype) -> PiecewiseConstant2D:
        # The table in the input's dtype (strict promotion; float32 renders under x64).
        return jax.tree.map(lambda a: a.astype(dtype), self._distribution)

    def sample(self, u):
        u = _uniforms(u)
        offset, p, _ = self._table(u.dtype).sample(u)
        f = self.evaluate(offset)
        ok = p > 0
        return offset, jnp.where(ok, f / jnp.where(ok, p, 1.0), 0.0)

    def pdf(self, offset):
        xy = _offsets(offset)
        return self._table(xy.dtype).pdf(xy)


class MitchellFilter(_AbstractTabulatedFilter):
    r"""Mitchell-Netravali cubic filter, $B = C = 1/3$ by default (Mitsuba's `mitchell`).

    $f_1(x) = \frac{2}{r} k\!\left(\frac{2x}{r}\right)$ with the cubic $k$ of Mitchell and
    Netravali on $[-2, 2]$, which integrates to 1 for every $B, C$; default radius 2 px.
    It has small negative lobes for $1 < |2x/r| < 2$: `sample` draws from a tabulated
    piecewise-constant density $\propto |f_1|$ and returns signed weights $f/p$.

    **Arguments:**

    - `B`, `C`: the cubic's parameters. [dimensionless]
    - `radius`: support half-width, > 0. [px]

    !!! note "Thesis"
        Thesis section 2.3.2, eq. 2.35.

    ??? cite "References"
        `Mitchell1988`; `Pharr2023` §8.8.4.
    """

    B: float = eqx.field(static=True)
    C: float = eqx.field(static=True)
    radius: float = eqx.field(static=True)
    _distribution: PiecewiseConstant2D
    _norm: float = eqx.field(static=True)

    def __init__(self, B: float = 1.0 / 3.0, C: float = 1.0 / 3.0, radius: float = 2.0):
        self.B = _check_param(B, "B", positive=False)
        self.C = _check_param(C, "C", positive=False)
        self.radius = _check_param(radius, "radius")
        self._distribution, self._norm = self._build()

    def _cubic(self, x, xp):
        B, C = self.B, self.C
        x = xp.abs(x)
        inner = ((12 - 9 * B - 6 * C) * x**3 + (-18 + 12 * B + 6 * C) * x**2 + (6 - 2 * B)) / 6
        outer = (
            (-B - 6 * C) * x**3
            + (6 * B + 30 * C) * x**2
            + (-12 * B - 48 * C) * x
            + (8 * B + 24 * C)
        ) / 6
        return xp.where(x < 1, inner, xp.where(x < 2, outer, 0.0))

    def _profile_np(self, x):
        return 2.0 / self.radius * self._cubic(2.0 * x / self.radius, np)

    def evaluate_1d(self, x):
        return 2.0 / self.radius * self._cubic(2.0 * x / self.radius, jnp) / self._norm


class LanczosFilter(_AbstractTabulatedFilter):
    r"""Lanczos windowed-sinc filter, $f_1(x) \propto \mathrm{sinc}(x)\,\mathrm{sinc}(x/\tau)$.

    Zero for $|x| \ge r$.

    $\mathrm{sinc}(x) = \sin(\pi x)/(\pi x)$; $\tau = 3$ lobes and $r = \tau$ by default
    (Mitsuba's `lanczos` with `lobes = 3`; pbrt-v4's `LanczosSincFilter` takes $r$ and $\tau$
    separately, as here). Normalised numerically to unit integral; sampled from a tabulated
    piecewise-constant density $\propto |f_1|$ with signed weights.

    **Arguments:**

    - `tau`: number of lobes of the window, > 0. [dimensionless]
    - `radius`: support half-width, > 0; `None` for `tau`. [px]

    !!! note "Thesis"
        Thesis section 2.3.2, eq. 2.35.

    ??? cite "References"
        `Duchon1979`; `Pharr2023` §8.8.5.
    """

    tau: float = eqx.field(static=True)
    radius: float = eqx.field(static=True)
    _distribution: PiecewiseConstant2D
    _norm: float = eqx.field(static=True)

    def __init__(self, tau: float = 3.0, radius: float | None = None):
        self.tau = _check_param(tau, "tau")
        self.radius = self.tau if radius is None else _check_param(radius, "radius")
        self._distribution, self._norm = self._build()

    def _profile_np(self, x):
        return np.where(np.abs(x) < self.radius, np.sinc(x) * np.sinc(x / self.tau), 0.0)

    def evaluate_1d(self, x):
        f = jnp.sinc(x) * jnp.sinc(x / self.tau)
        return jnp.where(jnp.abs(x) < self.radius, f, 0.0) / self._norm
