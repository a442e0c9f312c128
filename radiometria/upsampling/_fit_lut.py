r"""Fitting the RGB -> coefficient table (thesis eq. 2.27, section 2.2.3): `fit_lut`.

The table's layout and lookup are in `_lut.py` (`RGBToSpectrumLUT`).

**Fit.** Each column (l, j, i) of the table is a curve along brightness. As in pbrt's
`rgb2spec_opt`, the column is solved first at `k0 = res // 5` from c = 0, then warm-started
upwards to k = res - 1 and downwards to k = 1 (`lax.scan`), every column at once (`vmap`-style
batching over the flattened (3 res res) axis, optionally sharded over devices). Each step runs
a fixed number of damped Gauss-Newton iterations (`_fit.lm_iterate`); entries that miss the
tolerance are then refitted with many more iterations from their converged neighbours (the
"repair" pass), and each entry's final residual and `optimistix.RESULTS` code are reported.

**Explicit ends.** The black row (k = 0, z = 0) has no finite solution (S = 0 needs
$c_2 = -\infty$); it stores the coefficients of row k = 1 (z = 1.7e-6 at res 64), so lookups
below that brightness reproduce a colour darker than L* = 0.002. The grey column (i = j =
res - 1) is set to the closed form, and its top node, white, to the finite
`WHITE_C2 = 2048` (s(2048) = 1 - 6e-8, i.e. 1 in float32; Mitsuba's new rgb2spec uses 8192 the
same way): lookups of white itself take the exact grey path.
"""

import functools
import time
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jax import lax
from jax.sharding import Mesh, NamedSharding, PartitionSpec as P
from jaxtyping import Array, Float

from .._checks import check_positive_int
from ._forward import forward_model
from ._layout import column_directions
from ._lm import (
    DEFAULT_TOLERANCE,
    LMState,
    ModelArrays,
    lm_init,
    lm_iterate,
    lm_retarget,
    lm_solve,
    residual_and_jacobian,
    target_Lab,
)
from ._lut import REFINE_STEPS, RGBToSpectrumLUT, brightness_scale
from ._sigmoid_polynomial import _normalised_to_nm_np
from ._tails import suppress_infrared_tails

WHITE_C2 = 2048.0  # c2 of the white node (module docstring)


class LUTFitResult(eqx.Module):
    """What `fit_lut` returns: the table and a per-entry account of the fit.

    - `lut`: the `RGBToSpectrumLUT`.
    - `residual` (3, res, res, res): $\\Delta E^*_{ab}$ of each table entry against its own
        target colour (0 for the closed-form entries). [-]
    - `result`: `optimistix.RESULTS` per entry (`successful` where residual <= tolerance).
    - `exact` (3, res, res, res) bool: entries set in closed form (greys, white, black row).
    - `tolerance`: the convergence tolerance (static). [Delta E*ab]
    - `num_repaired`: entries that needed the repair pass (static).
    - `seconds`: wall time of the fit, compilation included (static). [s]
    - `settings`: the fit settings, JSON-able (static).

    !!! note "Thesis"
        Eq. 2.27 and the lookup table of section 2.2.3.
    """

    lut: RGBToSpectrumLUT
    residual: Float[Array, "3 res res res"]
    result: Any  # an optimistix-style RESULTS item array (`RESULTS` below)
    exact: Array
    tolerance: float = eqx.field(static=True)
    num_repaired: int = eqx.field(static=True)
    seconds: float = eqx.field(static=True)
    settings: dict = eqx.field(static=True)

    @property
    def converged(self) -> Array:
        """Boolean (3, res, res, res): the entry reached the tolerance (or is exact)."""
        return self.result._value == RESULTS.successful._value

    @property
    def out_of_reach(self) -> Array:
        """Boolean (3, res, res, res): no sigmoid spectrum reaches the colour (best fit kept)."""
        return self.result._value == RESULTS.out_of_reach._value

    @property
    def tail_free(self) -> Array:
        """Boolean (3, res, res, res): refitted without an infrared tail (`_tails.py`)."""
        return self.result._value == RESULTS.tail_free._value

    def summary(self) -> dict:
        """Residual distribution of the table points and outcome counts (plain Python)."""
        r = np.asarray(self.residual).ravel()
        fitted = ~np.asarray(self.exact).ravel()
        rf = r[fitted]
        q = np.quantile(rf, [0.5, 0.9, 0.99, 0.999, 1.0]) if rf.size else np.zeros(5)
        conv = np.asarray(self.converged).ravel()
        oor = np.asarray(self.out_of_reach).ravel()
        tail = np.asarray(self.tail_free).ravel()
        return {
            "entries": int(r.size),
            "fitted": int(fitted.sum()),
            "closed_form": int((~fitted).sum()),
            "converged": int(conv.sum()),
            "out_of_reach": int(oor.sum()),
            "not_converged": int((~conv & ~oor & ~tail).sum()),
            "tail_free": int(tail.sum()),
            "repaired": self.num_repaired,
            "residual_median": float(q[0]),
            "residual_p90": float(q[1]),
            "residual_p99": float(q[2]),
            "residual_p999": float(q[3]),
            "residual_max": float(q[4]),
            "residual_max_converged": float(np.max(r[conv & fitted], initial=0.0)),
            "tolerance": self.tolerance,
            "seconds": self.seconds,
        }


class RESULTS(optx.RESULTS):
    """Per-entry outcome of `fit_lut`: optimistix's `RESULTS` plus `out_of_reach`.

    `successful`: within the tolerance (or set in closed form);
    `nonlinear_max_steps_reached`: the iteration stopped above the tolerance away from a
    stationary point (a failure; `fit_lut(throw=True)` raises);
    `out_of_reach`: above the tolerance at a stationary point of the least-squares problem:
    no sigmoid-polynomial reflectance in [0, 1] reproduces the colour (wide-gamut spaces have
    colours beyond the object-colour solid), and the entry is the best fit;
    `tail_free`: the fit had converged with an infrared tail, and the entry is the tail stage's
    refit (within `_tails.TAIL_TOLERANCE` of the colour, tail ratio at most
    `_tails.TAIL_RATIO`); an out-of-reach entry that the stage refits stays `out_of_reach`.

    ??? cite "References"
        `Rader2024` (optimistix's `RESULTS`); thesis eq. 2.27.
    """

    out_of_reach = (
        "No spectrum s(c0 l^2 + c1 l + c2) reproduces this colour within the tolerance; the "
        "entry is the least-squares best fit (a stationary point)."
    )
    tail_free = (
        "The fit of this colour has an infrared tail (pbrt-v4 #82); the entry is the tail-free "
        "refit of the tail stage, within its tolerance of the colour (`_tails.py`)."
    )


def _results_array(code: np.ndarray) -> RESULTS:
    """A `RESULTS` array from integer codes 0 (successful), 1 (max steps), 2 (out of reach),
    3 (tail-free refit)."""
    items = [
        RESULTS.successful,
        RESULTS.nonlinear_max_steps_reached,
        RESULTS.out_of_reach,
        RESULTS.tail_free,
    ]
    values = np.asarray([int(it._value) for it in items])[np.asarray(code)]
    # An enumeration item is a pytree whose one leaf is its integer value.
    return jax.tree_util.tree_map(lambda v: jnp.asarray(values, v.dtype), items[0])


def _stationary(c: np.ndarray, targets: np.ndarray, m: ModelArrays, threshold: float = 1e-2):
    """True where the least-squares gradient J^T r is negligible: |J^T r| <= t |J|_F |r|."""
    if c.shape[0] == 0:
        return np.zeros(0, bool)
    size = 1 << int(np.ceil(np.log2(max(c.shape[0], 256))))
    pad = size - c.shape[0]
    cp = np.concatenate([c, np.zeros((pad, 3), c.dtype)])
    tp = np.concatenate([targets, np.full((pad, 3), 0.5, targets.dtype)])
    r, J = _rj_jit(jnp.asarray(cp), jnp.asarray(tp, cp.dtype), m)
    r, J = np.asarray(r, np.float64)[: c.shape[0]], np.asarray(J, np.float64)[: c.shape[0]]
    g = np.einsum("nki,nk->ni", J, r)
    scale = np.sqrt(np.sum(J * J, axis=(1, 2)) * np.sum(r * r, axis=1))
    return np.linalg.norm(g, axis=1) <= threshold * scale


@jax.jit
def _rj_jit(c, rgb, m):
    return residual_and_jacobian(c, target_Lab(rgb, m), m, 512)


class _Schedule(eqx.Module):
    """Iteration limits of the sweep, traced (changing them does not recompile)."""

    n_first: Array  # LM steps (at most) for the cold start at k0
    n_steps: Array  # LM steps (at most) per brightness step
    min_steps: Array  # LM steps (at least) per brightness step
    n_sub: Array  # LM steps (at most) at an intermediate brightness level
    tolerance: Array  # Delta E*ab at which a step may end
    allowed_fraction: Array  # fraction of a block's columns that may miss it

    @staticmethod
    def make(n_first, n_steps, min_steps, n_sub, tolerance, allowed_fraction, dtype):
        i32 = lambda v: jnp.asarray(v, jnp.int32)  # noqa: E731
        return _Schedule(
            i32(n_first), i32(n_steps), i32(min_steps), i32(n_sub),
            jnp.asarray(tolerance, dtype), jnp.asarray(allowed_fraction, dtype),
        )  # fmt: skip


def _sweep_plan(scale: np.ndarray, k0: int, max_ratio: float = 2.0, max_step: float = 0.1):
    """The brightness path of the sweep: values, starts, and which steps are table nodes.

    Order: node k0 (cold, from c = 0), up through k0+1 .. res-1, then down from k0's solution
    through k0-1 .. 1, as pbrt's `rgb2spec_opt`. Where two consecutive nodes are far apart
    (brightness ratio above `max_ratio` or difference above `max_step`, e.g. next to black,
    or everywhere in a coarse table), intermediate brightness levels are inserted
    (geometrically spaced) so each continuation step stays small; without them the warm start
    can fall into a wrong local minimum of eq. 2.27.

    Returns `(z, start, node)` of length T: brightness per step, the start of each step
    (0 = cold, 1 = previous step, 2 = the solution at k0) and the table row it fills (-1 for
    an intermediate level).
    """
    res = scale.shape[0]
    z, start, node = [scale[k0]], [0], [k0]

    def walk(ks, first_start):
        prev = scale[k0]
        for i, k in enumerate(ks):
            target = scale[k]
            ratio = max(target / prev, prev / target)
            m = max(1, int(np.ceil(np.log(ratio) / np.log(max_ratio))))
            m = max(m, int(np.ceil(abs(target - prev) / max_step)))
            levels = np.geomspace(prev, target, m + 1)[1:]
            for j, zz in enumerate(levels):
                z.append(float(zz) if j < m - 1 else float(target))
                start.append(first_start if (i == 0 and j == 0) else 1)
                node.append(k if j == m - 1 else -1)
            prev = target

    walk(list(range(k0 + 1, res)), 1)
    walk(list(range(k0 - 1, 0, -1)), 2)
    return np.asarray(z), np.asarray(start, np.int32), np.asarray(node, np.int32)


def _fit_columns(e, scale, k0, m, schedule: _Schedule):
    """Coefficients (res, n, 3), residuals (res, n) and LM iterations (res,) for one block of
    columns with directions e (n, 3).

    One `lax.scan` along the `_sweep_plan` path: a single compiled Gauss-Newton loop whose
    iteration count adapts to the block (a step ends once all but `allowed_fraction` of the
    block's columns reach the tolerance). Row 0 (black) is a placeholder that the caller sets.
    """
    scale_np = np.asarray(scale, np.float64)
    res = scale_np.shape[0]
    n = e.shape[0]
    dtype = e.dtype
    zs, start, node = _sweep_plan(scale_np, k0)

    def step(carry, xs):
        s_prev, lab_prev, s_k0, lab_k0 = carry
        z, how, is_node = xs
        lab_t = target_Lab(e * z, m)

        a = lm_retarget(s_prev, lab_prev, lab_t)
        b = lm_retarget(s_k0, lab_k0, lab_t)
        cold = lm_init(jnp.zeros((n, 3), dtype))
        s0 = jax.tree_util.tree_map(
            lambda u, v, w: jnp.where(how == 0, w, jnp.where(how == 1, u, v)), a, b, cold
        )
        limit = jnp.where(how == 0, schedule.n_first, schedule.n_steps)
        n_it, s = lm_solve(
            s0,
            lab_t,
            m,
            jnp.where(is_node, limit, schedule.n_sub),
            schedule.tolerance,
            min_steps=jnp.where(is_node, schedule.min_steps, 1),
            allowed_fraction=schedule.allowed_fraction,
        )
        first = how == 0
        s_k0 = jax.tree_util.tree_map(lambda u, v: jnp.where(first, u, v), s, s_k0)
        lab_k0 = jnp.where(first, lab_t, lab_k0)
        return (s, lab_t, s_k0, lab_k0), (s.c, jnp.sqrt(s.cost), n_it)

    # A placeholder state for the carry (replaced at the cold start, step 0).
    zero = jnp.zeros((n, 3), dtype)
    s_dummy = lm_init(zero)
    xs = (jnp.asarray(zs, dtype), jnp.asarray(start), jnp.asarray(node >= 0))
    _, (cs, rs, its) = lax.scan(step, (s_dummy, zero, s_dummy, zero), xs)
    # The node rows, in brightness order 1 .. res-1; row 0 = copy of row 1 (placeholder).
    rows = np.full(res, -1)
    rows[node[node >= 0]] = np.flatnonzero(node >= 0)
    rows = rows[1:]
    coeffs = jnp.concatenate([cs[rows[:1]], cs[rows]], axis=0)
    resid = jnp.concatenate([jnp.zeros_like(rs[:1]), rs[rows]], axis=0)
    it_rows = np.zeros((res, zs.shape[0]))
    next_node = 0
    for t in range(zs.shape[0] - 1, -1, -1):  # intermediate levels count to the next node
        next_node = node[t] if node[t] >= 0 else next_node
        it_rows[next_node, t] = 1.0
    iterations = jnp.asarray(it_rows, dtype) @ its.astype(dtype)
    return coeffs, resid, iterations


def _make_fit_fn(m: ModelArrays, scale, k0, chunk: int, mesh=None):
    """jit-compiled fit `(e (n, 3), schedule) -> (coeffs (res, n, 3), resid (res, n), its)`.

    The columns are processed in blocks of `chunk` by `lax.map` (cache blocking: each block's
    (chunk, n_lambda) arrays stay in cache through the whole sweep, and each block adapts its
    own iteration counts), and with a `mesh` the blocks are sharded over its devices
    (`jax.shard_map` over the column axis).
    """

    def blocks(e, schedule):
        nb = e.shape[0] // chunk
        c, r, it = lax.map(
            lambda eb: _fit_columns(eb, scale, k0, m, schedule), e.reshape(nb, chunk, 3)
        )
        res = scale.shape[0]
        c = jnp.moveaxis(c, 0, 1).reshape(res, nb * chunk, 3)
        r = jnp.moveaxis(r, 0, 1).reshape(res, nb * chunk)
        return c, r, jnp.sum(it, axis=0)

    if mesh is None:
        return jax.jit(blocks)

    def sharded(e, schedule):
        c, r, it = blocks(e, schedule)
        return c, r, jax.lax.psum(it, "columns")

    fn = jax.shard_map(
        sharded,
        mesh=mesh,
        in_specs=(P("columns"), P()),
        out_specs=(P(None, "columns"), P(None, "columns"), P()),
        check_vma=False,  # the loops mix replicated and per-device values; all are per-block
    )
    return jax.jit(fn)


@functools.lru_cache(maxsize=16)
def _cached_fit_fn(colourspace: str, step_nm: float, dtype: str, res: int, chunk: int, device_ids):
    """The compiled column fit for one configuration (cached, so repeated fits skip XLA)."""
    m = ModelArrays.build(forward_model(colourspace, step_nm=step_nm), jnp.dtype(dtype))
    scale = jnp.asarray(brightness_scale(res), dtype)
    mesh = sharding = None
    if device_ids is not None:  # also for one device: the sharded code path, testable anywhere
        by_id = {d.id: d for d in jax.devices()}
        mesh = Mesh(np.asarray([by_id[i] for i in device_ids]), ("columns",))
        sharding = NamedSharding(mesh, P("columns"))
    return _make_fit_fn(m, scale, max(1, res // 5), chunk, mesh), sharding


def _repair(coeffs, resid, e, scale, m, tol, exact, n_steps, rounds, chunk):
    """Refit entries above `tol` from their neighbours along brightness (host-driven rounds,
    after the in-block repair; usually nothing is left for it)."""
    res = scale.shape[0]
    n_repaired = 0
    lm = jax.jit(
        lambda c, lab_t: lm_iterate(lm_init(c), lab_t, m, n_steps + 1, chunk=chunk),
    )
    for _ in range(rounds):
        bad = (resid > tol) & ~exact
        bad[0] = False
        ks, cols = np.nonzero(bad)
        if ks.size == 0:
            break
        n_repaired += ks.size
        # Bucket the batch size to limit recompilations.
        size = 1 << int(np.ceil(np.log2(max(ks.size, 256))))
        targets = np.asarray(e)[cols] * np.asarray(scale)[ks][:, None]
        best_c = coeffs[ks, cols].copy()
        best_r = resid[ks, cols].copy()
        starts = [coeffs[np.clip(ks + d, 1, res - 1), cols] for d in (-1, 1, -2, 2)]
        starts.append(np.zeros_like(best_c))
        starts.append(best_c)
        for c_start in starts:
            pad = size - ks.size
            cp = np.concatenate([c_start, np.zeros((pad, 3), c_start.dtype)])
            tp = np.concatenate([targets, np.full((pad, 3), 0.5, targets.dtype)])
            lab_t = target_Lab(jnp.asarray(tp, coeffs.dtype), m)
            st: LMState = lm(jnp.asarray(cp, coeffs.dtype), lab_t)
            c_new = np.asarray(st.c)[: ks.size]
            r_new = np.sqrt(np.asarray(st.cost))[: ks.size]
            better = r_new < best_r
            best_c[better] = c_new[better]
            best_r[better] = r_new[better]
            if np.all(best_r <= tol):
                break
        coeffs[ks, cols] = best_c
        resid[ks, cols] = best_r
    return coeffs, resid, n_repaired


def fit_lut(
    colourspace="sRGB",
    resolution: int = 64,
    *,
    dtype=jnp.float32,
    tolerance: float = DEFAULT_TOLERANCE,
    n_first: int = 60,
    n_steps: int = 40,
    min_steps: int = 2,
    n_sub: int = 3,
    allowed_fraction: float = 0.0,
    retry_steps: int = 60,
    repair_steps: int = 60,
    repair_rounds: int = 3,
    chunk: int = 512,
    blocks_per_call: int = 2,
    step_nm: float = 1.0,
    devices=None,
    progress=None,
    throw: bool = True,
    infrared_tails: bool = True,
) -> LUTFitResult:
    r"""Fit the coefficient table of an RGB colour space (thesis eq. 2.27, section 2.2.3).

    See the module docstring for the layout, the sweep along brightness and the explicit
    black / grey / white entries. The work is vectorised over the 3 res^2 columns of the table
    in cache-sized blocks and, with `devices`, sharded over them (`jax.shard_map` over the
    flattened column axis; e.g. `devices=jax.devices()` after
    `XLA_FLAGS=--xla_force_host_platform_device_count=2` runs a 2-core CPU as two devices).

    Stages: (1) the sweep, every column; a brightness step ends once all but
    `allowed_fraction` of its block's columns are within `tolerance / 10`, or after `n_steps`
    iterations; (2) the columns with an entry above `tolerance` are swept again with up to
    `retry_steps` iterations per step and no early exit (the same compiled function), keeping
    the better entry; (3) whatever is still above `tolerance` is refitted from its neighbours
    along brightness (`repair_rounds` rounds of `repair_steps` iterations; rarely needed);
    (4) with `infrared_tails`, entries whose reflectance has an infrared tail are refitted
    without it where that keeps the colour within `_tails.TAIL_TOLERANCE`
    (`_tails.suppress_infrared_tails`: pbrt-v4 #82, the darkest reds).

    **Arguments:**

    - `colourspace`: a space of `colorimetry.RGB_COLOURSPACES` (name or alias).
    - `resolution`: table size per axis, >= 2 (pbrt and Mitsuba use 64).
    - `dtype`: working and storage dtype (float32 default; float64 for reference fits).
    - `tolerance`: per-entry convergence criterion on $\Delta E^*_{ab}$ (the float32 floor
        is about 2e-3 next to white). [-]
    - `n_first`, `n_steps`, `min_steps`, `allowed_fraction`, `retry_steps`, `repair_steps`,
        `repair_rounds`: iteration limits of the stages above; `n_sub`: iterations at the
        intermediate brightness levels the sweep inserts between distant nodes.
    - `chunk`: table columns per vectorised block (cache blocking); `blocks_per_call`:
        blocks per device per compiled call (the granularity of `progress`).
    - `step_nm`: quadrature step of the forward model (1 nm default). [nm]
    - `devices`: sequence of devices to shard the columns over (None: default device).
    - `progress`: optional callable `progress(stage: str, done: int, total: int)`.
    - `throw`: raise `RuntimeError` if an entry misses the tolerance at the end.
    - `infrared_tails`: run stage (4) (default; False gives the colour-only table, as pbrt's).

    **Returns:**

    A `LUTFitResult` (table, per-entry residual and `optimistix.RESULTS`, timings).

    **Colours no reflectance has.** A reflectance is at most 1 at every wavelength, so its
    colour lies in the object-colour solid (bounded by the Rösch-MacAdam optimal colours);
    the bright saturated corners of a wide-gamut cube (Rec.2020, ACEScg, ProPhoto) lie outside
    it, and no spectrum at all reproduces them. For such an entry the sweep ends at a
    stationary point of eq. 2.27 above `tolerance`; it is kept as the entry (the least-squares
    best fit the continuation reached: a sigmoid spectrum, hence in [0, 1], whose colour is
    the closest in $\Delta E^*_{ab}$ that the fit found, a local minimum) and reported as
    `RESULTS.out_of_reach` (`LUTFitResult.out_of_reach`, `summary()["out_of_reach"]`), which is
    not a failure for `throw`. Entries above `tolerance` away from a stationary point are
    `nonlinear_max_steps_reached`. `_roundtrip.object_colour_scale` says independently
    which colours have a reflectance.

    !!! note "Thesis"
        Eq. 2.25-2.27 and the lookup table of section 2.2.3; Gauss-Newton, appendix C.1.

    ??? cite "References"
        `Jakob2019` section 5; `Pharr2023` section 4.6.6 (`rgb2spec_opt`); `Levenberg1944`,
        `Marquardt1963` (damping); `Bjorck1967` (the least-squares step by Gram-Schmidt).
    """
    t_start = time.perf_counter()
    res = check_positive_int(resolution, "resolution", minimum=2)
    model = forward_model(colourspace, step_nm=step_nm)
    dtype = jnp.dtype(dtype)
    if dtype not in (jnp.dtype(jnp.float32), jnp.dtype(jnp.float64)):
        raise TypeError(f"`dtype` must be float32 or float64, got {dtype}.")
    if dtype == jnp.dtype(jnp.float64) and not jax.config.jax_enable_x64:
        raise ValueError("`dtype=float64` needs `jax.config.update('jax_enable_x64', True)`.")
    m = ModelArrays.build(model, dtype)
    scale_np = brightness_scale(res)
    k0 = max(1, res // 5)
    e_np = column_directions(res, np.float64)
    n_cols = e_np.shape[0]
    n_dev = 1 if devices is None else len(devices)
    chunk = min(check_positive_int(chunk, "chunk"), -(-n_cols // n_dev))
    blocks_per_call = check_positive_int(blocks_per_call, "blocks_per_call")
    device_ids = None if devices is None else tuple(d.id for d in devices)
    fit_fn, sharding = _cached_fit_fn(
        model.colourspace, step_nm, dtype.name, res, chunk, device_ids
    )
    per_call = n_dev * chunk * blocks_per_call
    sweep_tol = tolerance / 10

    def run(cols: np.ndarray, schedule: _Schedule, stage: str):
        """Sweep the columns `cols` in calls of `per_call` columns (padded by repetition)."""
        n_calls = -(-cols.size // per_call)
        idx = np.resize(cols, n_calls * per_call) if cols.size else cols
        out_c = np.empty((res, n_calls * per_call, 3), dtype)
        out_r = np.empty((res, n_calls * per_call), dtype)
        its = np.zeros(res, np.float64)
        for i in range(n_calls):
            sl = slice(i * per_call, (i + 1) * per_call)
            e = jnp.asarray(e_np[idx[sl]], dtype)
            if sharding is not None:
                e = jax.device_put(e, sharding)
            c, r, it = fit_fn(e, schedule)
            out_c[:, sl], out_r[:, sl] = np.asarray(c), np.asarray(r)
            its += np.asarray(it)
            if progress is not None:
                progress(stage, min((i + 1) * per_call, cols.size), cols.size)
        return out_c[:, : cols.size], out_r[:, : cols.size], its

    # (1) The sweep.
    sched = _Schedule.make(n_first, n_steps, min_steps, n_sub, sweep_tol, allowed_fraction, dtype)
    coeffs, resid, iterations = run(np.arange(n_cols), sched, "sweep")
    # Explicit entries: greys (closed form), white (finite), black row (copy of row 1, later).
    exact = np.zeros((res, n_cols), dtype=bool)
    exact[0] = True
    grey_cols = np.flatnonzero((e_np[:, 0] == 1) & (e_np[:, 1] == 1) & (e_np[:, 2] == 1))
    with np.errstate(divide="ignore"):
        v = scale_np
        g = np.zeros((res, 3))
        g[:, 2] = (v - 0.5) / np.sqrt(v * (1.0 - v))  # closed form; -inf at black
    g[0, 2] = -np.inf  # (row 0 is overwritten by row 1 below)
    g[-1, 2] = WHITE_C2
    coeffs[:, grey_cols] = g[:, None, :]
    resid[:, grey_cols] = 0.0
    exact[:, grey_cols] = True
    resid[0] = 0.0
    # (2) Retry the columns with an entry above the tolerance, with more iterations.
    bad = (resid > tolerance) & ~exact
    ks, cols = np.nonzero(bad)
    targets = e_np[cols] * scale_np[ks][:, None]
    stationary = np.zeros_like(bad)
    stationary[ks, cols] = _stationary(coeffs[ks, cols], targets, m)
    bad_cols = np.flatnonzero((bad & ~stationary).any(axis=0))
    n_retried = int(bad_cols.size)
    if bad_cols.size:
        sched2 = _Schedule.make(
            2 * n_first, retry_steps, min_steps, retry_steps, sweep_tol, 0.0, dtype
        )
        c2, r2, it2 = run(bad_cols, sched2, "retry")
        iterations += it2
        better = (r2 < resid[:, bad_cols]) & ~exact[:, bad_cols]
        sub_c, sub_r = coeffs[:, bad_cols], resid[:, bad_cols]
        sub_c[better], sub_r[better] = c2[better], r2[better]
        coeffs[:, bad_cols], resid[:, bad_cols] = sub_c, sub_r
    # (3) Host-side repair from neighbours for what is left.
    coeffs, resid, n_repaired = _repair(
        coeffs, resid, e_np.astype(dtype), scale_np.astype(dtype), m, tolerance,
        exact | stationary, repair_steps, repair_rounds, None,
    )  # fmt: skip
    # Classify what is left: stationary (out of reach) or not.
    bad = (resid > tolerance) & ~exact
    ks, cols = np.nonzero(bad)
    stationary = np.zeros_like(bad)
    stationary[ks, cols] = _stationary(coeffs[ks, cols], e_np[cols] * scale_np[ks][:, None], m)
    if progress is not None:
        progress("repair", 1, 1)
    coeffs[0] = coeffs[1]

    coeffs_nm = _normalised_to_nm_np(np.asarray(coeffs, np.float64)).astype(dtype)
    # (res_k, 3 * res_j * res_i, 3) -> (3, res_k, res_j, res_i, 3)
    table = coeffs_nm.reshape(res, 3, res, res, 3).transpose(1, 0, 2, 3, 4)
    resid_t = resid.reshape(res, 3, res, res).transpose(1, 0, 2, 3)
    exact_t = exact.reshape(res, 3, res, res).transpose(1, 0, 2, 3)
    stat_t = stationary.reshape(res, 3, res, res).transpose(1, 0, 2, 3)
    ok = (resid_t <= tolerance) | exact_t
    code = np.where(ok, 0, np.where(stat_t, 2, 1))
    # (4) The infrared-tail stage, on the finished table (`_tails.py`).
    tail_report = "off"
    if infrared_tails:
        stage = suppress_infrared_tails(table, scale_np, model.colourspace, progress=progress)
        table = stage.coeffs
        resid_t = np.where(stage.replaced, stage.residual, resid_t).astype(resid_t.dtype)
        # A converged entry becomes `tail_free`; an out-of-reach one stays out of reach (its
        # colour is still beyond the family; the refit is its tail-free approximation).
        code = np.where(stage.replaced & (code == 0), 3, code)
        tail_report = stage.report
    result = _results_array(code)
    # Entries no reflectance reaches: this table's lookups are refined by the fit (`_lut.py`).
    refine = REFINE_STEPS if bool(np.any(code == 2)) else 0
    lut = RGBToSpectrumLUT(
        jnp.asarray(scale_np, dtype), jnp.asarray(table), model.colourspace, refine
    )
    settings = {
        **model.description(),
        "resolution": res,
        "dtype": str(dtype),
        "tolerance_delta_E_ab": tolerance,
        "solver": "damped Gauss-Newton (Levenberg-Marquardt), exact JAX Jacobian",
        "n_first": n_first,
        "n_steps": n_steps,
        "min_steps": min_steps,
        "n_sub": n_sub,
        "allowed_fraction": allowed_fraction,
        "retry_steps": retry_steps,
        "repair_steps": repair_steps,
        "chunk": chunk,
        "columns_retried": n_retried,
        "lm_iterations_per_block": float(iterations.sum() / max(1, -(-n_cols // chunk))),
        "repair_rounds": repair_rounds,
        "start_index": k0,
        "white_c2": WHITE_C2,
        "infrared_tails": tail_report,
    }
    out = LUTFitResult(
        lut=lut,
        residual=jnp.asarray(resid_t),
        result=result,
        exact=jnp.asarray(exact_t),
        tolerance=float(tolerance),
        num_repaired=int(n_repaired),
        seconds=time.perf_counter() - t_start,
        settings=settings,
    )
    failed = code == 1
    if throw and failed.any():
        worst = np.unravel_index(np.argmax(np.where(failed, resid_t, -np.inf)), resid_t.shape)
        raise RuntimeError(
            f"fit_lut({model.colourspace!r}, {res}): {int(failed.sum())} entries stopped above "
            f"Delta E*ab = {tolerance} away from a stationary point; worst at index "
            f"{tuple(int(w) for w in worst)} with residual {float(resid_t[worst]):.3g}. Pass "
            "throw=False to inspect `result` and `residual`."
        )
    return out
