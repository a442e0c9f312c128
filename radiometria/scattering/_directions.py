r"""Directions: reflection, refraction, shading frames and spherical coordinates (thesis 3.1.1).

Conventions (thesis ch. 3, following `Pharr2023`):

- every direction points *away* from the surface point, including the incident direction
  $\hat\omega_i$ (thesis fig. 3.2), and directions are unit vectors on the last axis `(..., 3)`;
- the surface normal always points *out* of the surface (thesis table 3.2 caption), so a
  direction with $\langle\hat n,\hat\omega\rangle < 0$ lies inside the object;
- in the local shading frame the normal is $+z$, so $\cos\theta = \omega_z$.

**Unit-length policy.** Directions are *assumed* to be unit vectors and are neither checked nor
renormalised: these functions sit in a renderer's innermost loop, where a per-call check would
cost more than the formula. `reflect` is a mirror reflection for a vector of any length;
`refract` and the spherical helpers return the formula applied to the given vector, which is
meaningless for non-unit input. `normalize` is provided for callers that need it.

Leading (batch) axes broadcast. When inputs have different ranks, singleton axes are prepended
explicitly, so the functions also work under `jax_numpy_rank_promotion="raise"`.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import Array

from .._checks import as_float_array, check_last_axis
from .._math import align_ranks, dot, safe_sqrt

__all__ = [
    "Frame",
    "abs_cos_theta",
    "coordinate_system",
    "cos2_theta",
    "cos_phi",
    "cos_theta",
    "face_forward",
    "normalize",
    "reflect",
    "refract",
    "same_hemisphere",
    "sin2_theta",
    "sin_phi",
    "sin_theta",
    "spherical_direction",
    "spherical_phi",
    "spherical_theta",
    "tan2_theta",
    "tan_theta",
    "to_local",
    "to_world",
]


# --------------------------------------------------------------------------------------------
# Broadcasting helpers (explicit rank alignment; style.md section 10 runs with rank promotion
# set to "raise").


def _bcast(*arrays: Array) -> tuple[Array, ...]:
    """Broadcast arrays to their common shape (after rank alignment)."""
    return tuple(jnp.broadcast_arrays(*align_ranks(*arrays)))


@jax.custom_jvp
def _sqrt_clamped(x: Array) -> Array:
    """sqrt(max(x, 0)) with the gradient of `safe_sqrt` (0 where x <= 0), NaN propagating.

    For the BxDFs' inner loop: the square root is the last operation here (the derivative rule
    carries the guard instead of a double `where`), so XLA's CPU backend materialises the
    result once instead of recomputing its argument in every consumer.
    """
    return jnp.sqrt(jnp.maximum(x, 0.0))


@_sqrt_clamped.defjvp
def _sqrt_clamped_jvp(primals, tangents):
    (x,), (dx,) = primals, tangents
    y = _sqrt_clamped(x)
    pos = y > 0
    return y, jnp.where(pos, 0.5 / jnp.where(pos, y, 1.0), 0.0) * dx


def _xyz(w: Array) -> tuple[Array, Array, Array]:
    """The components of vectors `(..., 3)`, each `(...)`."""
    return w[..., 0], w[..., 1], w[..., 2]


def _stack3(x: Array, y: Array, z: Array) -> Array:
    """Stack components into vectors `(..., 3)`, as `jnp.stack(..., axis=-1)`.

    Written as a select on the component index: XLA's CPU backend emits a `concatenate` whose
    operands are long fused expressions very poorly (measured: 40x slower than computing the
    components), while this form computes each component once per vector.
    """
    x, y, z = jnp.broadcast_arrays(x, y, z)
    j = jax.lax.broadcasted_iota(jnp.int32, x.shape + (3,), x.ndim)
    return jnp.where(j == 0, x[..., None], jnp.where(j == 1, y[..., None], z[..., None]))


def _inv_norm(x: Array, y: Array, z: Array) -> tuple[Array, Array]:
    """(1/|v|, |v| > 0) for v = (x, y, z); 0 for the zero vector (finite gradients)."""
    n2 = x * x + y * y + z * z
    ok = n2 > 0
    return jnp.where(ok, 1.0 / jnp.sqrt(jnp.where(ok, n2, 1.0)), 0.0), ok


def _direction(w, name: str) -> Array:
    w = as_float_array(w, name)
    return check_last_axis(w, name, 3)


def normalize(v) -> Array:
    """`v / |v|` along the last axis; a zero vector stays zero (with a finite gradient).

    **Arguments:**

    - `v`: vectors `(..., 3)`. [any unit]

    **Returns:**

    Unit vectors `(..., 3)`. [dimensionless] (`Pharr2023` section 3.3.)
    """
    v = _direction(v, "v")
    n2 = jnp.sum(v * v, axis=-1, keepdims=True)
    ok = n2 > 0
    return jnp.where(ok, v / jnp.sqrt(jnp.where(ok, n2, 1.0)), 0.0)


# --------------------------------------------------------------------------------------------
# Reflection and refraction


def reflect(wi, n) -> Array:
    r"""Mirror reflection of `wi` about the normal `n` (law of reflection).

    $$\hat\omega_r = 2\langle\hat n,\hat\omega_i\rangle\,\hat n - \hat\omega_i$$

    Both directions point away from the surface, so $\theta_r = \theta_i$ and
    $\varphi_r = \varphi_i + \pi$ (thesis eq. 3.7). The thesis prints eq. 3.8 without the
    factor $\hat n$ on the first term; the formula above is the intended one.

    **Arguments:**

    - `wi`: direction `(..., 3)`, pointing away from the surface. [unit vector]
    - `n`: surface normal `(..., 3)`; either orientation gives the same result. [unit vector]

    **Returns:**

    The reflected direction `(..., 3)`, broadcast over the inputs. [unit vector]

    !!! note "Thesis"
        Eq. (3.7)-(3.8), section 3.1.1.

    ??? cite "References"
        `Pharr2023` section 9.2; `Hecht2002` section 4.3.
    """
    wi = _direction(wi, "wi")
    n = _direction(n, "n")
    wi, n = align_ranks(wi, n)
    return 2.0 * jnp.sum(wi * n, axis=-1, keepdims=True) * n - wi


def refract(wi, n, eta) -> tuple[Array, Array]:
    r"""Refraction of `wi` through an interface with relative index of refraction `eta`.

    $$\hat\omega_t = -\frac{\hat\omega_i}{\eta} + \left(\frac{\cos\theta_i}{\eta} -
      \cos\theta_t\right)\hat n,\qquad \cos\theta_t = \sqrt{1 - \frac{1-\cos^2\theta_i}{\eta^2}}$$

    with $\eta = \eta_t/\eta_i$ (thesis eq. 3.10-3.12 with $\eta_i/\eta_t = 1/\eta$). The normal
    points out of the surface: when `wi` lies on the side *opposite* to `n`
    ($\cos\theta_i < 0$, the ray leaves the object), the interface is flipped, i.e. `n` is
    negated and `eta` replaced by `1/eta`, as in `Pharr2023`.

    **Arguments:**

    - `wi`: incident direction `(..., 3)`, pointing away from the surface. [unit vector]
    - `n`: normal `(..., 3)`, pointing out of the surface (to the side of `eta_i`). [unit vector]
    - `eta`: relative index of refraction $\eta_t/\eta_i$ of the side opposite to `n` over the
        side of `n`, shape broadcastable to `wi.shape[:-1]`, > 0. [dimensionless]

    **Returns:**

    A tuple `(wt, valid)`: the transmitted direction `(..., 3)` (unit, pointing away from the
    surface on the side opposite to `wi`), and `valid` `(...)`, False under total internal
    reflection ($\sin^2\theta_t \ge 1$). Under total internal reflection there is no transmitted
    ray; `wt` then holds the mirror direction `reflect(wi, n)`, the physical outcome, so the
    result stays finite and differentiable.

    !!! note "Thesis"
        Eq. (3.7) (Snell's law), (3.10), (3.12), section 3.1.1.

    ??? cite "References"
        `Pharr2023` section 9.3; `Hecht2002` section 4.4.
    """
    wi = _direction(wi, "wi")
    n = _direction(n, "n")
    eta = as_float_array(eta, "eta")
    wi, n = align_ranks(wi, n)
    cos_i = jnp.sum(wi * n, axis=-1)
    cos_i, eta = align_ranks(cos_i, eta)
    # Flip the interface when wi is inside the object.
    inside = cos_i < 0
    eta_eff = jnp.where(inside, 1.0 / eta, eta)
    cos_i_eff = jnp.where(inside, -cos_i, cos_i)
    # Snell's law: sin^2(theta_t) = sin^2(theta_i) / eta^2   (thesis eq. 3.10)
    sin2_i = jnp.maximum(0.0, 1.0 - cos_i_eff * cos_i_eff)
    sin2_t = sin2_i / (eta_eff * eta_eff)
    valid = sin2_t < 1.0
    cos_t = safe_sqrt(jnp.where(valid, 1.0 - sin2_t, 1.0))
    sign = jnp.where(inside, -1.0, 1.0)
    # wt = -wi / eta + (cos_i / eta - cos_t) n, with n flipped when inside   (thesis eq. 3.12)
    coef = sign * (cos_i_eff / eta_eff - cos_t)
    wi_b, inv_eta, coef_b = align_ranks(wi, (1.0 / eta_eff)[..., None], coef[..., None])
    n_b = align_ranks(n, coef_b)[0]
    wt = -wi_b * inv_eta + coef_b * n_b
    wr = 2.0 * cos_i[..., None] * n_b - wi_b
    valid_b = align_ranks(valid[..., None], wt)[0]
    wt = jnp.where(valid_b, wt, wr)
    shape = jnp.broadcast_shapes(wt.shape[:-1], valid.shape)
    return jnp.broadcast_to(wt, shape + (3,)), jnp.broadcast_to(valid, shape)


def face_forward(n, v) -> Array:
    """`n` flipped, if needed, into the hemisphere of `v` (`Pharr2023` section 3.8.4).

    **Arguments:**

    - `n`: vector to orient `(..., 3)`. [unit vector]
    - `v`: reference direction `(..., 3)`. [unit vector]

    **Returns:**

    `n` or `-n`, whichever has a non-negative dot product with `v`. [unit vector]
    """
    n = _direction(n, "n")
    v = _direction(v, "v")
    n, v = align_ranks(n, v)
    d = jnp.sum(n * v, axis=-1, keepdims=True)
    return jnp.where(d < 0, -n, n)


# --------------------------------------------------------------------------------------------
# Shading frames


def coordinate_system(n) -> tuple[Array, Array]:
    """Two unit vectors `(s, t)` completing `n` to a right-handed orthonormal basis.

    Branchless construction of Duff et al. (2017), also used by `Pharr2023` (section 3.3.3):
    `s x t = n`, continuous except on the plane `n_z = 0` where the sign flips.

    **Arguments:**

    - `n`: unit vectors `(..., 3)`. [unit vector]

    **Returns:**

    `(s, t)`, each `(..., 3)`. [unit vectors]

    ??? cite "References"
        `Duff2017`; `Pharr2023` section 3.3.3.
    """
    n = _direction(n, "n")
    x, y, z = n[..., 0], n[..., 1], n[..., 2]
    sign = jnp.where(z >= 0, 1.0, -1.0)
    a = -1.0 / (sign + z)
    b = x * y * a
    s = jnp.stack([1.0 + sign * x * x * a, sign * b, -sign * x], axis=-1)
    t = jnp.stack([b, sign + y * y * a, -y], axis=-1)
    return s, t


class Frame(eqx.Module):
    """An orthonormal shading frame `(s, t, n)`; local coordinates put `n` on +z (thesis 3.1.1).

    Build it from a normal with `Frame.from_z(n)` (which uses `coordinate_system`) or from
    a normal and a tangent with `Frame.from_xz(s, n)`. Arrays may carry batch axes.
    """

    s: Array
    t: Array
    n: Array

    @classmethod
    def from_z(cls, n) -> "Frame":
        """Frame whose third axis is the unit vector `n` `(..., 3)`."""
        n = _direction(n, "n")
        s, t = coordinate_system(n)
        return cls(s, t, n)

    @classmethod
    def from_xz(cls, s, n) -> "Frame":
        """Frame with first axis `s` and third axis `n` (unit, orthogonal), `t = n x s`."""
        s = _direction(s, "s")
        n = _direction(n, "n")
        s, n = _bcast(s, n)
        return cls(s, jnp.cross(n, s), n)


def _frame_axes(frame) -> tuple[Array, Array, Array]:
    if isinstance(frame, Frame):
        return frame.s, frame.t, frame.n
    if isinstance(frame, tuple | list) and len(frame) == 3:
        return tuple(_direction(a, "frame") for a in frame)  # type: ignore[return-value]
    raise TypeError(f"`frame` must be a Frame or a tuple (s, t, n), got {type(frame).__name__}.")


def to_local(frame, v) -> Array:
    """Coordinates of the world-space vector `v` in `frame`: `(v.s, v.t, v.n)`.

    **Arguments:**

    - `frame`: a `Frame`, or a tuple `(s, t, n)` of `(..., 3)` arrays.
    - `v`: vectors `(..., 3)` in world space.

    **Returns:**

    Local coordinates `(..., 3)`; the normal maps to +z. [same unit as `v`]

    ??? cite "References"
        `Pharr2023` section 3.8.3.
    """
    s, t, n = _frame_axes(frame)
    v = _direction(v, "v")
    return jnp.stack([dot(v, s), dot(v, t), dot(v, n)], axis=-1)


def to_world(frame, v) -> Array:
    """World-space vector with local coordinates `v` in `frame`: `v_x s + v_y t + v_z n`.

    **Arguments:**

    - `frame`: a `Frame`, or a tuple `(s, t, n)` of `(..., 3)` arrays.
    - `v`: local coordinates `(..., 3)`.

    **Returns:**

    World-space vectors `(..., 3)`; inverse of `to_local`. [same unit as `v`]

    ??? cite "References"
        `Pharr2023` section 3.8.3.
    """
    s, t, n = _frame_axes(frame)
    v = _direction(v, "v")
    vx, vy, vz, s, t, n = align_ranks(v[..., 0:1], v[..., 1:2], v[..., 2:3], s, t, n)
    return vx * s + vy * t + vz * n


# --------------------------------------------------------------------------------------------
# Spherical coordinates in the local frame (normal = +z), pbrt names.


def cos_theta(w) -> Array:
    r"""$\cos\theta = \omega_z$ of a local direction `(..., 3)`. [dimensionless]

    `Pharr2023` section 3.8.3 (local shading frame, thesis section 3.1.1).
    """
    return _direction(w, "w")[..., 2]


def abs_cos_theta(w) -> Array:
    r"""$|\cos\theta| = |\omega_z|$ of a local direction `(..., 3)`. [dimensionless]

    `Pharr2023` section 3.8.3 (local shading frame, thesis section 3.1.1).
    """
    return jnp.abs(cos_theta(w))


def cos2_theta(w) -> Array:
    r"""$\cos^2\theta$ of a local direction `(..., 3)`. [dimensionless]

    `Pharr2023` section 3.8.3 (local shading frame, thesis section 3.1.1).
    """
    z = cos_theta(w)
    return z * z


def sin2_theta(w) -> Array:
    r"""$\sin^2\theta = \max(0, 1 - \cos^2\theta)$ of a local direction. [dimensionless]

    `Pharr2023` section 3.8.3 (local shading frame, thesis section 3.1.1).
    """
    return jnp.maximum(0.0, 1.0 - cos2_theta(w))


def sin_theta(w) -> Array:
    r"""$\sin\theta \ge 0$ of a local direction (finite gradient at the pole). [dimensionless]

    `Pharr2023` section 3.8.3 (local shading frame, thesis section 3.1.1).
    """
    return safe_sqrt(sin2_theta(w))


def tan_theta(w) -> Array:
    r"""$\tan\theta = \sin\theta/\cos\theta$; infinite at grazing angles. [dimensionless]

    `Pharr2023` section 3.8.3 (local shading frame, thesis section 3.1.1).
    """
    return sin_theta(w) / cos_theta(w)


def tan2_theta(w) -> Array:
    r"""$\tan^2\theta$; infinite at grazing angles. [dimensionless]

    `Pharr2023` section 3.8.3 (local shading frame, thesis section 3.1.1).
    """
    return sin2_theta(w) / cos2_theta(w)


def cos_phi(w) -> Array:
    r"""$\cos\varphi = \omega_x/\sin\theta$, 1 at the pole. [dimensionless]

    `Pharr2023` section 3.8.3 (local shading frame, thesis section 3.1.1).
    """
    w = _direction(w, "w")
    s = sin_theta(w)
    ok = s > 0
    return jnp.where(ok, jnp.clip(w[..., 0] / jnp.where(ok, s, 1.0), -1.0, 1.0), 1.0)


def sin_phi(w) -> Array:
    r"""$\sin\varphi = \omega_y/\sin\theta$, 0 at the pole. [dimensionless]

    `Pharr2023` section 3.8.3 (local shading frame, thesis section 3.1.1).
    """
    w = _direction(w, "w")
    s = sin_theta(w)
    ok = s > 0
    return jnp.where(ok, jnp.clip(w[..., 1] / jnp.where(ok, s, 1.0), -1.0, 1.0), 0.0)


def spherical_direction(sin_theta, cos_theta, phi) -> Array:
    r"""Unit vector $(\sin\theta\cos\varphi, \sin\theta\sin\varphi, \cos\theta)$.

    **Arguments:**

    - `sin_theta`, `cos_theta`: sine and cosine of the polar angle (clamped to [-1, 1]).
        [dimensionless]
    - `phi`: azimuth. [rad]

    **Returns:**

    Directions `(..., 3)` in the local frame. [unit vector]

    ??? cite "References"
        `Pharr2023` section 3.8.3.
    """
    st = jnp.clip(as_float_array(sin_theta, "sin_theta"), -1.0, 1.0)
    ct = jnp.clip(as_float_array(cos_theta, "cos_theta"), -1.0, 1.0)
    phi = as_float_array(phi, "phi")
    st, ct, phi = _bcast(st, ct, phi)
    return jnp.stack([st * jnp.cos(phi), st * jnp.sin(phi), ct], axis=-1)


def spherical_theta(v) -> Array:
    r"""Polar angle $\theta \in [0, \pi]$ of a unit vector, measured from +z. [rad]

    Computed as `arctan2(sqrt(x^2 + y^2), z)`, accurate near the poles (`Pharr2023` 3.8.3).
    """
    v = _direction(v, "v")
    return jnp.arctan2(jnp.sqrt(v[..., 0] ** 2 + v[..., 1] ** 2), v[..., 2])


def spherical_phi(v) -> Array:
    r"""Azimuth $\varphi \in [0, 2\pi)$ of a vector about +z (0 at the pole). [rad]

    `Pharr2023` section 3.8.3 (local shading frame, thesis section 3.1.1).
    """
    v = _direction(v, "v")
    p = jnp.arctan2(v[..., 1], v[..., 0])
    return jnp.where(p < 0, p + 2.0 * jnp.pi, p)


def same_hemisphere(w, wp) -> Array:
    """True where two local directions `(..., 3)` [unit vectors] lie strictly on one side.

    `Pharr2023` section 3.8.3 (local shading frame, thesis section 3.1.1).
    """
    w = _direction(w, "w")
    wp = _direction(wp, "wp")
    a, b = align_ranks(w[..., 2], wp[..., 2])
    return a * b > 0
