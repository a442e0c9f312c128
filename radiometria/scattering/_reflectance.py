r"""Reflectance quantities of thesis table 3.2, estimated by Monte Carlo.

All quantities are reflectances (ratios of reflected to incident flux, dimensionless) of a BxDF
for a given geometry of incidence and collection (`Nicodemus1977`, thesis table 3.2):

| function | incident | collected | thesis |
|---|---|---|---|
| `bidirectional_reflectance(bxdf, wo, wi)` | direction | $d\omega_o$ | table 3.2 |
| `directional_hemispherical_reflectance(bxdf, wi)` | direction | hemisphere | table 3.2 |
| `hemispherical_directional_reflectance(bxdf, wo)` | hemisphere | direction | eq. 3.5 |
| `normalised_hemispherical_directional_reflectance(bxdf, wo)` | hemisphere | $d\omega_o$ | 3.2 |
| `directional_conical_reflectance(bxdf, wi, cone)` | direction | cone $\Omega$ | table 3.2 |
| `conical_directional_reflectance(bxdf, cone, wo)` | cone $\Omega$ | $d\omega_o$ | table 3.2 |
| `conical_hemispherical_reflectance(bxdf, cone)` | cone | hemisphere | table 3.2 |
| `hemispherical_conical_reflectance(bxdf, cone)` | hemisphere | cone | table 3.2 |
| `biconical_reflectance(bxdf, cone_i, cone_o)` | cone | cone | table 3.2 |
| `bihemispherical_reflectance(bxdf)` | hemisphere | hemisphere | eq. 3.6 |

$$\rho(\Omega_i, \Omega_o) = \frac{1}{\Omega'_i}\int_{\Omega_i}\int_{\Omega_o}
  f(\omega_o, \omega_i)\,|\cos\theta_o|\,|\cos\theta_i|\,d\omega_o\,d\omega_i,\qquad
  \Omega'_i = \int_{\Omega_i}|\cos\theta_i|\,d\omega_i$$

and its directional limits, with uniform incident radiance over $\Omega_i$. For incidence from
the whole hemisphere $\Omega'_i = \pi$, the thesis's normalisation. For a *cone* of incidence
the thesis prints the same $1/\pi$; this module follows Nicodemus et al. (1977) and divides
by the projected solid angle $\Omega'_i$ of the incident cone (`Nicodemus1977`), so that a
perfect white reflector has reflectance 1 for every geometry (the two agree when the cone is the
hemisphere).

"Hemispherical-directional reflectance" here is the thesis's eq. (3.5), which the thesis calls
the albedo, $\rho(\omega_o) = \int f(\omega_o,\omega_i)|\cos\theta_i|\,d\omega_i$; the
differential form of table 3.2 is this times $|\cos\theta_o|\,d\omega_o/\pi$.

The three "$d\omega_o$" rows are Nicodemus' differential reflectances $d\rho/d\omega_o$ into an
element of solid angle around `wo` (units sr^-1): the integrands of hemispherical or conical
collection. Divided by $|\cos\theta_o|/\pi$ (the value for the perfect white Lambertian
reflector) they become reflectance *factors*, equal to $R$ for a Lambertian surface.

Geometry: the local shading frame (normal +z); the hemisphere is the one of the given direction
(`wi` / `wo`), or the upper one (+z) when the incidence is hemispherical or conical. Only
reflection counts: transmitted directions of a dielectric are excluded. A `Cone` must lie above
the horizon.

Estimators: the BxDF's own importance sampling (`sample_f`; with `mode="importance"`, the
adjoint, when sampling outgoing from incident directions), cosine-weighted hemisphere or uniform
cone sampling for hemispherical or conical incidence (`radiometria.montecarlo` warps). Each
function returns a `radiometria.montecarlo.Estimate` (mean, variance, standard error) per
wavelength, shape `(..., n_lambda)`. Pass `key` for independent samples or `u` (`(n, d)`
variates, e.g. `montecarlo.sobol`) for quasi-Monte Carlo; then the standard error is the naive
i.i.d. one and only indicative.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import Array

from .._checks import as_float_array, check_positive_int
from .._math import align_ranks
from .._types import Key
from ..montecarlo import Estimate, estimate_mean, sample_cosine_hemisphere, sample_uniform_cone
from ._bxdfs import AbstractBxDF
from ._directions import coordinate_system

__all__ = [
    "Cone",
    "biconical_reflectance",
    "bidirectional_reflectance",
    "bihemispherical_reflectance",
    "conical_directional_reflectance",
    "conical_hemispherical_reflectance",
    "directional_conical_reflectance",
    "directional_hemispherical_reflectance",
    "hemispherical_conical_reflectance",
    "hemispherical_directional_reflectance",
    "normalised_hemispherical_directional_reflectance",
]


class Cone(eqx.Module):
    r"""A cone of directions for the conical reflectances of thesis table 3.2.

    Unit `axis` `(3,)` and half-angle $\gamma$ (stored as `cos_half_angle`).

    The cone must lie above the horizon of the local frame, $\theta_{axis} + \gamma \le \pi/2$
    (checked). Its solid angle is $2\pi(1 - \cos\gamma)$ and its projected solid angle
    $\Omega' = \pi\sin^2\gamma\cos\theta_{axis}$ [sr].

    **Fields:**

    - `axis`: unit vector `(3,)` in the local frame. [unit vector]
    - `cos_half_angle`: $\cos\gamma$, in [0, 1). [dimensionless]
    """

    axis: Array
    cos_half_angle: Array

    def __init__(self, axis, half_angle):
        """Build from the axis `(3,)` and the half-angle $\\gamma$ [rad], in (0, pi/2]."""
        axis = as_float_array(axis, "axis")
        if axis.shape != (3,):
            raise ValueError(f"`axis` must have shape (3,), got {axis.shape}.")
        axis = axis / jnp.linalg.norm(axis)
        g = as_float_array(half_angle, "half_angle")
        if g.ndim != 0:
            raise ValueError(f"`half_angle` must be a scalar, got shape {g.shape}.")
        theta_axis = jnp.arccos(jnp.clip(axis[2], -1.0, 1.0))
        g = eqx.error_if(
            g,
            (g <= 0) | (theta_axis + g > jnp.pi / 2 + 1e-12),
            "`half_angle` must lie in (0, pi/2] [rad] and the cone above the horizon "
            "(axis polar angle + half_angle <= pi/2).",
        )
        self.axis = axis
        self.cos_half_angle = jnp.cos(g)

    def solid_angle(self) -> Array:
        """$2\\pi(1 - \\cos\\gamma)$. [sr]"""
        return 2.0 * jnp.pi * (1.0 - self.cos_half_angle)

    def projected_solid_angle(self) -> Array:
        """$\\pi\\sin^2\\gamma\\cos\\theta_{axis}$ (the cone is above the horizon). [sr]"""
        return jnp.pi * (1.0 - self.cos_half_angle**2) * self.axis[2]

    def contains(self, w: Array) -> Array:
        """True for directions `(..., 3)` inside the cone."""
        axis = jnp.reshape(self.axis, (1,) * (w.ndim - 1) + (3,))
        return jnp.sum(w * axis, axis=-1) >= self.cos_half_angle

    def sample(self, u: Array) -> Array:
        """Uniform directions in the cone from `u` `(..., 2)`; density `1/solid_angle()`."""
        local = sample_uniform_cone(u, self.cos_half_angle)
        shape = (1,) * (local.ndim - 1) + (3,)
        s, t = coordinate_system(self.axis)
        s, t, a = (jnp.reshape(x, shape) for x in (s, t, self.axis))
        return local[..., 0:1] * s + local[..., 1:2] * t + local[..., 2:3] * a


def _variates(n_samples, d: int, key, u) -> Array:
    if u is not None:
        u = as_float_array(u, "u")
        if u.ndim != 2 or u.shape[1] < d:
            raise ValueError(f"`u` must have shape (n, {d}) or more columns, got {u.shape}.")
        return u[:, :d]
    if key is None:
        raise ValueError("Pass `key` (Monte Carlo) or `u` (explicit variates).")
    n = check_positive_int(n_samples, "n_samples", minimum=2)
    return jax.random.uniform(key, (n, d))


def _check_bxdf(bxdf) -> AbstractBxDF:
    if not isinstance(bxdf, AbstractBxDF):
        raise TypeError(f"`bxdf` must be a BxDF, got {type(bxdf).__name__}.")
    return bxdf


def _collect(bxdf, w_from, u3, cone_o, mode) -> Array:
    """Terms f |cos| / pdf * [reflected into the collecting region], `(n, ..., n_lambda)`.

    `w_from` `(n, ..., 3)` is the fixed direction, the sample is drawn with `sample_f`."""
    s = bxdf.sample_f(w_from, u3[..., 0], u3[..., 1:3], mode=mode)
    keep = (w_from[..., 2] * s.wi[..., 2] > 0) & (s.pdf > 0)
    if cone_o is not None:
        keep = keep & cone_o.contains(s.wi)
    w = s.weight()
    return jnp.where(keep[..., None], w, 0.0)


def _expand(w: Array, n: int) -> Array:
    return jnp.broadcast_to(w, (n,) + w.shape)


def _u_batch(u: Array, batch: tuple[int, ...]) -> Array:
    """(n, d) -> (n, *batch, d)."""
    return jnp.broadcast_to(
        u.reshape((u.shape[0],) + (1,) * len(batch) + (u.shape[1],)),
        (u.shape[0],) + batch + (u.shape[1],),
    )


def directional_hemispherical_reflectance(
    bxdf, wi, *, n_samples: int | None = None, key: Key | None = None, u=None
) -> Estimate:
    r"""Directional-hemispherical reflectance $\rho(\omega_i)$.

    $$\rho(\omega_i) = \int_{\mathcal H^2} f(\omega_o, \omega_i)|\cos\theta_o|\,d\omega_o$$

    The fraction of the flux arriving from `wi` that is reflected into the hemisphere of `wi`.

    **Arguments:**

    - `bxdf`: any BxDF of this module.
    - `wi`: incident direction `(..., 3)`, local frame. [unit vector]
    - `n_samples`, `key`: number of samples and `jax.random` key; or
    - `u`: explicit uniform variates `(n, 3)`.

    **Returns:**

    `Estimate` with `mean` `(..., n_lambda)` in [0, 1]. [dimensionless]

    !!! note "Thesis"
        Table 3.2, "Directional-Hemispherical Reflectance".
    """
    bxdf = _check_bxdf(bxdf)
    wi = as_float_array(wi, "wi")
    u = _variates(n_samples, 3, key, u)
    n = u.shape[0]
    terms = _collect(bxdf, _expand(wi, n), _u_batch(u, wi.shape[:-1]), None, "importance")
    return estimate_mean(terms, axis=0)


def hemispherical_directional_reflectance(
    bxdf, wo, *, n_samples: int | None = None, key: Key | None = None, u=None
) -> Estimate:
    r"""Hemispherical-directional reflectance or albedo $\rho(\omega_o)$ (thesis eq. 3.5).

    $$\rho(\omega_o) = \int_{\mathcal H^2} f(\omega_o, \omega_i)|\cos\theta_i|\,d\omega_i$$

    The reflected radiance towards `wo` under uniform unit incident radiance from the hemisphere
    of `wo` (the white furnace); equal to `directional_hemispherical_reflectance(bxdf, wo)` for a
    reciprocal BRDF.

    **Arguments:**

    - `bxdf`: any BxDF of this module.
    - `wo`: outgoing direction `(..., 3)`, local frame. [unit vector]
    - `n_samples`, `key`, `u`: as in `directional_hemispherical_reflectance`.

    **Returns:**

    `Estimate` with `mean` `(..., n_lambda)`. [dimensionless]

    !!! note "Thesis"
        Eq. (3.5), table 3.2 "Hemispherical-Directional Reflectance (alt)".
    """
    bxdf = _check_bxdf(bxdf)
    wo = as_float_array(wo, "wo")
    u = _variates(n_samples, 3, key, u)
    n = u.shape[0]
    terms = _collect(bxdf, _expand(wo, n), _u_batch(u, wo.shape[:-1]), None, "radiance")
    return estimate_mean(terms, axis=0)


def directional_conical_reflectance(
    bxdf, wi, cone: Cone, *, n_samples: int | None = None, key: Key | None = None, u=None
) -> Estimate:
    r"""Directional-conical reflectance $\rho(\omega_i; \Omega)$.

    $$\rho(\omega_i; \Omega) = \int_\Omega f(\omega_o, \omega_i)|\cos\theta_o|\,d\omega_o$$

    **Arguments:**

    - `bxdf`: any BxDF of this module.
    - `wi`: incident direction `(..., 3)`. [unit vector]
    - `cone`: the collecting `Cone`.
    - `n_samples`, `key`, `u`: as in `directional_hemispherical_reflectance` (`u` `(n, 3)`).

    **Returns:**

    `Estimate` with `mean` `(..., n_lambda)`. [dimensionless]

    !!! note "Thesis"
        Table 3.2, "Directional-Conical Reflectance".
    """
    bxdf = _check_bxdf(bxdf)
    wi = as_float_array(wi, "wi")
    u = _variates(n_samples, 3, key, u)
    n = u.shape[0]
    terms = _collect(bxdf, _expand(wi, n), _u_batch(u, wi.shape[:-1]), cone, "importance")
    return estimate_mean(terms, axis=0)


def _incident(cone_i: Cone | None, u2: Array) -> tuple[Array, Array]:
    """Incident directions and weights cos/(Omega'_i p) for hemispherical or conical incidence."""
    if cone_i is None:
        # Cosine-weighted: p = cos/pi = cos/Omega'_i, the weight is exactly 1.
        return sample_cosine_hemisphere(u2), jnp.ones(u2.shape[:-1], u2.dtype)
    wi = cone_i.sample(u2)
    weight = wi[..., 2] * cone_i.solid_angle() / cone_i.projected_solid_angle()
    return wi, weight


def biconical_reflectance(
    bxdf,
    cone_i: Cone | None,
    cone_o: Cone | None,
    *,
    n_samples: int | None = None,
    key: Key | None = None,
    u=None,
) -> Estimate:
    r"""Biconical reflectance $\rho(\Omega_i, \Omega_o)$ for uniform radiance from $\Omega_i$.

    $$\rho = \frac{1}{\Omega'_i}\int_{\Omega_i}\int_{\Omega_o} f\,|\cos\theta_o\cos\theta_i|\,
      d\omega_o\,d\omega_i$$

    `None` for a cone means the upper hemisphere; the other conical and hemispherical variants
    are special cases.

    **Arguments:**

    - `bxdf`: any BxDF of this module.
    - `cone_i`, `cone_o`: incident and collecting `Cone`s, or `None` for the hemisphere.
    - `n_samples`, `key`: number of samples and key; or `u` `(n, 5)` variates.

    **Returns:**

    `Estimate` with `mean` `(n_lambda,)`. [dimensionless]

    !!! note "Thesis"
        Table 3.2, "Biconical Reflectance"; eq. (3.6) for two hemispheres.
    """
    bxdf = _check_bxdf(bxdf)
    u = _variates(n_samples, 5, key, u)
    wi, w_in = _incident(cone_i, u[:, 3:5])
    terms = _collect(bxdf, wi, u[:, 0:3], cone_o, "importance") * w_in[:, None]
    return estimate_mean(terms, axis=0)


def conical_hemispherical_reflectance(bxdf, cone: Cone, **kwargs) -> Estimate:
    """Conical-hemispherical reflectance: incidence over `cone`, collection over the hemisphere.

    See `biconical_reflectance` (keywords `n_samples`, `key`, `u`). Thesis table 3.2.
    Returns an `Estimate` of the reflectance `(n_lambda,)`. [dimensionless]
    """
    return biconical_reflectance(bxdf, cone, None, **kwargs)


def hemispherical_conical_reflectance(bxdf, cone: Cone, **kwargs) -> Estimate:
    """Hemispherical-conical reflectance: incidence over the hemisphere, collection over `cone`.

    See `biconical_reflectance` (keywords `n_samples`, `key`, `u`). Thesis table 3.2.
    Returns an `Estimate` of the reflectance `(n_lambda,)`. [dimensionless]
    """
    return biconical_reflectance(bxdf, None, cone, **kwargs)


def bihemispherical_reflectance(bxdf, **kwargs) -> Estimate:
    r"""Bi-hemispherical reflectance (thesis eq. 3.6).

    $$\rho = \frac1\pi\int\int f|\cos\theta_o\cos\theta_i|\,d\omega_o d\omega_i$$

    The spherical albedo: the fraction of uniformly incident flux that is reflected. See
    `biconical_reflectance` (keywords `n_samples`, `key`, `u`). Returns an `Estimate`
    `(n_lambda,)`. [dimensionless]
    """
    return biconical_reflectance(bxdf, None, None, **kwargs)


def bidirectional_reflectance(bxdf, wo, wi) -> Array:
    r"""Bidirectional reflectance $d\rho/d\omega_o$, per unit solid angle of collection.

    $$\frac{d\rho(\omega_o, \omega_i)}{d\omega_o} = f(\omega_o, \omega_i)\,|\cos\theta_o|$$

    The fraction of the flux arriving from `wi` that is reflected into the solid angle
    $d\omega_o$ around `wo`: the integrand of every other reflectance of the table, and a
    probability density over the collecting directions (its integral over the hemisphere is
    `directional_hemispherical_reflectance`). For a Lambertian surface it is
    $R|\cos\theta_o|/\pi$. Exact (no sampling); a delta (specular) lobe gives 0, as its
    BxDF is not a function.

    **Arguments:**

    - `bxdf`: any BxDF of this module.
    - `wo`, `wi`: collecting and incident directions `(..., 3)`, local frame; pairs on opposite
        sides (transmission) give 0. [unit vectors]

    **Returns:**

    `(..., n_lambda)`. [sr^-1]

    !!! note "Thesis"
        Table 3.2, "Bidirectional Reflectance".

    ??? cite "References"
        `Nicodemus1977`.
    """
    bxdf = _check_bxdf(bxdf)
    wo = as_float_array(wo, "wo")
    wi = as_float_array(wi, "wi")
    f = bxdf.f(wo, wi)
    cos_o, cos_i = align_ranks(wo[..., 2:3], wi[..., 2:3])
    cos_o, f = align_ranks(jnp.where(cos_o * cos_i > 0, jnp.abs(cos_o), 0.0), f)
    return f * cos_o


def conical_directional_reflectance(
    bxdf, cone: Cone, wo, *, n_samples: int | None = None, key: Key | None = None, u=None
) -> Estimate:
    r"""Conical-directional reflectance $d\rho(\Omega; \omega_o)/d\omega_o$ for uniform radiance
    from the cone $\Omega$.

    $$\frac{d\rho(\Omega; \omega_o)}{d\omega_o} = \frac{|\cos\theta_o|}{\Omega'}
      \int_\Omega f(\omega_o, \omega_i)|\cos\theta_i|\,d\omega_i,\qquad
      \Omega' = \int_\Omega|\cos\theta_i|\,d\omega_i$$

    per unit solid angle of collection around `wo` (the thesis normalises by $\pi$ instead of
    $\Omega'$; see the module notes). Reciprocity (`Nicodemus1977`) ties it to the
    directional-conical reflectance: $\Omega'\,d\rho(\Omega;\omega)/d\omega =
    |\cos\theta|\,\rho(\omega;\Omega)$ for a reciprocal BxDF. For a Lambertian surface it is
    $R|\cos\theta_o|/\pi$ for every cone.

    Estimated with the BxDF's sampling from `wo` (`mode="radiance"`), keeping the directions
    inside the cone, so delta lobes count.

    **Arguments:**

    - `bxdf`: any BxDF of this module.
    - `cone`: the incident `Cone`.
    - `wo`: collecting direction `(..., 3)`, upper hemisphere. [unit vector]
    - `n_samples`, `key`, `u`: as in `directional_hemispherical_reflectance` (`u` `(n, 3)`).

    **Returns:**

    `Estimate` with `mean` `(..., n_lambda)`. [sr^-1]

    !!! note "Thesis"
        Table 3.2, "Conical-Directional Reflectance".

    ??? cite "References"
        `Nicodemus1977`.
    """
    bxdf = _check_bxdf(bxdf)
    if not isinstance(cone, Cone):
        raise TypeError(f"`cone` must be a Cone, got {type(cone).__name__}.")
    wo = as_float_array(wo, "wo")
    u = _variates(n_samples, 3, key, u)
    n = u.shape[0]
    terms = _collect(bxdf, _expand(wo, n), _u_batch(u, wo.shape[:-1]), cone, "radiance")
    scale = jnp.abs(wo[..., 2:3]) / cone.projected_solid_angle()
    return estimate_mean(terms * scale[None], axis=0)


def normalised_hemispherical_directional_reflectance(
    bxdf, wo, *, n_samples: int | None = None, key: Key | None = None, u=None
) -> Estimate:
    r"""Hemispherical-directional reflectance $d\rho(\omega_o)/d\omega_o$ for uniform radiance
    from the hemisphere, per unit solid angle of collection (Nicodemus' form).

    $$\frac{d\rho(\omega_o)}{d\omega_o} = \frac{|\cos\theta_o|}{\pi}
      \int_{\mathcal H^2} f(\omega_o, \omega_i)|\cos\theta_i|\,d\omega_i
      = \frac{|\cos\theta_o|}{\pi}\,\rho(\omega_o)$$

    with $\rho(\omega_o)$ the albedo of eq. (3.5) (`hemispherical_directional_reflectance`).
    The fraction of uniformly incident flux reflected into $d\omega_o$; its integral over the
    hemisphere is the bi-hemispherical reflectance (eq. 3.6). For a Lambertian surface it is
    $R|\cos\theta_o|/\pi$, for a mirror $F_r(\cos\theta_o)|\cos\theta_o|/\pi$.

    **Arguments:**

    - `bxdf`: any BxDF of this module.
    - `wo`: collecting direction `(..., 3)`, local frame. [unit vector]
    - `n_samples`, `key`, `u`: as in `directional_hemispherical_reflectance`.

    **Returns:**

    `Estimate` with `mean` `(..., n_lambda)`. [sr^-1]

    !!! note "Thesis"
        Table 3.2, "Hemispherical-Directional Reflectance" (the "(alt)" form is eq. 3.5).

    ??? cite "References"
        `Nicodemus1977`.
    """
    bxdf = _check_bxdf(bxdf)
    wo = as_float_array(wo, "wo")
    u = _variates(n_samples, 3, key, u)
    n = u.shape[0]
    terms = _collect(bxdf, _expand(wo, n), _u_batch(u, wo.shape[:-1]), None, "radiance")
    return estimate_mean(terms * (jnp.abs(wo[..., 2:3]) / jnp.pi)[None], axis=0)
