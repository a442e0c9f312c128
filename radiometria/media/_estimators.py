r"""Free-flight sampling and transmittance estimators (thesis ch. 4; `Novak2018`).

Along a ray $\mathbf x(t) = \mathbf o + t\boldsymbol\omega$ through a medium of extinction
$\sigma_t(\mathbf x)$, the transmittance of the segment $(0, d)$ is $T = e^{-\tau}$,
$\tau = \int_0^d\sigma_t(\mathbf x(t))\,\mathrm dt$ (thesis eq. 1.12 with extinction in place of
absorption), and the free-flight distance to the first interaction has density
$p(t) = \sigma_t(\mathbf x(t))\,e^{-\tau(t)}$, with the remaining probability $T$ of no
interaction before $d$.

- **Homogeneous** media have closed forms: $t = -\ln(1 - u)/\sigma_t$ and $T = e^{-\sigma_t d}$
  (`sample_homogeneous_free_flight`, `homogeneous_free_flight_pdf`, `homogeneous_transmittance`).
- **Heterogeneous** media are handled with a *majorant* $\bar\mu \ge \sigma_t$ on the segment:
  tentative collisions are drawn from the homogeneous process of rate $\bar\mu$, and at each
  one the real extinction decides what happens (`Woodcock1965`; `Novak2014`).
    - *Delta tracking* (`delta_tracking`) accepts a tentative collision as real with
      probability $\sigma_t/\bar\mu$; the first real collision is an exact sample of $p(t)$,
      and $1 - [\text{collided}]$ is an unbiased (binary, "track-length") estimate of $T$
      (`delta_tracking_transmittance`). It needs $\bar\mu \ge \sigma_t$ everywhere.
    - *Ratio tracking* (`ratio_tracking_transmittance`) walks through every tentative collision
      to the end of the segment and multiplies the weights $1 - \sigma_t/\bar\mu$.
    - *Residual ratio tracking* (`residual_ratio_tracking_transmittance`) splits
      $\sigma_t = \sigma_c + \sigma_r$ into a constant control $\sigma_c$, whose
      transmittance $e^{-\sigma_c d}$ is exact, and a residual tracked with rate $\bar\mu_r$:
      $\hat T = e^{-\sigma_c d}\prod_i (1 - (\sigma_t(\mathbf x_i) - \sigma_c)/\bar\mu_r)$.

  Both ratio estimators are unbiased for *any* positive rate (for a Poisson process of rate
  $\lambda$ on $(0, d)$, $E\prod_i(1 - f(t_i)/\lambda) = e^{-\int_0^d f}$); a rate that bounds
  $|\sigma_t - \sigma_c|$ keeps the weights in [0, 1] and the variance low.

Loops. Every estimator runs a `lax.while_loop` over the whole batch of rays until *every* ray
has left its segment (or collided, for delta tracking), so no step cap truncates a walk and
nothing is biased by one: the number of steps is Poisson with mean $\bar\mu d$, finite with
probability 1. Segments must therefore be finite. A ray whose distance becomes NaN stops
(its result is then NaN or its last weight). The $i$-th step of every ray draws its variates
from `jax.random.fold_in(key, i)`, so the same key gives the same result. The loops are not
reverse-mode differentiable (`lax.while_loop`); differentiate the closed forms or
`optical_depth_along_ray` instead.

The extinction field is a JAX callable `sigma_t_fn(points (..., 3)) -> (...)` [m^-1]; for
spectral media call the estimators per wavelength, or with a wavelength-independent density
scaled per wavelength.
"""

import math
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, Bool, Float, Int

from .._checks import (
    as_float_array,
    check_in_range,
    check_last_axis,
    check_unit_interval,
)
from .._math import align_ranks
from .._types import FloatLike, Key
from ._coefficients import optical_depth


class FreeFlightSample(eqx.Module):
    """The outcome of `delta_tracking` for a batch of rays.

    **Fields:**

    - `t`: distance to the first real collision, or `t_max` where the ray left its segment
        without one `(n,)`. [m]
    - `collided`: True where a real collision happened before `t_max` `(n,)`.
    - `n_steps`: tentative (majorant) collisions drawn for each ray, a cost measure `(n,)`.

    ??? cite "References"
        `Woodcock1965`; `Novak2018` §4.1.
    """

    t: Float[Array, " n"]
    collided: Bool[Array, " n"]
    n_steps: Int[Array, " n"]


def sample_homogeneous_free_flight(sigma_t: FloatLike, u: FloatLike) -> Float[Array, "..."]:
    r"""Free-flight distance in a homogeneous medium, $t = -\ln(1 - u)/\sigma_t$.

    **Arguments:**

    - `sigma_t`: extinction coefficient, >= 0. [m^-1]
    - `u`: uniform variates in [0, 1). [dimensionless]

    **Returns:**

    Distances $t \ge 0$ with density `homogeneous_free_flight_pdf`; infinite where
    $\sigma_t = 0$ (no interaction ever). [m]

    !!! note "Thesis"
        Eq. (1.12), section 1.3 (the exponential attenuation sampled here); chapter 4.

    ??? cite "References"
        `Pharr2023` §11.2.2 (eq. 11.10); `Novak2018` §3.
    """
    s = check_in_range(as_float_array(sigma_t, "sigma_t"), "sigma_t", 0.0, math.inf, unit="m^-1")
    u = check_unit_interval(as_float_array(u, "u"))
    s, u = align_ranks(s, u)
    pos = s > 0
    return jnp.where(pos, -jnp.log1p(-u) / jnp.where(pos, s, 1.0), jnp.inf)


def homogeneous_free_flight_pdf(t: FloatLike, sigma_t: FloatLike) -> Float[Array, "..."]:
    r"""Density $p(t) = \sigma_t e^{-\sigma_t t}$ of `sample_homogeneous_free_flight`
    (0 for $t < 0$).

    **Arguments:**

    - `t`: distances. [m]
    - `sigma_t`: extinction coefficient, >= 0. [m^-1]

    **Returns:**

    Density per unit length. [m^-1]

    !!! note "Thesis"
        Eq. (1.12), section 1.3; chapter 4.

    ??? cite "References"
        `Pharr2023` §11.2.2.
    """
    t = as_float_array(t, "t")
    s = check_in_range(as_float_array(sigma_t, "sigma_t"), "sigma_t", 0.0, math.inf, unit="m^-1")
    t, s = align_ranks(t, s)
    inside = t >= 0
    return jnp.where(inside, s * jnp.exp(-s * jnp.where(inside, t, 0.0)), 0.0)


def homogeneous_transmittance(sigma_t: FloatLike, distance: FloatLike) -> Float[Array, "..."]:
    r"""Transmittance of a homogeneous segment, $T = e^{-\sigma_t d}$ (Beer-Lambert).

    **Arguments:**

    - `sigma_t`: extinction coefficient, >= 0. [m^-1]
    - `distance`: segment length, >= 0, may be infinite. [m]

    **Returns:**

    $T \in [0, 1]$; 1 in a vacuum even over an infinite distance. [dimensionless] With
    $\sigma_t = \kappa_a$ this is `radiometry.beer_lambert_transmittance`.

    !!! note "Thesis"
        Eq. (1.12), section 1.3.

    ??? cite "References"
        `Pharr2023` §11.2 (eq. 11.6).
    """
    return jnp.exp(-optical_depth(sigma_t, distance))


def _rays(origins, directions, t_max):
    o = check_last_axis(as_float_array(origins, "origins"), "origins", 3)
    w = check_last_axis(as_float_array(directions, "directions"), "directions", 3)
    d = as_float_array(t_max, "t_max")
    d = check_in_range(d, "t_max", 0.0, math.inf, unit="m", closed_upper=False)
    if o.ndim != 2 or w.shape != o.shape or d.shape != o.shape[:1]:
        raise ValueError(
            f"`origins` and `directions` must be (n, 3) and `t_max` (n,); got "
            f"{o.shape}, {w.shape} and {d.shape}."
        )
    return o, w, d


def _rate(x, name: str, n: int, dtype) -> Array:
    r = check_in_range(as_float_array(x, name), name, 0.0, math.inf, unit="m^-1")
    r = check_in_range(r, name, -math.inf, math.inf, closed_lower=False, closed_upper=False)
    if r.ndim > 1 or (r.ndim == 1 and r.shape[0] != n):
        raise ValueError(f"`{name}` must be a scalar or have shape ({n},), got {r.shape}.")
    return jnp.broadcast_to(r, (n,)).astype(dtype)


def _track(sigma_t_fn, o, w, d, rate, control, key, mode: str):
    """The shared walk through the tentative collisions of rate `rate` on (0, d).

    mode "delta": stop at the first accepted collision (u1 rate < sigma_t).
    mode "ratio": multiply the weight by 1 - (sigma_t - control) / rate at every collision.
    """
    n = d.shape[0]
    dtype = jnp.result_type(o, w, d)

    def cond(state):
        return jnp.any(~state[2])

    def body(state):
        i, t, done, collided, weight, steps = state
        u = jax.random.uniform(jax.random.fold_in(key, i), (n, 2), dtype=dtype)
        pos = rate > 0
        step = jnp.where(pos, -jnp.log1p(-u[:, 0]) / jnp.where(pos, rate, 1.0), jnp.inf)
        t_new = t + step
        active = ~done
        left = (t_new >= d) | ~jnp.isfinite(t_new)
        hit = active & ~left
        x = o + jnp.where(hit, t_new, 0.0)[:, None] * w
        sig = jnp.asarray(sigma_t_fn(x)).astype(dtype)
        if mode == "delta":
            real = hit & (u[:, 1] * rate < sig)
            collided = collided | real
            done = done | left | real
        else:
            ratio = 1.0 - (sig - control) / jnp.where(pos, rate, 1.0)
            weight = jnp.where(hit, weight * ratio, weight)
            done = done | left
        t = jnp.where(hit, t_new, jnp.where(active, d, t))
        steps = steps + hit.astype(steps.dtype)
        return i + 1, t, done, collided, weight, steps

    init = (
        jnp.asarray(0, jnp.uint32),
        jnp.zeros((n,), dtype),
        d <= 0,
        jnp.zeros((n,), bool),
        jnp.ones((n,), dtype),
        jnp.zeros((n,), jnp.int32),
    )
    _, t, _, collided, weight, steps = lax.while_loop(cond, body, init)
    if mode == "delta":
        t = jnp.where(collided, t, d)
    return t, collided, weight, steps


def delta_tracking(
    sigma_t_fn: Callable[[Array], Array],
    origins: Float[Array, "n 3"],
    directions: Float[Array, "n 3"],
    t_max: Float[Array, " n"],
    majorant: FloatLike,
    *,
    key: Key,
) -> FreeFlightSample:
    r"""Delta (Woodcock) tracking: sample the first real collision along each segment.

    Tentative collisions are drawn at rate $\bar\mu$; one at $\mathbf x_i$ is real with
    probability $\sigma_t(\mathbf x_i)/\bar\mu$ and otherwise a *null* collision that leaves
    the ray unchanged. The accepted distance has exactly the density
    $\sigma_t(\mathbf x(t))e^{-\tau(t)}$ on $(0, t_{max})$, and no collision happens with
    probability $T = e^{-\tau(t_{max})}$: the estimator is unbiased as long as the majorant
    bounds the extinction on the segment, $\bar\mu \ge \sigma_t$ (a smaller one
    under-samples the dense parts, and this is not checked).

    **Arguments:**

    - `sigma_t_fn`: the extinction field, a JAX callable from points `(n, 3)` to `(n,)`.
        [m^-1]
    - `origins`: ray origins `(n, 3)`. [m]
    - `directions`: unit ray directions `(n, 3)`. [dimensionless]
    - `t_max`: segment lengths `(n,)`, >= 0 and finite. [m]
    - `majorant`: $\bar\mu \ge \sigma_t$ on each segment, a scalar or `(n,)`, >= 0 and
        finite. [m^-1]
    - `key`: a `jax.random` key (keyword-only); step $i$ uses `fold_in(key, i)`.

    **Returns:**

    A `FreeFlightSample` (`t`, `collided`, `n_steps`).

    !!! note "Thesis"
        Chapter 4 (energy transport in a medium; title only in the text); eq. (1.12).

    ??? cite "References"
        `Woodcock1965`; `Novak2018` §4.1; `Pharr2023` §11.2.3 (`SampleT_maj`).
    """
    o, w, d = _rays(origins, directions, t_max)
    rate = _rate(majorant, "majorant", d.shape[0], d.dtype)
    t, collided, _, steps = _track(sigma_t_fn, o, w, d, rate, 0.0, key, "delta")
    return FreeFlightSample(t=t, collided=collided, n_steps=steps)


def delta_tracking_transmittance(
    sigma_t_fn: Callable[[Array], Array],
    origins: Float[Array, "n 3"],
    directions: Float[Array, "n 3"],
    t_max: Float[Array, " n"],
    majorant: FloatLike,
    *,
    key: Key,
) -> Float[Array, " n"]:
    r"""Track-length transmittance estimate $\hat T = 1 - [\text{delta tracking collided}]$.

    Binary (0 or 1) and unbiased, $E\hat T = e^{-\tau}$, with variance $T(1 - T)$. Arguments
    as in `delta_tracking`.

    **Returns:**

    $\hat T$ `(n,)` in {0, 1}. [dimensionless]

    !!! note "Thesis"
        Eq. (1.12), section 1.3; chapter 4 (title only in the text).

    ??? cite "References"
        `Woodcock1965`; `Novak2014` §3; `Novak2018` §5.1.
    """
    s = delta_tracking(sigma_t_fn, origins, directions, t_max, majorant, key=key)
    return jnp.where(s.collided, 0.0, 1.0).astype(s.t.dtype)


def ratio_tracking_transmittance(
    sigma_t_fn: Callable[[Array], Array],
    origins: Float[Array, "n 3"],
    directions: Float[Array, "n 3"],
    t_max: Float[Array, " n"],
    majorant: FloatLike,
    *,
    key: Key,
) -> Float[Array, " n"]:
    r"""Ratio tracking: $\hat T = \prod_i \bigl(1 - \sigma_t(\mathbf x_i)/\bar\mu\bigr)$ over
    the tentative collisions $\mathbf x_i$ of rate $\bar\mu$ on the whole segment.

    Unbiased for any $\bar\mu > 0$; with $\bar\mu \ge \sigma_t$ every factor lies in [0, 1].

    **Arguments:**

    - `sigma_t_fn`: the extinction field, a JAX callable from points `(n, 3)` to `(n,)`.
        [m^-1]
    - `origins`, `directions`, `t_max`: the segments, as in `delta_tracking`. [m, 1, m]
    - `majorant`: the tracking rate $\bar\mu$, scalar or `(n,)`, >= 0 and finite. [m^-1]
    - `key`: a `jax.random` key (keyword-only).

    **Returns:**

    $\hat T$ `(n,)`, with $E\hat T = e^{-\tau}$. [dimensionless]

    !!! note "Thesis"
        Eq. (1.12), section 1.3; chapter 4 (title only in the text).

    ??? cite "References"
        `Novak2014` §3 (ratio tracking); `Novak2018` §5.2; `Pharr2023` §14.2.
    """
    o, w, d = _rays(origins, directions, t_max)
    rate = _rate(majorant, "majorant", d.shape[0], d.dtype)
    _, _, weight, _ = _track(sigma_t_fn, o, w, d, rate, 0.0, key, "ratio")
    return weight


def residual_ratio_tracking_transmittance(
    sigma_t_fn: Callable[[Array], Array],
    origins: Float[Array, "n 3"],
    directions: Float[Array, "n 3"],
    t_max: Float[Array, " n"],
    control: FloatLike,
    residual_majorant: FloatLike,
    *,
    key: Key,
) -> Float[Array, " n"]:
    r"""Residual ratio tracking (Novák et al. 2014): a constant control extinction
    $\sigma_c$ is attenuated in closed form and only the residual is tracked,

    $$\hat T = e^{-\sigma_c d}\prod_i\left(1 - \frac{\sigma_t(\mathbf x_i) - \sigma_c}
    {\bar\mu_r}\right),$$

    with tentative collisions $\mathbf x_i$ of rate $\bar\mu_r$. Unbiased for any
    $\bar\mu_r > 0$; with $\bar\mu_r \ge |\sigma_t - \sigma_c|$ the factors lie in [0, 2],
    and a control near the mean extinction (e.g. the segment's minimum or average) makes
    the walk short and the variance small.

    **Arguments:**

    - `sigma_t_fn`, `origins`, `directions`, `t_max`, `key`: as in `ratio_tracking_transmittance`.
    - `control`: control extinction $\sigma_c$, scalar or `(n,)`, >= 0 and finite. [m^-1]
    - `residual_majorant`: tracking rate $\bar\mu_r$, scalar or `(n,)`, >= 0 and finite.
        [m^-1]

    **Returns:**

    $\hat T$ `(n,)`, with $E\hat T = e^{-\tau}$. [dimensionless]

    !!! note "Thesis"
        Eq. (1.12), section 1.3; chapter 4 (title only in the text).

    ??? cite "References"
        `Novak2014` §4 (residual ratio tracking); `Novak2018` §5.3.
    """
    o, w, d = _rays(origins, directions, t_max)
    n = d.shape[0]
    rate = _rate(residual_majorant, "residual_majorant", n, d.dtype)
    sc = _rate(control, "control", n, d.dtype)
    _, _, weight, _ = _track(sigma_t_fn, o, w, d, rate, sc, key, "ratio")
    return jnp.exp(-sc * d) * weight
