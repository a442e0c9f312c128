r"""A batched Levenberg-Marquardt solver for thesis eq. 2.27, free of optimistix.

The residual of eq. 2.27 (CIELAB of the reproduced reflectance minus CIELAB of the target
colour) with its exact Jacobian, and a hand-written damped Gauss-Newton iteration for
millions of colours at once: the table builder's inner solver (`_fit_lut.py`) and the
refinement of wide-gamut table lookups (`_lut.py`). `_fit.py` has the module's theory and the
reference solver (`fit_rgb`, optimistix); this module stays importable without optimistix and
lineax, so that rendering never imports them.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array, Float

from ._forward import ForwardModel, XYZ_to_Lab_white, lab_f
from ._sigmoid_polynomial import _sigmoid

# Delta E*ab: the table's per-entry convergence criterion (the float32 floor is ~2e-3 near white).
DEFAULT_TOLERANCE = 5e-3


class ModelArrays(eqx.Module):
    """The forward model's arrays in the fitter's working dtype (JAX arrays)."""

    lam: Float[Array, " n"]  # normalised wavelength
    weights: Float[Array, "n 3"]  # reflectance -> XYZ
    moments: Float[Array, "n 9"]  # [W lam^2, W lam, W]: d XYZ / d c via s'(x)
    to_xyz: Float[Array, "3 3"]
    white: Float[Array, " 3"]

    @staticmethod
    def build(model: ForwardModel, dtype) -> "ModelArrays":
        lam = np.asarray(model.lambda_normalised)
        w = np.asarray(model.weights_XYZ)
        moments = np.concatenate([w * (lam**2)[:, None], w * lam[:, None], w], axis=1)
        return ModelArrays(
            lam=jnp.asarray(lam, dtype),
            weights=jnp.asarray(w, dtype),
            moments=jnp.asarray(moments, dtype),
            to_xyz=jnp.asarray(model.matrix_RGB_to_XYZ, dtype),
            white=jnp.asarray(model.white_XYZ, dtype),
        )


def _polynomial(c: Array, lam: Array) -> Array:
    lam = lam.reshape((1,) * (c.ndim - 1) + lam.shape)
    return (c[..., 0:1] * lam + c[..., 1:2]) * lam + c[..., 2:3]


def model_XYZ(c: Array, m: ModelArrays) -> Array:
    """XYZ (..., 3) of the reflectance with normalised coefficients `c` (..., 3)."""
    return _sigmoid(_polynomial(c, m.lam)) @ m.weights


def target_Lab(rgb: Array, m: ModelArrays) -> Array:
    """CIELAB of linear RGB (..., 3) in the model's colour space (white = the space's white)."""
    return XYZ_to_Lab_white(rgb @ m.to_xyz.T, m.white)


def residual(c: Array, rgb: Array, m: ModelArrays) -> Array:
    r"""The residual of eq. 2.27: Lab(reproduction) - Lab(target), shape (..., 3)."""
    return XYZ_to_Lab_white(model_XYZ(c, m), m.white) - target_Lab(rgb, m)


def _xyz_and_jacobian(c: Array, m: ModelArrays) -> tuple[Array, Array]:
    """XYZ (n, 3) and d XYZ / d c (n, 3, 3) for a batch of coefficients (n, 3).

    The sigmoid's value and exact derivative come from one `jax.jvp`; the chain rule through
    the (linear) polynomial and quadrature is the precomputed `moments` matrix.
    """
    x = _polynomial(c, m.lam)
    s, ds = jax.jvp(_sigmoid, (x,), (jnp.ones_like(x),))
    xyz = s @ m.weights
    d = (ds @ m.moments).reshape(c.shape[0], 3, 3)  # [i (c index), k (XYZ)]
    return xyz, jnp.swapaxes(d, -1, -2)  # [k, i]


def residual_and_jacobian(c: Array, lab_t: Array, m: ModelArrays, chunk: int | None = None):
    """Residual (n, 3) and its Jacobian d r / d c (n, 3, 3) for n coefficient vectors.

    The CIELAB part of the chain rule is $f'$ (by `jax.jvp` of the CIE f, elementwise)
    assembled into the sparse 3x3 d Lab / d XYZ. With `chunk`, the batch is processed in
    blocks of `chunk` colours by `lax.map`, so the (chunk, n_lambda) intermediates stay in
    cache; the table builder instead blocks at the outermost level.
    """
    n = c.shape[0]
    if chunk is None or chunk >= n:
        xyz, dxyz = _xyz_and_jacobian(c, m)  # (n, 3), (n, 3 [XYZ], 3 [c])
        white = m.white[None, :]
        t = xyz / white
        f, fp = jax.jvp(lab_f, (t,), (jnp.ones_like(t),))
        g = fp / white  # d f(X / Xn) / dX etc.
        L = 116.0 * f[:, 1] - 16.0
        a = 500.0 * (f[:, 0] - f[:, 1])
        b = 200.0 * (f[:, 1] - f[:, 2])
        dX, dY, dZ = dxyz[:, 0], dxyz[:, 1], dxyz[:, 2]
        gx, gy, gz = g[:, 0:1], g[:, 1:2], g[:, 2:3]
        J = jnp.stack(
            [116.0 * gy * dY, 500.0 * (gx * dX - gy * dY), 200.0 * (gy * dY - gz * dZ)], 1
        )
        return jnp.stack([L, a, b], -1) - lab_t, J
    pad = (-n) % chunk
    cp = jnp.pad(c, ((0, pad), (0, 0)))
    tp = jnp.pad(lab_t, ((0, pad), (0, 0)))
    r, J = lax.map(
        lambda args: residual_and_jacobian(args[0], args[1], m),
        (cp.reshape(-1, chunk, 3), tp.reshape(-1, chunk, 3)),
    )
    return r.reshape(-1, 3)[:n], J.reshape(-1, 3, 3)[:n]


def _lm_direction(J: Array, r: Array, mu: Array) -> Array:
    r"""The Levenberg-Marquardt step $\delta$ minimising $|J\delta + r|^2 + \mu|D\delta|^2$.

    $D = \mathrm{diag}(|J_{:,i}|)$ (Marquardt's scaling). Solved as the linear least-squares
    problem $[J; \sqrt\mu D]\,\delta \approx [-r; 0]$ by modified Gram-Schmidt on the
    augmented (m + 3, 4) matrix (m residuals: 3 for eq. 2.27, 4 with the tail penalty of
    `_tails.py`) (backward stable for least squares, Bjorck 1967), never by the
    normal equations: their condition number is cond(J)^2, which reaches 1e7 for the narrow
    spectra of dark saturated colours and made float32 solves stall. Batched over leading axes,
    closed form, branch-free; a zero pivot gives a zero step component.
    """
    dtype = J.dtype
    d = jnp.sqrt(jnp.sum(J * J, axis=-2))  # (n, 3) column norms
    damp = jnp.sqrt(mu)[..., None] * d  # (n, 3)
    eye = jnp.eye(3, dtype=dtype)
    eye = eye.reshape((1,) * (J.ndim - 2) + (3, 3))
    A = jnp.concatenate([J, damp[..., None, :] * eye], axis=-2)  # (n, m + 3, 3)
    b = jnp.concatenate([-r, jnp.zeros(r.shape[:-1] + (3,), dtype)], axis=-1)  # (n, m + 3)
    cols = [A[..., :, 0], A[..., :, 1], A[..., :, 2], b]
    R = [[None] * 4 for _ in range(3)]
    for k in range(3):
        nrm = jnp.sqrt(jnp.sum(cols[k] * cols[k], axis=-1))
        ok = nrm > 0
        q = cols[k] / jnp.where(ok, nrm, 1.0)[..., None]
        R[k][k] = nrm
        for j in range(k + 1, 4):
            R[k][j] = jnp.sum(q * cols[j], axis=-1)
            cols[j] = cols[j] - R[k][j][..., None] * q
    # Back substitution R delta = Q^T b.
    delta = [None, None, None]
    for k in (2, 1, 0):
        acc = R[k][3]
        for j in range(k + 1, 3):
            acc = acc - R[k][j] * delta[j]
        pivot = R[k][k]
        delta[k] = jnp.where(pivot > 0, acc / jnp.where(pivot > 0, pivot, 1.0), 0.0)
    return jnp.stack(delta, axis=-1)


class LMState(eqx.Module):
    """State of the batched Levenberg-Marquardt iteration (one row per colour).

    `c, r, J, cost` describe the best point so far; `c_next` is the candidate the next
    iteration evaluates. Each iteration costs exactly one spectral evaluation (residual and
    Jacobian at `c_next`), and the loop body is the only place that evaluates the model, so the
    compiled program holds one copy of it.
    """

    c: Array  # (n, 3) best coefficients so far, normalised
    r: Array  # (n, 3) residual at c
    J: Array  # (n, 3, 3) Jacobian at c
    cost: Array  # (n,) |r|^2 (inf before the first evaluation)
    mu: Array  # (n,) damping
    c_next: Array  # (n, 3) the candidate to evaluate next


def _propose(c: Array, r: Array, J: Array, mu: Array) -> Array:
    return c + _lm_direction(J, r, mu)


def lm_init(c: Array, mu0: float = 1e-4) -> LMState:
    """A state whose first iteration evaluates the start point `c` (n, 3) (cost = inf)."""
    n = c.shape[0]
    zero = jnp.zeros_like(c)
    return LMState(
        c=c,
        r=zero,
        J=jnp.zeros((n, 3, 3), c.dtype),
        cost=jnp.full((n,), jnp.inf, c.dtype),
        mu=jnp.full((n,), mu0, c.dtype),
        c_next=c,
    )


def lm_retarget(s: LMState, lab_old: Array, lab_new: Array, mu0: float = 1e-4) -> LMState:
    """The state at the same coefficients for a new target colour, without evaluating the model.

    The residual is Lab(model) - Lab(target), so moving the target only shifts it; the
    Jacobian depends on the coefficients alone. The brightness sweep starts every step this
    way from the previous step's final state (saving one spectral evaluation per step), and the
    first candidate is the Gauss-Newton step from there (the tangent predictor).
    """
    r = s.r + (lab_old - lab_new)
    cost = jnp.sum(r * r, axis=-1)
    cost = jnp.where(jnp.isfinite(cost), cost, jnp.inf)
    mu = jnp.full(cost.shape, mu0, s.c.dtype)
    return LMState(s.c, r, s.J, cost, mu, _propose(s.c, r, s.J, mu))


def lm_step(s: LMState, lab_t: Array, m: ModelArrays, chunk: int | None = None) -> LMState:
    """One Levenberg-Marquardt iteration for every row.

    Evaluates the residual and Jacobian at the candidate `c_next`, keeps it where it lowers the
    cost (then $\\mu \\leftarrow \\mu/5$, else $\\mu \\leftarrow 8\\mu$), and proposes the
    next candidate, the damped step of `_lm_direction` from the best point.
    """
    r_new, J_new = residual_and_jacobian(s.c_next, lab_t, m, chunk)
    cost_new = jnp.sum(r_new * r_new, axis=-1)
    ok = (cost_new < s.cost) & jnp.isfinite(cost_new)
    sel = lambda a, b: jnp.where(ok.reshape(ok.shape + (1,) * (a.ndim - 1)), a, b)  # noqa: E731
    c, r, J = sel(s.c_next, s.c), sel(r_new, s.r), sel(J_new, s.J)
    cost = jnp.where(ok, cost_new, s.cost)
    first = jnp.isinf(s.cost)  # the evaluation of a start point is not a step
    mu = jnp.where(first, s.mu, jnp.clip(jnp.where(ok, s.mu * 0.2, s.mu * 8.0), 1e-9, 1e9))
    return LMState(c, r, J, cost, mu, _propose(c, r, J, mu))


def lm_iterate(
    state: LMState, lab_t: Array, m: ModelArrays, n_steps, chunk: int | None = None
) -> LMState:
    """Exactly `n_steps` `lm_step`s (`lax.fori_loop`)."""
    return lax.fori_loop(0, n_steps, lambda _, s: lm_step(s, lab_t, m, chunk), state)


def lm_solve(
    state: LMState,
    lab_t: Array,
    m: ModelArrays,
    max_steps,
    tolerance,
    *,
    min_steps=1,
    allowed_fraction=0.0,
    chunk: int | None = None,
) -> tuple[Array, LMState]:
    """`lm_step`s until at most `allowed_fraction` of the rows miss `tolerance` (a residual
    norm, Delta E*ab) or `max_steps` (may be traced) is reached (`lax.while_loop`).

    The batch is one vectorised computation, so converged rows ride along; the fraction lets
    a handful of hard rows go to a later repair pass instead of holding up the whole batch.
    Returns the number of steps taken and the final state.
    """
    n = state.cost.shape[0]
    dtype = state.c.dtype
    tol2 = jnp.asarray(tolerance, dtype) ** 2
    limit = jnp.floor(jnp.asarray(allowed_fraction, dtype) * n)

    def cond(carry):
        i, s = carry
        n_bad = jnp.sum(~(s.cost <= tol2)).astype(dtype)
        return (i < max_steps) & ((i < min_steps) | (n_bad > limit))

    def body(carry):
        i, s = carry
        return i + 1, lm_step(s, lab_t, m, chunk)

    return lax.while_loop(cond, body, (jnp.asarray(0, jnp.int32), state))
