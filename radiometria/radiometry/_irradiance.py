r"""Irradiance from an arbitrary radiance distribution (thesis eq. 1.13), by quadrature.

$$E_e = \int_\Omega L_{e,\Omega}(\hat\omega)\cos\theta\,\mathrm d\hat\omega
      = \int_{\theta_1}^{\theta_2}\!\int_{\varphi_1}^{\varphi_2}
        L_{e,\Omega}(\theta, \varphi)\cos\theta\sin\theta\,\mathrm d\varphi\,\mathrm d\theta$$

over a rectangle of the (theta, phi) parametrisation of directions above a surface (theta from
the normal). The tensor-product Gauss-Legendre rule integrates $L\cos\theta\sin\theta$ exactly
when it is a polynomial of degree <= 2n - 1 in each variable, and converges faster than any
power of n for an integrand that is smooth on the rectangle; a radiance with a jump (a sharp
cone, a light's edge) converges slowly unless the bounds are split at the jump. The closed form
for a uniform radiance over a cone around the normal is `irradiance_from_radiance`.
"""

import math
from collections.abc import Callable

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_in_range, check_positive_int


def _interval(bounds, name: str) -> tuple[Array, Array]:
    """The two scalar ends of an integration interval (a pair), as float arrays."""
    if isinstance(bounds, str) or not hasattr(bounds, "__len__") or len(bounds) != 2:
        raise ValueError(f"`{name}` must be a pair (lower, upper) [rad], got {bounds!r}.")
    lo = as_float_array(bounds[0], name)
    hi = as_float_array(bounds[1], name)
    if lo.ndim or hi.ndim:
        raise ValueError(
            f"`{name}` must hold two scalars [rad], got shapes {lo.shape} and {hi.shape}."
        )
    return lo, hi


def _gauss_legendre(lo: Array, hi: Array, n: int, dtype) -> tuple[Array, Array]:
    """Nodes and weights of the n-point Gauss-Legendre rule mapped from [-1, 1] to [lo, hi]."""
    x, w = np.polynomial.legendre.leggauss(n)  # static: n is a Python int
    x = jnp.asarray(x, dtype=dtype)
    w = jnp.asarray(w, dtype=dtype)
    lo = lo.astype(dtype)
    hi = hi.astype(dtype)
    half = 0.5 * (hi - lo)
    return 0.5 * (hi + lo) + half * x, half * w


def irradiance_from_radiance_distribution(
    radiance_fn: Callable[[Array, Array], ArrayLike],
    theta_bounds=(0.0, math.pi / 2),
    phi_bounds=(0.0, 2.0 * math.pi),
    *,
    n_theta: int = 64,
    n_phi: int = 64,
) -> Float[Array, "*channels"]:
    r"""Irradiance from any radiance distribution $L(\theta, \varphi)$ (Gauss-Legendre rule).

    $$E = \int_{\theta_1}^{\theta_2}\!\int_{\varphi_1}^{\varphi_2}
          L(\theta, \varphi)\cos\theta\sin\theta\,\mathrm d\varphi\,\mathrm d\theta
        \approx \sum_{i,j} w_i w_j\, L(\theta_i, \varphi_j)\cos\theta_i\sin\theta_i$$

    with `n_theta` x `n_phi` Gauss-Legendre nodes. The bounds may be traced values, so the
    result is differentiable in them (and in anything `radiance_fn` closes over); the function
    can be `jax.jit`-ted with `radiance_fn` closed over or passed through `equinox.filter_jit`.

    **Arguments:**

    - `radiance_fn`: a function `(theta, phi) -> L` of two arrays of shape (n_theta, n_phi)
        [rad] (theta from the surface normal, phi the azimuth) returning the incident radiance
        there, of shape (n_theta, n_phi, *channels) (e.g. a spectral axis last) or a scalar
        for a constant. [W sr^-1 m^-2] (or [W sr^-1 m^-2 nm^-1], or luminance [cd m^-2])
    - `theta_bounds`: (theta_1, theta_2), polar angles with 0 <= theta_1 <= theta_2 <= pi/2:
        directions above the surface. [rad]
    - `phi_bounds`: (phi_1, phi_2), azimuths with phi_1 <= phi_2; (0, 2 pi) is the full turn.
        [rad]
    - `n_theta`, `n_phi`: numbers of quadrature nodes in theta and phi (static ints >= 1).

    **Returns:**

    Irradiance $E$, of shape `channels`. [W m^-2] (or [W m^-2 nm^-1], or illuminance [lx]) It
    is computed in the dtype of the bounds (the default float dtype for Python floats),
    promoted with that of the radiance.

    Bounds out of range or decreasing raise `equinox.EquinoxRuntimeError` (also under
    `jax.jit`); a radiance of the wrong shape raises `ValueError`.

    !!! note "Thesis"
        Thesis eq. (1.13), section 1.4.

    ??? cite "References"
        `Pharr2023` §4.2 (radiometric integrals over spherical coordinates); `Davis1984`
        (Gauss-Legendre and product rules).
    """
    if not callable(radiance_fn):
        raise TypeError(f"`radiance_fn` must be callable, got {type(radiance_fn).__name__}.")
    n_theta = check_positive_int(n_theta, "n_theta")
    n_phi = check_positive_int(n_phi, "n_phi")
    theta_1, theta_2 = _interval(theta_bounds, "theta_bounds")
    phi_1, phi_2 = _interval(phi_bounds, "phi_bounds")
    theta_1 = check_in_range(theta_1, "theta_bounds", 0.0, math.pi / 2, unit="rad")
    theta_2 = check_in_range(theta_2, "theta_bounds", 0.0, math.pi / 2, unit="rad")
    theta_2 = eqx.error_if(
        theta_2, theta_2 < theta_1, "`theta_bounds` must be increasing [rad]: theta_1 > theta_2."
    )
    phi_2 = eqx.error_if(
        phi_2, phi_2 < phi_1, "`phi_bounds` must be increasing [rad]: phi_1 > phi_2."
    )
    dtype = jnp.result_type(theta_1, theta_2, phi_1, phi_2)
    theta, w_theta = _gauss_legendre(theta_1, theta_2, n_theta, dtype)
    phi, w_phi = _gauss_legendre(phi_1, phi_2, n_phi, dtype)
    grid = (n_theta, n_phi)
    theta_grid = jnp.broadcast_to(theta[:, None], grid)
    phi_grid = jnp.broadcast_to(phi[None, :], grid)
    radiance = jnp.asarray(radiance_fn(theta_grid, phi_grid))
    if not jnp.issubdtype(radiance.dtype, jnp.floating):
        raise TypeError(
            f"`radiance_fn` must return a floating-point array, got dtype {radiance.dtype}."
        )
    if radiance.ndim == 0:
        radiance = jnp.broadcast_to(radiance, grid)
    if radiance.shape[:2] != grid:
        raise ValueError(
            f"`radiance_fn` must return shape {grid} + channels (or a scalar), got "
            f"{radiance.shape}."
        )
    out = jnp.promote_types(dtype, radiance.dtype)
    # Quadrature weight of node (i, j): w_i w_j cos(theta_i) sin(theta_i), the projected
    # solid angle d(omega) cos(theta) = cos(theta) sin(theta) d(theta) d(phi) it stands for.
    w_proj = w_theta * jnp.cos(theta) * jnp.sin(theta)
    weights = (w_proj[:, None] * w_phi[None, :]).astype(out)
    return jnp.tensordot(weights, radiance.astype(out), axes=((0, 1), (0, 1)))
