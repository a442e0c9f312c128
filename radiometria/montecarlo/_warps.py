"""Warps: maps from uniform variates `u` in [0, 1)^k to other distributions (thesis ch. 5-6).

Every warp comes as a pbrt-style triad (style.md section 3):

- `sample_X(u, ...)` maps uniform variates to a sample;
- `X_pdf(...)` is the density of that sample with respect to the stated measure;
- `invert_X_sample(x, ...)` maps a sample back to the variates that produce it, so that
  `invert_X_sample(sample_X(u)) == u` (up to round-off) and QMC points keep their structure
  through the warp.

The formulas follow `Pharr2023` (pbrt-v4, `util/sampling.h`, ch. A.5 and 2.2) unless stated.
Variates are checked to lie in [0, 1) with `equinox.error_if`; every `sample_X` takes a static
keyword `check=False` that skips the check for callers that validated their variates already
(checks at the entry point, not in the renderer's inner loop; the results are identical). Each
public warp is wrapped in `equinox.filter_jit`: called eagerly it compiles once per shape instead
of dispatching dozens of tiny operations, and inside a caller's `jit` it is simply inlined.
"""

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax import Array

from .._checks import as_float_array, check_last_axis, check_unit_interval
from .._math import disk_concentric_xy, dot, safe_div, safe_sqrt, sincos_pi
from .._types import Float, FloatLike
from ..constants import VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM

PI = math.pi
INV_PI = 1.0 / math.pi
INV_2PI = 0.5 / math.pi
INV_4PI = 0.25 / math.pi
PI_OVER_2 = 0.5 * math.pi
PI_OVER_4 = 0.25 * math.pi


def _u(u, k: int | None = None, name: str = "u", *, check: bool = True) -> Array:
    """`u` as a float array with `k` entries on its last axis; its values are checked to lie in
    [0, 1) (`eqx.error_if`) unless `check` is False. The shape check is static and always runs."""
    u = as_float_array(u, name)
    if k is not None:
        check_last_axis(u, name, k)
    return check_unit_interval(u, name) if check else u


def _atan2_0_2pi(y: Array, x: Array) -> Array:
    """Azimuth phi = atan2(y, x) wrapped to [0, 2 pi)."""
    phi = jnp.arctan2(y, x)
    phi = jnp.where(phi < 0, phi + 2 * PI, phi)
    return jnp.where(phi >= 2 * PI, 0.0, phi)


def _frac_to_unit(x: Array) -> Array:
    """Clamp an inverted variate into [0, 1) (round-off can land exactly on 1)."""
    one_minus_eps = 1.0 - jnp.finfo(x.dtype).epsneg
    return jnp.clip(x, 0.0, one_minus_eps)


# --------------------------------------------------------------------------------------------
# Disks
# --------------------------------------------------------------------------------------------


@eqx.filter_jit
def sample_uniform_disk_polar(u: FloatLike, *, check: bool = True) -> Float[Array, "*batch 2"]:
    r"""Uniform point on the unit disk by the polar map $r = \sqrt{u_0}$, $\phi = 2\pi u_1$.

    **Arguments:**

    - `u`: uniform variates, shape `(..., 2)`, in [0, 1). [dimensionless]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]

    **Returns:**

    Points `(..., 2)` on the unit disk; density `uniform_disk_pdf() = 1/pi` per unit area. [m]

    ??? cite "References"
        `Pharr2023` §A.5.1.
        Thesis ch. 5.
    """
    u = _u(u, 2, check=check)
    r = jnp.sqrt(u[..., 0])
    sin, cos = sincos_pi(2.0 * u[..., 1])  # theta = 2 pi u1
    return jnp.stack([r * cos, r * sin], axis=-1)


@eqx.filter_jit
def uniform_disk_pdf(p: FloatLike | None = None) -> Array:
    """Density of a uniform point on the unit disk: 1/pi inside, 0 outside.

    **Arguments:**

    - `p`: optional points `(..., 2)`; without them the constant 1/pi is returned. [m]

    **Returns:**

    Density per unit area. [m^-2]

    ??? cite "References"
        `Pharr2023` §A.5.1.
        Thesis ch. 5.
    """
    if p is None:
        return jnp.asarray(INV_PI)
    p = check_last_axis(as_float_array(p, "p"), "p", 2)
    inside = jnp.sum(p * p, axis=-1) <= 1.0
    return jnp.where(inside, INV_PI, 0.0).astype(p.dtype)


@eqx.filter_jit
def invert_uniform_disk_polar_sample(p: FloatLike) -> Float[Array, "*batch 2"]:
    """Invert `sample_uniform_disk_polar`: the variates `u` that give the disk point `p`.

    **Arguments:**

    - `p`: points on the unit disk, shape `(..., 2)`. [m]

    **Returns:**

    Variates `(..., 2)` in [0, 1). [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.5.1.
        Thesis ch. 5.
    """
    p = check_last_axis(as_float_array(p, "p"), "p", 2)
    r2 = jnp.sum(p * p, axis=-1)
    phi = _atan2_0_2pi(p[..., 1], p[..., 0])
    return _frac_to_unit(jnp.stack([r2, phi * INV_2PI], axis=-1))


@eqx.filter_jit
def sample_uniform_disk_concentric(u: FloatLike, *, check: bool = True) -> Float[Array, "*batch 2"]:
    """Uniform point on the unit disk by Shirley and Chiu's concentric map.

    The map takes concentric squares of [-1, 1]^2 to concentric circles, so it keeps the
    stratification of QMC points much better than the polar map.

    **Arguments:**

    - `u`: uniform variates, shape `(..., 2)`, in [0, 1). [dimensionless]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]

    **Returns:**

    Points `(..., 2)` on the unit disk, density 1/pi. [m]

    ??? cite "References"
        `Shirley1997`; `Pharr2023` §A.5.1.
        Thesis ch. 5.
    """
    u = _u(u, 2, check=check)
    return jnp.stack(disk_concentric_xy(u[..., 0], u[..., 1]), axis=-1)


@eqx.filter_jit
def invert_uniform_disk_concentric_sample(p: FloatLike) -> Float[Array, "*batch 2"]:
    """Invert `sample_uniform_disk_concentric`: disk point `p` -> variates `u`.

    **Arguments:**

    - `p`: points on the unit disk, shape `(..., 2)`. [m]

    **Returns:**

    Variates `(..., 2)` in [0, 1). [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.5.1 (`InvertUniformDiskConcentricSample`); `Shirley1997`.
        Thesis ch. 5.
    """
    p = check_last_axis(as_float_array(p, "p"), "p", 2)
    theta = jnp.arctan2(p[..., 1], p[..., 0])
    theta = jnp.where(theta < -PI_OVER_4, theta + 2 * PI, theta)
    r = jnp.sqrt(jnp.sum(p * p, axis=-1))
    # Four wedges: right (|y| < x), top, left, bottom.
    w0 = theta < PI_OVER_4
    w1 = (~w0) & (theta < 3 * PI_OVER_4)
    w2 = (~w0) & (~w1) & (theta < 5 * PI_OVER_4)
    a0, b0 = r, theta * r / PI_OVER_4
    b1 = r
    a1 = -(theta - PI_OVER_2) * b1 / PI_OVER_4
    a2 = -r
    b2 = (theta - PI) * a2 / PI_OVER_4
    b3 = -r
    a3 = -(theta - 3 * PI_OVER_2) * b3 / PI_OVER_4
    a = jnp.where(w0, a0, jnp.where(w1, a1, jnp.where(w2, a2, a3)))
    b = jnp.where(w0, b0, jnp.where(w1, b1, jnp.where(w2, b2, b3)))
    return _frac_to_unit(jnp.stack([(a + 1) / 2, (b + 1) / 2], axis=-1))


# --------------------------------------------------------------------------------------------
# Hemisphere, sphere, cone (local frame: normal on +z)
# --------------------------------------------------------------------------------------------


@eqx.filter_jit
def sample_cosine_hemisphere(u: FloatLike, *, check: bool = True) -> Float[Array, "*batch 3"]:
    r"""Cosine-weighted direction on the +z hemisphere (Malley's method).

    A concentric disk sample is lifted to the hemisphere, $z = \sqrt{1 - x^2 - y^2}$.

    **Arguments:**

    - `u`: uniform variates, shape `(..., 2)`, in [0, 1). [dimensionless]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]

    **Returns:**

    Unit directions `(..., 3)` with `z >= 0`; density `cos(theta)/pi` per steradian
    (`cosine_hemisphere_pdf`). [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.5.3; `Shirley1997`.
        Thesis ch. 5.
    """
    d = sample_uniform_disk_concentric(u, check=check)
    z = safe_sqrt(1.0 - d[..., 0] ** 2 - d[..., 1] ** 2)
    return jnp.concatenate([d, z[..., None]], axis=-1)


@eqx.filter_jit
def cosine_hemisphere_pdf(cos_theta: FloatLike) -> Array:
    r"""Density $p(\omega) = \cos\theta / \pi$ of `sample_cosine_hemisphere` (0 below the horizon).

    **Arguments:**

    - `cos_theta`: cosine of the angle to +z. [dimensionless]

    **Returns:**

    Density per steradian. [sr^-1]

    ??? cite "References"
        `Pharr2023` §A.5.3.
        Thesis ch. 5.
    """
    c = as_float_array(cos_theta, "cos_theta")
    return jnp.where(c > 0, c * INV_PI, 0.0).astype(c.dtype)


@eqx.filter_jit
def invert_cosine_hemisphere_sample(w: FloatLike) -> Float[Array, "*batch 2"]:
    """Invert `sample_cosine_hemisphere`: direction `w` -> variates `u`.

    **Arguments:**

    - `w`: unit directions `(..., 3)` on the +z hemisphere. [dimensionless]

    **Returns:**

    Variates `(..., 2)` in [0, 1). [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.5.3.
        Thesis ch. 5.
    """
    w = check_last_axis(as_float_array(w, "w"), "w", 3)
    return invert_uniform_disk_concentric_sample(w[..., :2])


@eqx.filter_jit
def sample_uniform_hemisphere(u: FloatLike, *, check: bool = True) -> Float[Array, "*batch 3"]:
    """Uniform direction on the +z hemisphere: `z = u0`, `phi = 2 pi u1`.

    **Arguments:**

    - `u`: uniform variates `(..., 2)` in [0, 1). [dimensionless]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]

    **Returns:**

    Unit directions `(..., 3)`, density `1/(2 pi)` per steradian. [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.5.2.
        Thesis ch. 5.
    """
    u = _u(u, 2, check=check)
    z = u[..., 0]
    r = safe_sqrt(1.0 - z * z)
    sin, cos = sincos_pi(2.0 * u[..., 1])  # phi = 2 pi u1
    return jnp.stack([r * cos, r * sin, z], axis=-1)


@eqx.filter_jit
def uniform_hemisphere_pdf(w: FloatLike | None = None) -> Array:
    """Density of `sample_uniform_hemisphere`: `1/(2 pi)` on the +z hemisphere.

    **Arguments:**

    - `w`: optional directions `(..., 3)`; without them the constant is returned. [dimensionless]

    **Returns:**

    Density per steradian (0 for `z < 0`). [sr^-1]

    ??? cite "References"
        `Pharr2023` §A.5.2.
        Thesis ch. 5.
    """
    if w is None:
        return jnp.asarray(INV_2PI)
    w = check_last_axis(as_float_array(w, "w"), "w", 3)
    return jnp.where(w[..., 2] >= 0, INV_2PI, 0.0).astype(w.dtype)


@eqx.filter_jit
def invert_uniform_hemisphere_sample(w: FloatLike) -> Float[Array, "*batch 2"]:
    """Invert `sample_uniform_hemisphere`: direction -> variates.

    **Arguments:**

    - `w`: unit directions `(..., 3)` with `z >= 0`. [dimensionless]

    **Returns:**

    Variates `(..., 2)` in [0, 1). [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.5.2.
        Thesis ch. 5.
    """
    w = check_last_axis(as_float_array(w, "w"), "w", 3)
    phi = _atan2_0_2pi(w[..., 1], w[..., 0])
    return _frac_to_unit(jnp.stack([w[..., 2], phi * INV_2PI], axis=-1))


@eqx.filter_jit
def sample_uniform_sphere(u: FloatLike, *, check: bool = True) -> Float[Array, "*batch 3"]:
    """Uniform direction on the unit sphere: `z = 1 - 2 u0`, `phi = 2 pi u1`.

    **Arguments:**

    - `u`: uniform variates `(..., 2)` in [0, 1). [dimensionless]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]

    **Returns:**

    Unit directions `(..., 3)`, density `1/(4 pi)` per steradian. [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.5.2.
        Thesis ch. 5.
    """
    u = _u(u, 2, check=check)
    z = 1.0 - 2.0 * u[..., 0]
    r = safe_sqrt(1.0 - z * z)
    sin, cos = sincos_pi(2.0 * u[..., 1])  # phi = 2 pi u1
    return jnp.stack([r * cos, r * sin, z], axis=-1)


@eqx.filter_jit
def uniform_sphere_pdf(w: FloatLike | None = None) -> Array:
    """Density of `sample_uniform_sphere`: the constant `1/(4 pi)`.

    **Arguments:**

    - `w`: optional directions `(..., 3)` to broadcast the constant over. [dimensionless]

    **Returns:**

    Density per steradian. [sr^-1]

    ??? cite "References"
        `Pharr2023` §A.5.2.
        Thesis ch. 5.
    """
    if w is None:
        return jnp.asarray(INV_4PI)
    w = check_last_axis(as_float_array(w, "w"), "w", 3)
    return jnp.full(w.shape[:-1], INV_4PI, dtype=w.dtype)


@eqx.filter_jit
def invert_uniform_sphere_sample(w: FloatLike) -> Float[Array, "*batch 2"]:
    """Invert `sample_uniform_sphere`: direction -> variates.

    **Arguments:**

    - `w`: unit directions `(..., 3)`. [dimensionless]

    **Returns:**

    Variates `(..., 2)` in [0, 1). [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.5.2.
        Thesis ch. 5.
    """
    w = check_last_axis(as_float_array(w, "w"), "w", 3)
    phi = _atan2_0_2pi(w[..., 1], w[..., 0])
    return _frac_to_unit(jnp.stack([(1.0 - w[..., 2]) / 2, phi * INV_2PI], axis=-1))


@eqx.filter_jit
def sample_uniform_cone(
    u: FloatLike,
    cos_theta_max: FloatLike,
    *,
    check: bool = True,
    one_minus_cos_theta_max: FloatLike | None = None,
) -> Float[Array, "*batch 3"]:
    r"""Uniform direction in the cone of half-angle $\theta_{max}$ around +z.

    $1 - \cos\theta = u_0 (1 - \cos\theta_{max})$, $\phi = 2\pi u_1$, and
    $\sin^2\theta = (1 - \cos\theta)(1 + \cos\theta)$ without cancellation, so narrow cones
    stay accurate in float32.

    **Arguments:**

    - `u`: uniform variates `(..., 2)` in [0, 1). [dimensionless]
    - `cos_theta_max`: cosine of the half-angle, in [-1, 1). [dimensionless]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]
    - `one_minus_cos_theta_max`: $1 - \cos\theta_{max}$ computed without cancellation
        (e.g. $\sin^2\theta_{max} / (1 + \cos\theta_{max})$ for the cone of a distant
        sphere), used instead of `1 - cos_theta_max`; in float32 that difference keeps only
        a few digits of a cone a few milliradians wide. [dimensionless]

    **Returns:**

    Unit directions `(..., 3)`, density `1/(2 pi (1 - cos_theta_max))`. [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.5.4.
        Thesis ch. 5.
    """
    u = _u(u, 2, check=check)
    if one_minus_cos_theta_max is None:
        omc = 1.0 - as_float_array(cos_theta_max, "cos_theta_max")
    else:
        omc = as_float_array(one_minus_cos_theta_max, "one_minus_cos_theta_max")
    v = u[..., 0] * omc  # 1 - cos theta
    sin_t = safe_sqrt(v * (2.0 - v))
    sin, cos = sincos_pi(2.0 * u[..., 1])  # phi = 2 pi u1
    return jnp.stack([sin_t * cos, sin_t * sin, 1.0 - v], axis=-1)


@eqx.filter_jit
def uniform_cone_pdf(cos_theta_max: FloatLike, w: FloatLike | None = None) -> Array:
    """Density of `sample_uniform_cone`: `1/(2 pi (1 - cos_theta_max))` inside the cone.

    **Arguments:**

    - `cos_theta_max`: cosine of the half-angle. [dimensionless]
    - `w`: optional directions `(..., 3)`; outside the cone the density is 0. [dimensionless]

    **Returns:**

    Density per steradian. [sr^-1]

    ??? cite "References"
        `Pharr2023` §A.5.4.
        Thesis ch. 5.
    """
    c = as_float_array(cos_theta_max, "cos_theta_max")
    pdf = 1.0 / (2 * PI * (1.0 - c))
    if w is None:
        return pdf
    w = check_last_axis(as_float_array(w, "w"), "w", 3)
    return jnp.where(w[..., 2] >= c, pdf, 0.0)


@eqx.filter_jit
def invert_uniform_cone_sample(w: FloatLike, cos_theta_max: FloatLike) -> Float[Array, "*batch 2"]:
    """Invert `sample_uniform_cone`: direction -> variates.

    **Arguments:**

    - `w`: unit directions `(..., 3)` inside the cone. [dimensionless]
    - `cos_theta_max`: cosine of the half-angle. [dimensionless]

    **Returns:**

    Variates `(..., 2)` in [0, 1). [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.5.4.
        Thesis ch. 5.
    """
    w = check_last_axis(as_float_array(w, "w"), "w", 3)
    c = as_float_array(cos_theta_max, "cos_theta_max")
    u0 = (1.0 - w[..., 2]) / (1.0 - c)
    phi = _atan2_0_2pi(w[..., 1], w[..., 0])
    return _frac_to_unit(jnp.stack([u0, phi * INV_2PI], axis=-1))


# --------------------------------------------------------------------------------------------
# Triangles
# --------------------------------------------------------------------------------------------


@eqx.filter_jit
def sample_uniform_triangle(u: FloatLike, *, check: bool = True) -> Float[Array, "*batch 3"]:
    """Uniform barycentric coordinates `(b0, b1, b2)` on a triangle (Heitz's low-distortion map).

    The point `b0 p0 + b1 p1 + b2 p2` is uniform over the triangle's area for any vertices.

    **Arguments:**

    - `u`: uniform variates `(..., 2)` in [0, 1). [dimensionless]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]

    **Returns:**

    Barycentrics `(..., 3)`, non-negative, summing to 1. Their density over `(b0, b1)` is 2
    (`uniform_triangle_pdf`); over the triangle it is 1/area. [dimensionless]

    ??? cite "References"
        `Heitz2019`; `Pharr2023` §A.5.5.
        Thesis ch. 5.
    """
    u = _u(u, 2, check=check)
    u0, u1 = u[..., 0], u[..., 1]
    first = u0 < u1
    b0 = jnp.where(first, u0 / 2, u0 - u1 / 2)
    b1 = jnp.where(first, u1 - u0 / 2, u1 / 2)
    return jnp.stack([b0, b1, 1.0 - b0 - b1], axis=-1)


@eqx.filter_jit
def uniform_triangle_pdf(b: FloatLike | None = None) -> Array:
    """Density of `sample_uniform_triangle` over the barycentric plane `(b0, b1)`: 2 inside.

    Divide by `2 * area` to get the density per unit area of a triangle of that area.

    **Arguments:**

    - `b`: optional barycentrics `(..., 2)` or `(..., 3)`; outside the simplex the density is 0.
        [dimensionless]

    **Returns:**

    Density with respect to `db0 db1`. [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.5.5.
        Thesis ch. 5.
    """
    if b is None:
        return jnp.asarray(2.0)
    b = as_float_array(b, "b")
    b0, b1 = b[..., 0], b[..., 1]
    inside = (b0 >= 0) & (b1 >= 0) & (b0 + b1 <= 1)
    return jnp.where(inside, 2.0, 0.0).astype(b.dtype)


@eqx.filter_jit
def invert_uniform_triangle_sample(b: FloatLike) -> Float[Array, "*batch 2"]:
    """Invert `sample_uniform_triangle`: barycentrics `(..., 2 or 3)` -> variates `(..., 2)`.

    **Arguments:**

    - `b`: barycentrics; only `b0` and `b1` are used. [dimensionless]

    **Returns:**

    Variates `(..., 2)` in [0, 1). [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.5.5.
        Thesis ch. 5.
    """
    b = as_float_array(b, "b")
    b0, b1 = b[..., 0], b[..., 1]
    first = b0 < b1
    u0 = jnp.where(first, 2 * b0, b0 + b1)
    u1 = jnp.where(first, b0 + b1, 2 * b1)
    return _frac_to_unit(jnp.stack([u0, u1], axis=-1))


def _normalize(v):
    n2 = dot(v, v)
    ok = n2 > 0
    return v / jnp.sqrt(jnp.where(ok, n2, 1.0))[..., None]


def _angle_between(v1, v2):
    """Numerically robust angle between unit vectors (pbrt's `AngleBetween`)."""
    d = dot(v1, v2)
    s = jnp.sqrt(dot(v1 + v2, v1 + v2)) / 2
    t = jnp.sqrt(dot(v2 - v1, v2 - v1)) / 2
    return jnp.where(
        d < 0, PI - 2 * jnp.arcsin(jnp.clip(s, -1, 1)), 2 * jnp.arcsin(jnp.clip(t, -1, 1))
    )


def _gram_schmidt(v, w):
    return v - dot(v, w)[..., None] * w


def _sph_tri_setup(a, b, c):
    n_ab = _normalize(jnp.cross(a, b))
    n_bc = _normalize(jnp.cross(b, c))
    n_ca = _normalize(jnp.cross(c, a))
    alpha = _angle_between(n_ab, -n_ca)
    beta = _angle_between(n_bc, -n_ab)
    gamma = _angle_between(n_ca, -n_bc)
    return n_ab, alpha, beta, gamma


def _vertices(a, b, c, *others):
    """Normalised vertices, broadcast (batch and all) against `others` (arrays `(..., k)`)."""
    a = check_last_axis(as_float_array(a, "a"), "a", 3)
    b = check_last_axis(as_float_array(b, "b"), "b", 3)
    c = check_last_axis(as_float_array(c, "c"), "c", 3)
    batch = np.broadcast_shapes(*(x.shape[:-1] for x in (a, b, c, *others)))
    a, b, c = (jnp.broadcast_to(x, batch + (3,)) for x in (a, b, c))
    others = tuple(jnp.broadcast_to(x, batch + x.shape[-1:]) for x in others)
    return (_normalize(a), _normalize(b), _normalize(c), *others)


@eqx.filter_jit
def spherical_triangle_area(a: FloatLike, b: FloatLike, c: FloatLike) -> Array:
    """Solid angle of the spherical triangle with vertex directions `a`, `b`, `c`.

    Girard's theorem: area = alpha + beta + gamma - pi.

    **Arguments:**

    - `a`, `b`, `c`: vertex directions `(..., 3)` (normalised here). [dimensionless]

    **Returns:**

    Solid angle. [sr]

    ??? cite "References"
        `Arvo1995`; `Pharr2023` §6.5.4.
        Thesis ch. 5.
    """
    a, b, c = _vertices(a, b, c)
    _, alpha, beta, gamma = _sph_tri_setup(a, b, c)
    return alpha + beta + gamma - PI


@eqx.filter_jit
def sample_spherical_triangle(
    u: FloatLike, a: FloatLike, b: FloatLike, c: FloatLike, *, check: bool = True
) -> Float[Array, "*batch 3"]:
    """Uniform direction inside the spherical triangle `(a, b, c)` (Arvo 1995).

    `u0` picks the area of a sub-triangle `(a, b, c')`, `u1` a point on the arc from `b` to `c'`.

    **Arguments:**

    - `u`: uniform variates `(..., 2)` in [0, 1). [dimensionless]
    - `a`, `b`, `c`: vertex directions `(..., 3)`, normalised here; seen from the origin.
        [dimensionless]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]

    **Returns:**

    Unit directions `(..., 3)`, density `spherical_triangle_pdf(a, b, c)` = 1/solid angle.
    [dimensionless]

    ??? cite "References"
        `Arvo1995`; `Pharr2023` §6.5.4 (`SampleSphericalTriangle`).
        Thesis ch. 5.
    """
    u = _u(u, 2, check=check)
    a, b, c, u = _vertices(a, b, c, u)
    _, alpha, beta, gamma = _sph_tri_setup(a, b, c)
    a_pi = alpha + beta + gamma
    ap_pi = PI + u[..., 0] * (a_pi - PI)  # area of the sub-triangle, plus pi
    cos_alpha, sin_alpha = jnp.cos(alpha), jnp.sin(alpha)
    sin_phi = jnp.sin(ap_pi) * cos_alpha - jnp.cos(ap_pi) * sin_alpha
    cos_phi = jnp.cos(ap_pi) * cos_alpha + jnp.sin(ap_pi) * sin_alpha
    k1 = cos_phi + cos_alpha
    k2 = sin_phi - sin_alpha * dot(a, b)
    num = k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha
    den = (k2 * sin_phi + k1 * cos_phi) * sin_alpha
    cos_bp = jnp.clip(safe_div(num, den), -1.0, 1.0)
    sin_bp = safe_sqrt(1.0 - cos_bp * cos_bp)
    cp = cos_bp[..., None] * a + sin_bp[..., None] * _normalize(_gram_schmidt(c, a))
    cos_t = 1.0 - u[..., 1] * (1.0 - dot(cp, b))
    sin_t = safe_sqrt(1.0 - cos_t * cos_t)
    return cos_t[..., None] * b + sin_t[..., None] * _normalize(_gram_schmidt(cp, b))


@eqx.filter_jit
def spherical_triangle_pdf(
    a: FloatLike, b: FloatLike, c: FloatLike, w: FloatLike | None = None
) -> Array:
    """Density of `sample_spherical_triangle`: 1/solid angle inside the triangle, 0 outside.

    **Arguments:**

    - `a`, `b`, `c`: vertex directions `(..., 3)`. [dimensionless]
    - `w`: optional directions `(..., 3)`; without them the constant is returned. [dimensionless]

    **Returns:**

    Density per steradian. [sr^-1]

    ??? cite "References"
        `Arvo1995`; `Pharr2023` §6.5.4.
        Thesis ch. 5.
    """
    if w is None:
        area = spherical_triangle_area(a, b, c)
        return jnp.where(area > 0, 1.0 / jnp.where(area > 0, area, 1.0), 0.0)
    w = check_last_axis(as_float_array(w, "w"), "w", 3)
    a, b, c, w = _vertices(a, b, c, w)
    area = spherical_triangle_area(a, b, c)
    pdf = jnp.where(area > 0, 1.0 / jnp.where(area > 0, area, 1.0), 0.0)
    orient = jnp.sign(dot(jnp.cross(a, b), c))
    inside = (
        (orient * dot(jnp.cross(a, b), w) >= 0)
        & (orient * dot(jnp.cross(b, c), w) >= 0)
        & (orient * dot(jnp.cross(c, a), w) >= 0)
    )
    return jnp.where(inside, pdf, 0.0)


@eqx.filter_jit
def invert_spherical_triangle_sample(
    w: FloatLike, a: FloatLike, b: FloatLike, c: FloatLike
) -> Float[Array, "*batch 2"]:
    """Invert `sample_spherical_triangle`: direction `w` inside `(a, b, c)` -> variates `u`.

    **Arguments:**

    - `w`: unit directions `(..., 3)` inside the triangle. [dimensionless]
    - `a`, `b`, `c`: vertex directions `(..., 3)`. [dimensionless]

    **Returns:**

    Variates `(..., 2)` in [0, 1). [dimensionless]

    ??? cite "References"
        `Pharr2023` §6.5.4 (`InvertSphericalTriangleSample`); `Arvo1995`.
        Thesis ch. 5.
    """
    w = check_last_axis(as_float_array(w, "w"), "w", 3)
    a, b, c, w = _vertices(a, b, c, w)
    w = _normalize(w)
    n_ab, alpha, beta, gamma = _sph_tri_setup(a, b, c)
    # c' is where the great circle through b and w meets the arc a-c.
    cp = _normalize(jnp.cross(jnp.cross(b, w), jnp.cross(c, a)))
    cp = jnp.where((dot(cp, a + c) < 0)[..., None], -cp, cp)
    n_cpb = _normalize(jnp.cross(cp, b))
    n_acp = _normalize(jnp.cross(a, cp))
    ap = alpha + _angle_between(n_ab, n_cpb) + _angle_between(n_acp, -n_cpb) - PI
    area = alpha + beta + gamma - PI
    near_a = dot(a, cp) > 0.99999847691  # c' within 0.1 degree of a: the sub-area is 0
    u0 = jnp.where(near_a, 0.0, safe_div(ap, area))
    u1 = safe_div(1.0 - dot(w, b), 1.0 - dot(cp, b))
    return _frac_to_unit(jnp.stack([u0, u1], axis=-1))


# --------------------------------------------------------------------------------------------
# 1D warps: linear, tent, exponential
# --------------------------------------------------------------------------------------------


@eqx.filter_jit
def sample_linear(u: FloatLike, a: FloatLike, b: FloatLike, *, check: bool = True) -> Array:
    r"""Sample $x \in [0, 1)$ with density proportional to the line $(1-x) a + x b$.

    **Arguments:**

    - `u`: uniform variates in [0, 1). [dimensionless]
    - `a`, `b`: non-negative values of the line at 0 and 1, not both 0. [dimensionless]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]

    **Returns:**

    Samples in [0, 1), density `linear_pdf(x, a, b)`. [dimensionless]

    ??? cite "References"
        `Pharr2023` §2.3.1 (`SampleLinear`).
        Thesis ch. 5.
    """
    u = _u(u, check=check)
    a = as_float_array(a, "a")
    b = as_float_array(b, "b")
    den = a + safe_sqrt((1.0 - u) * a * a + u * b * b)
    x = safe_div(u * (a + b), den)
    one_minus_eps = 1.0 - jnp.finfo(x.dtype).epsneg
    return jnp.minimum(x, one_minus_eps)


@eqx.filter_jit
def linear_pdf(x: FloatLike, a: FloatLike, b: FloatLike) -> Array:
    """Density `2 ((1-x) a + x b) / (a + b)` on [0, 1] of `sample_linear` (0 outside).

    **Arguments:**

    - `x`: points. [dimensionless]
    - `a`, `b`: values of the line at 0 and 1. [dimensionless]

    **Returns:**

    Density with respect to `dx`. [dimensionless]

    ??? cite "References"
        `Pharr2023` §2.3.1.
        Thesis ch. 5.
    """
    x = as_float_array(x, "x")
    a = as_float_array(a, "a")
    b = as_float_array(b, "b")
    inside = (x >= 0) & (x <= 1)
    return jnp.where(inside, 2 * ((1 - x) * a + x * b) / (a + b), 0.0)


@eqx.filter_jit
def invert_linear_sample(x: FloatLike, a: FloatLike, b: FloatLike) -> Array:
    """Invert `sample_linear`: `u = x (a (2 - x) + b x) / (a + b)`.

    **Arguments:**

    - `x`: samples in [0, 1]. [dimensionless]
    - `a`, `b`: values of the line at 0 and 1. [dimensionless]

    **Returns:**

    Variates in [0, 1). [dimensionless]

    ??? cite "References"
        `Pharr2023` §2.3.1.
        Thesis ch. 5.
    """
    x = as_float_array(x, "x")
    a = as_float_array(a, "a")
    b = as_float_array(b, "b")
    return _frac_to_unit(x * (a * (2 - x) + b * x) / (a + b))


@eqx.filter_jit
def sample_tent(u: FloatLike, radius: FloatLike, *, check: bool = True) -> Array:
    """Sample the tent (triangle) density of half-width `radius` centred at 0.

    The first half of [0, 1) samples the left half of the tent, the second half the right.

    **Arguments:**

    - `u`: uniform variates in [0, 1). [dimensionless]
    - `radius`: half-width r > 0. [same unit as the result]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]

    **Returns:**

    Samples in (-r, r), density `tent_pdf(x, r)`. [same unit as `radius`]

    ??? cite "References"
        `Pharr2023` §2.3.1 (`SampleTent`).
        Thesis ch. 5 and eq. 2.31.
    """
    u = _u(u, check=check)
    r = as_float_array(radius, "radius")
    left = u < 0.5
    u_left = jnp.minimum(2 * u, 1.0 - jnp.finfo(u.dtype).epsneg)
    u_right = jnp.clip(2 * u - 1.0, 0.0, 1.0 - jnp.finfo(u.dtype).epsneg)
    x_left = -r + r * sample_linear(jnp.where(left, u_left, 0.0), 0.0, 1.0, check=False)
    x_right = r * sample_linear(jnp.where(left, 0.0, u_right), 1.0, 0.0, check=False)
    return jnp.where(left, x_left, x_right)


@eqx.filter_jit
def tent_pdf(x: FloatLike, radius: FloatLike) -> Array:
    """Density `1/r - |x|/r^2` of the tent of half-width `r` (0 for `|x| >= r`).

    **Arguments:**

    - `x`: points. [same unit as `radius`]
    - `radius`: half-width r > 0. [length or any unit]

    **Returns:**

    Density with respect to `dx`. [1/unit of x]

    ??? cite "References"
        `Pharr2023` §2.3.1.
        Thesis ch. 5.
    """
    x = as_float_array(x, "x")
    r = as_float_array(radius, "radius")
    return jnp.where(jnp.abs(x) < r, 1 / r - jnp.abs(x) / (r * r), 0.0)


@eqx.filter_jit
def invert_tent_sample(x: FloatLike, radius: FloatLike) -> Array:
    """Invert `sample_tent`: sample `x` in (-r, r) -> variate `u`.

    **Arguments:**

    - `x`: samples. [same unit as `radius`]
    - `radius`: half-width r > 0. [length or any unit]

    **Returns:**

    Variates in [0, 1). [dimensionless]

    ??? cite "References"
        `Pharr2023` §2.3.1 (`InvertTentSample`).
        Thesis ch. 5.
    """
    x = as_float_array(x, "x")
    r = as_float_array(radius, "radius")
    left = x <= 0
    u_left = (1.0 - invert_linear_sample(jnp.where(left, -x / r, 0.0), 1.0, 0.0)) / 2
    u_right = 0.5 + invert_linear_sample(jnp.where(left, 0.0, x / r), 1.0, 0.0) / 2
    return _frac_to_unit(jnp.where(left, u_left, u_right))


@eqx.filter_jit
def sample_exponential(u: FloatLike, a: FloatLike, *, check: bool = True) -> Array:
    """Sample the exponential density `a exp(-a x)` on [0, inf): `x = -log(1 - u) / a`.

    **Arguments:**

    - `u`: uniform variates in [0, 1). [dimensionless]
    - `a`: rate, > 0. [1/unit of x, e.g. m^-1 for free-flight distances]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]

    **Returns:**

    Samples >= 0. [1/unit of `a`]

    ??? cite "References"
        `Pharr2023` §A.4.2 (`SampleExponential`).
        Thesis ch. 5.
    """
    u = _u(u, check=check)
    a = as_float_array(a, "a")
    return -jnp.log1p(-u) / a


@eqx.filter_jit
def exponential_pdf(x: FloatLike, a: FloatLike) -> Array:
    """Density `a exp(-a x)` of `sample_exponential` (0 for `x < 0`).

    **Arguments:**

    - `x`: points. [unit of 1/a]
    - `a`: rate, > 0. [1/unit of x]

    **Returns:**

    Density with respect to `dx`. [1/unit of x]

    ??? cite "References"
        `Pharr2023` §A.4.2.
        Thesis ch. 5.
    """
    x = as_float_array(x, "x")
    a = as_float_array(a, "a")
    return jnp.where(x >= 0, a * jnp.exp(-a * jnp.maximum(x, 0.0)), 0.0)


@eqx.filter_jit
def invert_exponential_sample(x: FloatLike, a: FloatLike) -> Array:
    """Invert `sample_exponential`: `u = 1 - exp(-a x)`.

    **Arguments:**

    - `x`: samples >= 0. [unit of 1/a]
    - `a`: rate, > 0. [1/unit of x]

    **Returns:**

    Variates in [0, 1). [dimensionless]

    ??? cite "References"
        `Pharr2023` §A.4.2.
        Thesis ch. 5.
    """
    x = as_float_array(x, "x")
    a = as_float_array(a, "a")
    return _frac_to_unit(-jnp.expm1(-a * x))


# --------------------------------------------------------------------------------------------
# Visible wavelengths (pbrt-v4 SampleVisibleWavelengths)
# --------------------------------------------------------------------------------------------

_VIS_K = 0.0072  # nm^-1, pbrt-v4: p(lambda) ~ 1 / cosh^2(0.0072 (lambda - 538))
_VIS_MU = 538.0  # nm
# Derived rather than retyped: tanh at the range ends, and the normalisation so that the pdf
# integrates to exactly 1 over [360, 830] nm. pbrt-v4 rounds these to 0.85691062, 1.82750197
# and 0.0039398042 (relative differences below 1e-7).
_VIS_T0 = math.tanh(_VIS_K * (_VIS_MU - VISIBLE_WAVELENGTH_MIN_NM))  # 0.85691062...
_VIS_T1 = math.tanh(_VIS_K * (VISIBLE_WAVELENGTH_MAX_NM - _VIS_MU))
_VIS_NORM = _VIS_K / (_VIS_T0 + _VIS_T1)  # 0.0039398042... nm^-1


@eqx.filter_jit
def sample_visible_wavelengths(u: FloatLike, *, check: bool = True) -> Array:
    r"""Sample wavelengths in [360, 830] nm with pbrt-v4's visible-light density.

    $\lambda = 538 - \operatorname{atanh}(0.85691062 - 1.82750197 u)/0.0072$, the inverse CDF
    of $p(\lambda) \propto 1/\cosh^2(0.0072(\lambda - 538))$, which follows the luminous
    efficiency curve closely (thesis 2.1).

    **Arguments:**

    - `u`: uniform variates in [0, 1). [dimensionless]
    - `check`: validate `u` in [0, 1) with `eqx.error_if` (default); `False` skips it for
        callers that validated already, such as the renderer's inner loop. [bool]

    **Returns:**

    Wavelengths in [360, 830]. [nm]

    ??? cite "References"
        `Pharr2023` §4.6.2 (`SampleVisibleWavelengths`); `Radziszewski2009`.
        Thesis ch. 5.
    """
    u = _u(u, check=check)
    return _visible_wavelength(_VIS_T0 - (_VIS_T0 + _VIS_T1) * u)


def _visible_wavelength(t: Array) -> Array:
    r"""$538 - \operatorname{atanh}(t)/0.0072$ clipped to [360, 830] nm, with
    $\operatorname{atanh} t = \tfrac12 \log\frac{1 + t}{1 - t}$: one logarithm, which
    XLA:CPU vectorises, where its `atanh` takes two `log1p` (measured in a render step:
    8 ns per wavelength against about 2)."""
    lam = _VIS_MU - 0.5 * jnp.log((1.0 + t) / (1.0 - t)) / _VIS_K
    return jnp.clip(lam, VISIBLE_WAVELENGTH_MIN_NM, VISIBLE_WAVELENGTH_MAX_NM)


@eqx.filter_jit
def sample_visible_wavelengths_with_pdf(u: FloatLike, *, check: bool = True) -> tuple[Array, Array]:
    r"""`sample_visible_wavelengths` and the density of its samples, from one inversion.

    With $t = 0.85691062 - 1.82750197\,u$ the sample is
    $\lambda = 538 - \operatorname{atanh}(t)/0.0072$, and since
    $\cosh^{-2}(\operatorname{atanh} t) = 1 - t^2$ its density is
    $0.0039398\,(1 - t^2)$: no hyperbolic cosine to evaluate (the renderer draws four
    wavelengths for every path).

    **Arguments:**

    - `u`: uniform variates in [0, 1). [dimensionless]
    - `check`: validate `u` as `sample_visible_wavelengths` does. [bool]

    **Returns:**

    `(wavelength_nm, pdf)`, each of `u`'s shape: the wavelengths, in 360-830 nm [nm], and
    `visible_wavelengths_pdf` at them [nm^-1].

    ??? cite "References"
        `Pharr2023` §4.6.2 (`SampleVisibleWavelengths`, `VisibleWavelengthsPDF`).
        Thesis ch. 5.
    """
    u = _u(u, check=check)
    t = _VIS_T0 - (_VIS_T0 + _VIS_T1) * u
    return _visible_wavelength(t), _VIS_NORM * (1.0 - t * t)


@eqx.filter_jit
def visible_wavelengths_pdf(wavelength_nm: FloatLike) -> Array:
    r"""Density of `sample_visible_wavelengths`: $0.0039398 / \cosh^2(0.0072(\lambda - 538))$.

    **Arguments:**

    - `wavelength_nm`: wavelengths. [nm]

    **Returns:**

    Density per nanometre; 0 outside [360, 830] nm. [nm^-1]

    ??? cite "References"
        `Pharr2023` §4.6.2 (`VisibleWavelengthsPDF`).
        Thesis ch. 5.
    """
    lam = as_float_array(wavelength_nm, "wavelength_nm")
    inside = (lam >= VISIBLE_WAVELENGTH_MIN_NM) & (lam <= VISIBLE_WAVELENGTH_MAX_NM)
    return jnp.where(inside, _VIS_NORM / jnp.cosh(_VIS_K * (lam - _VIS_MU)) ** 2, 0.0)


@eqx.filter_jit
def invert_visible_wavelengths_sample(wavelength_nm: FloatLike) -> Array:
    """Invert `sample_visible_wavelengths`: wavelength -> variate (its CDF).

    **Arguments:**

    - `wavelength_nm`: wavelengths in [360, 830]. [nm]

    **Returns:**

    Variates in [0, 1). [dimensionless]

    ??? cite "References"
        `Pharr2023` §4.6.2.
        Thesis ch. 5.
    """
    lam = as_float_array(wavelength_nm, "wavelength_nm")
    return _frac_to_unit((_VIS_T0 - jnp.tanh(_VIS_K * (_VIS_MU - lam))) / (_VIS_T0 + _VIS_T1))
