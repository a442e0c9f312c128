r"""A heterogeneous medium on a voxel grid (thesis ch. 4; Mitsuba 3's `heterogeneous` medium).

The extinction is a density grid times a spectrum,
$\sigma_{t,j}(\mathbf x) = d(\mathbf x)\,s_j$, and the albedo an optional grid times a
spectrum, $\varrho_j(\mathbf x) = a(\mathbf x)\,r_j$. The grids live in the unit box
$[0, 1]^3$ of the grid's local frame, which `to_world` (4x4, affine) places in the scene;
outside the box the medium is empty (as in Mitsuba, whose heterogeneous medium clips rays to
the grid's bounding box). Lookups are trilinear between voxel centres, the voxel
$(i_x, i_y, i_z)$ of an $X\times Y\times Z$ grid being centred at
$((i_x + \frac12)/X, (i_y + \frac12)/Y, (i_z + \frac12)/Z)$, clamped to the outermost centres
towards the faces (Mitsuba 3's `gridvolume` with `filter_type="trilinear"`, which looks the
grid up as a clamped texture).

**Majorant grid.** The box is split into a coarse grid of cells (`coarse_majorant_grid`:
about 2 voxels a cell, at most $16^3$ cells, as pbrt-v4's `MajorantGrid`), each holding the
largest and smallest density its trilinear lookups can return, $\bar d_c$ and $\underline d_c$
(the extreme voxels of the cell's interpolation support: conservative bounds). A ray walks the
cells it crosses with a 3-D DDA (`Amanatides1987`) and draws tentative collisions at the
piecewise-constant grey rate $\bar\mu_c = \bar d_c \max_j s_j$ of the cell it is in: an
exponential optical depth is used up cell by cell, so crossing a cell costs no density
lookup, and empty cells ($\bar d_c = 0$) are skipped outright. A one-cell grid
(`majorant_resolution=1`, or a traced density) is the global majorant
$\max d\cdot\max_j s_j$. Tentative collisions are drawn only on the part of a segment inside
the box.

**Free flight (spectral tracking).** At a tentative collision $\mathbf x$ the walk stops with
probability $P = d(\mathbf x)\,\bar s/\bar\mu$ ($\bar s$ the mean of $s_j$ over the path's
wavelengths), multiplying the weight of every wavelength by
$\sigma_{s,j}/(\bar\mu P) = \varrho_j(\mathbf x)\,s_j/\bar s$; otherwise it passes a null
collision and multiplies it by $(\bar\mu - \sigma_{t,j})/(\bar\mu (1 - P))$. Past the segment
the weight is the product of the null factors. This is Kutz et al.'s spectral tracking with a
grey collision probability (`Kutz2017`; `Novak2018` §4): unbiased at every wavelength, with
exactly the weight convention of `HomogeneousMedium` ($E[w_j 1_{event} f(t)] =
\int_0^{t_{max}} \sigma_{s,j}T_j f\,\mathrm dt$, $E[w_j 1_{no\ event}] = T_j(t_{max})$), and
for a grey medium it is delta tracking with the weight $\varrho$ at an event and 1 otherwise.

**Transmittance** is estimated by residual ratio tracking about the per-cell control
extinction $\sigma_{c,j} = \underline d_c s_j$, with the cell's rate
$\bar\mu_{r,c} = (\bar d_c - \underline d_c)\max_j s_j$:
$\hat T_j = e^{-\int\sigma_{c,j}\,\mathrm dt}\prod_i (1 - (\sigma_{t,j}(\mathbf x_i) -
\sigma_{c,j})/\bar\mu_{r,c})$ (`Novak2014`; the control's optical depth is summed exactly
over the cells crossed); a constant grid gets the exact transmittance, as a homogeneous medium
does, and so does every cell of constant density. Once a path's estimate (the product so far
times the control's transmittance so far, largest over the wavelengths) falls below 0.2, each
further collision plays Russian roulette: the walk ends with probability 0.75 (estimate 0) or
goes on with its weight divided by 0.25 (pbrt-v4's shadow rays do so below 0.05, `Pharr2023`
§14.2.2), which keeps it unbiased and ends the long walks through dense regions early. On the
`bench_media.py` heterogeneous scene (256 x 256, 64 spp) the render took 17.8 s without it,
15.0 s below 0.05, 13.5 s below 0.2 and 12.6 s below 0.5, with relMSE 1.254e-2, 1.256e-2,
1.278e-2 and 1.361e-2: 0.2 gives about the time to equal error of 0.5 with a quarter of its
added variance.

**Variates.** The interface hands one variate per path (`u[:, 0]`, with `u[:, 1]` mixed in
where given); the tracking steps draw theirs (the optical depth to the next collision, and
the real-or-null or roulette decision) from the hash `pcg4d` of those variates and the
step number (`Jarzynski2020`), so the same `u` gives the same result.

**Loop.** The walks run in `lax.while_loop`s until every path has left its segment (no step
cap biases them). Each path crosses its cells on its own and waits at its tentative collisions;
an iteration either moves every path that is not waiting by one cell (or to its collision in
that cell) or, once half of the active paths wait (or all of them), evaluates their collisions
together (a density lookup, dearer than a cell crossing). Walks differ much in length, and an
iteration costs every lane of the loop, so once at most an eighth of the lanes' paths are
still walking, those are gathered into an eighth as many lanes and a new loop goes on with
them, down to 32 lanes (`_staged_loop`: a chunk of 2048 paths walks in loops of 2048, 256 and
32 lanes). Each path does the same steps with the same variates whatever the grouping, so the
estimates are the same. On random walks through `bench_media.py`'s grid, lanes in one loop of
256 were busy 26 % (free flights) and 31 % (transmittances) of the iterations; loops of 2048,
256 and 32 lanes do 1.9x and 1.6x fewer lane-iterations than loops of 256, and halving
stages down to 16 lanes 3.2x and 2.3x, but each loop size is compiled anew (7 sizes: about
20 s more compile time for a scene's first render; 3 sizes: about 5 s). `bench_media.py`'s
heterogeneous scene (256 x 256, 16 spp, two CPU devices, warm, alternating runs) took
4.2-4.8 s against 5.9-7.2 s with one loop per walk in chunks of 256 paths, the same image.
With the command line's XLA flags (`radiometria.cli.cpu_xla_flags`) XLA:CPU compiles each of
these loops into a single function.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array, Float

from .._bits import pcg4d, uint32_to_unit_float
from .._checks import as_float_array
from .._math import compact_indices, safe_div
from ._medium import AbstractMedium, MediumInteraction
from ._phase import AbstractPhaseFunction
from ._validation import check_coefficient

__all__ = [
    "GridMedium",
    "coarse_majorant_grid",
    "default_majorant_resolution",
    "trilinear_lookup",
]


_ONE_GATHER_VOXELS = 32**3  # `trilinear_lookup` reads larger grids by one gather


def trilinear_lookup(grid: Float[Array, "z y x"], p: Float[Array, "n 3"]) -> Float[Array, " n"]:
    r"""Trilinear interpolation of a voxel grid at local points in $[0, 1]^3$ (module
    docstring: voxel centres at $(i + \frac12)/N$, clamped towards the faces); 0 outside the
    box.

    **Arguments:**

    - `grid`: voxel values `(Z, Y, X)` (x fastest, as in Mitsuba's `.vol` files). [any]
    - `p`: points `(n, 3)` in the grid's local frame, `(x, y, z)`. [1]

    **Returns:**

    Interpolated values `(n,)`, in the grid's unit. [any]

    ??? cite "References"
        `Jakob2022` (`gridvolume`); `Pharr2023` §11.4.3.
    """
    nz, ny, nx = grid.shape
    shape = jnp.asarray((nx, ny, nz), p.dtype)[None, :]  # (1, 3): X, Y, Z
    inside = jnp.all((p >= 0) & (p <= 1), axis=-1)
    f = jnp.clip(p * shape - 0.5, 0.0, shape - 1)
    i0 = jnp.floor(f).astype(jnp.int32)
    i1 = jnp.minimum(i0 + 1, jnp.asarray((nx, ny, nz), jnp.int32)[None, :] - 1)
    a = f - i0.astype(p.dtype)
    # The 8 corners' flat indices (z-major, as the grid is stored) and weights. A grid of more
    # than _ONE_GATHER_VOXELS is read by one gather of all 8 corners, (n, 8): XLA's cost
    # analysis then counts the grid once rather than once per corner, which keeps the tracking
    # loops of a 64^3 grid small enough for XLA:CPU to compile into single functions
    # (`radiometria.cli.cpu_xla_flags`): 0.83 s against 1.30 s for `bench_media.py`'s
    # heterogeneous scene with a 64^3 grid (128 x 128, 16 spp, warm). A smaller grid is read
    # corner by corner, which is faster there (16^3: 0.67 s against 0.74 s).
    g = grid.astype(p.dtype)
    corners = []  # (iz, iy, ix, weight) of the 8 corners
    for cz in (0, 1):
        iz = i1[:, 2] if cz else i0[:, 2]
        wz = a[:, 2] if cz else 1.0 - a[:, 2]
        for cy in (0, 1):
            iy = i1[:, 1] if cy else i0[:, 1]
            wy = a[:, 1] if cy else 1.0 - a[:, 1]
            for cx in (0, 1):
                ix = i1[:, 0] if cx else i0[:, 0]
                corners.append((iz, iy, ix, wz * wy * (a[:, 0] if cx else 1.0 - a[:, 0])))
    if grid.size > _ONE_GATHER_VOXELS:
        index = jnp.stack([(iz * ny + iy) * nx + ix for iz, iy, ix, _ in corners], axis=-1)
        values = g.reshape(-1).at[index].get(mode="promise_in_bounds")  # clamped above
        out = jnp.sum(jnp.stack([w for *_, w in corners], axis=-1) * values, axis=-1)
    else:
        out = sum(w * g[iz, iy, ix] for iz, iy, ix, w in corners)
    return jnp.where(inside, out, 0.0)


def _affine(m: Array, p: Array) -> Array:
    return p @ m[:3, :3].T + m[None, :3, 3]


def _box_interval(o_l: Array, w_l: Array) -> tuple[Array, Array]:
    """Parameter interval `(t0, t1)` of rays `o_l + t w_l` inside the unit box (empty: t0 > t1)."""
    safe = jnp.where(jnp.abs(w_l) > 0, w_l, 1.0)
    ta = (0.0 - o_l) / safe
    tb = (1.0 - o_l) / safe
    lo = jnp.where(jnp.abs(w_l) > 0, jnp.minimum(ta, tb), jnp.where((o_l >= 0) & (o_l <= 1),
                   -jnp.inf, jnp.inf))  # fmt: skip
    hi = jnp.where(jnp.abs(w_l) > 0, jnp.maximum(ta, tb), jnp.where((o_l >= 0) & (o_l <= 1),
                   jnp.inf, -jnp.inf))  # fmt: skip
    return jnp.max(lo, axis=-1), jnp.min(hi, axis=-1)


def _range_reduce(a: np.ndarray, axis: int, lo: np.ndarray, hi: np.ndarray, ufunc, fill):
    """`ufunc` (np.maximum / np.minimum) of `a` over the index ranges `[lo[c], hi[c]]` along
    `axis`, one result per `c` (ranges may overlap: interleaved `reduceat` indices)."""
    pad = [(0, 0)] * a.ndim
    pad[axis] = (0, 1)
    a = np.pad(a, pad, constant_values=fill)
    idx = np.stack([lo, hi + 1], axis=-1).ravel()
    return np.take(ufunc.reduceat(a, idx, axis=axis), np.arange(0, idx.size, 2), axis=axis)


def default_majorant_resolution(shape: tuple[int, int, int]) -> tuple[int, int, int]:
    """The coarse majorant grid's cells for a density grid: about 2 voxels per cell, at most
    16 per axis (`Pharr2023` uses 16^3). On `benchmarks/bench_media.py`'s 16^3 grid, 4^3 to
    16^3 cells render 1.6-2.2x faster than one cell (the global majorant), the three within
    the noise of a loaded 2-core machine.

    **Arguments:**

    - `shape`: the density grid's voxels `(Z, Y, X)`. [1]

    **Returns:**

    The cells `(Rz, Ry, Rx)`, each in [1, 16]. [1]
    """
    return tuple(int(min(16, max(1, -(-n // 2)))) for n in shape)


def coarse_majorant_grid(
    density, resolution: tuple[int, int, int] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    r"""Per-cell bounds `(max, min)` of the trilinear density over a coarse grid of cells.

    The unit box is split into $R_z\times R_y\times R_x$ equal cells; cell $c$ along an axis of
    $N$ voxels spans $[c/R, (c+1)/R]$, where the trilinear lookup (`trilinear_lookup`) touches
    the voxels $\lfloor cN/R - \frac12 \rfloor$ to $\lfloor (c+1)N/R - \frac12 \rfloor + 1$
    (clamped). A trilinear value is a convex combination of its corner voxels, so the maximum
    (minimum) of those voxels bounds the density everywhere in the cell from above (below):
    the bounds are conservative, never just sampled.

    **Arguments:**

    - `density`: concrete voxel grid `(Z, Y, X)`. [1]
    - `resolution`: cells `(Rz, Ry, Rx)`, each >= 1 (default `default_majorant_resolution`).

    **Returns:**

    `(max_grid, min_grid)`, NumPy arrays of shape `(Rz, Ry, Rx)`. [1]

    ??? cite "References"
        `Pharr2023` §11.4.3 (`MajorantGrid`); `Novak2014` §4 (per-region majorants).
    """
    d = np.asarray(density, np.float64)
    res = default_majorant_resolution(d.shape) if resolution is None else tuple(resolution)
    if len(res) != 3 or any(int(r) != r or r < 1 for r in res):
        raise ValueError(f"`resolution` must be three integers >= 1, got {resolution!r}.")
    hi_d, lo_d = d, d
    for axis, (n, r) in enumerate(zip(d.shape, res, strict=True)):
        c = np.arange(int(r))
        lo = np.clip((2 * c * n - r) // (2 * r), 0, n - 1)
        hi = np.clip((2 * (c + 1) * n - r) // (2 * r) + 1, 0, n - 1)
        hi_d = _range_reduce(hi_d, axis, lo, hi, np.maximum, -np.inf)
        lo_d = _range_reduce(lo_d, axis, lo, hi, np.minimum, np.inf)
    return hi_d, lo_d


_RR_BELOW = 0.2  # transmittance estimates below this play Russian roulette (module docstring)
_RR_END = 0.75  # ... and end with this probability


def _uniforms(u: Array, step, n_out: int) -> Array:
    """`(n, n_out)` uniforms hashed from the variates `u (n, d)` and a step number."""
    scale = 4294967296.0
    a = (jnp.clip(u[:, 0], 0.0, 1.0 - 1e-7).astype(jnp.float32) * scale).astype(jnp.uint32)
    if u.shape[1] > 1:
        b = (jnp.clip(u[:, 1], 0.0, 1.0 - 1e-7).astype(jnp.float32) * scale).astype(jnp.uint32)
    else:
        b = jnp.full_like(a, 0x27D4EB2F)
    s = jnp.broadcast_to(jnp.asarray(step).astype(jnp.uint32), a.shape)
    words = pcg4d(a, b, s, jnp.full_like(a, 0x165667B1))
    return uint32_to_unit_float(words[..., :n_out], u.dtype)


def _check(x, name: str, **kw) -> Array:
    """`check_coefficient` for concrete values; traced values (a renderer plugin's rows,
    checked when the plugin was built) pass unchecked to keep the tracer's loop free of
    runtime checks."""
    if isinstance(x, jax.core.Tracer):
        return x
    return check_coefficient(x, name, **kw)


class _Track(eqx.Module):
    """Where each path's walk through the majorant cells stands (`GridMedium._walk`)."""

    t: Array  # (n,) distance along the ray [scene units]
    cell: Array  # (n, 3) int32 majorant cell (x, y, z)
    tau: Array  # (n,) optical depth left before the next tentative collision
    v: Array  # (n,) the variate deciding that collision
    step: Array  # (n,) uint32 tentative collisions so far (the hash's step number)
    ctrl: Array  # (n,) the control density times length so far (ratio tracking)
    active: Array  # (n,) bool: still walking
    waiting: Array  # (n,) bool: at a tentative collision not yet evaluated
    scattered: Array  # (n,) bool: a real collision (spectral tracking)
    weight: Array  # (n, k)


class _Ray(eqx.Module):
    """What each path's walk keeps fixed (`GridMedium._walk`), in the scene (`o`, `d`) and
    the grid's local frame (`o_l`, `w_l`, `safe_w`: `w_l` with zeros replaced by 1)."""

    o: Array  # (n, 3)
    d: Array  # (n, 3)
    o_l: Array  # (n, 3)
    w_l: Array  # (n, 3)
    safe_w: Array  # (n, 3)
    stop: Array  # (n,) where the walk ends [scene units]
    u: Array  # (n, d) the variates
    s: Array  # (n, k) extinction spectrum
    r: Array  # (n, k) albedo spectrum
    s_max: Array  # (n,)


_STAGE_FACTOR = 8  # `_staged_loop`: lanes shrink by this factor per stage ...
_STAGE_MIN = 32  # ... down to this many


def _staged_loop(body, ray: _Ray, track: _Track) -> _Track:
    """Run `body(ray, track)` until no path is active, compacting the active paths into
    fewer lanes as they finish (module docstring, "Loop").

    A loop over `n` lanes runs until its longest walk ends, every iteration costing all `n`
    lanes. Here the loop stops once at most `n / _STAGE_FACTOR` paths are active; those are gathered
    into that many lanes (`_math.compact_indices`: `jnp.nonzero` with a static size), the next loop
    goes on with them, down to `_STAGE_MIN` lanes, and the results are scattered back. Each path
    does the same steps with the same variates in either case (only when a group's tentative
    collisions are evaluated differs), so the estimates are the same. The gathers and
    scatters sit between the loops, which stay free of scatters and custom calls, so
    XLA:CPU still compiles each loop into one function (`radiometria.cli.cpu_xla_flags`)."""
    n = track.active.shape[0]
    size = n // _STAGE_FACTOR
    floor = size if size >= _STAGE_MIN else 0

    def cond(c):
        a = jnp.sum(c.active, dtype=jnp.int32)
        return (a > floor) & (a > 0)

    track = lax.while_loop(cond, lambda c: body(ray, c), track)
    if floor == 0:
        return track
    idx = compact_indices(track.active, size, n)

    def take(x):
        return jnp.take(x, idx, axis=0, mode="clip")

    sub = jax.tree.map(take, track)
    sub = eqx.tree_at(lambda c: c.active, sub, sub.active & (idx < n))
    sub = _staged_loop(body, jax.tree.map(take, ray), sub)
    return jax.tree.map(lambda a, b: a.at[idx].set(b, mode="drop"), track, sub)


class GridMedium(AbstractMedium):
    r"""A heterogeneous medium: density and albedo grids in a box placed by `to_world`
    (module docstring), at a batch of paths' wavelengths.

    **Arguments:**

    - `density`: the extinction's shape $d$, voxels `(Z, Y, X)`, finite and >= 0 (x
        fastest in memory, as in Mitsuba's `.vol` files). [1]
    - `sigma_t`: the extinction spectrum $s_j$ at the paths' wavelengths: scalar, `(k,)` or
        `(n, k)`, finite and >= 0; $\sigma_t = d\,s$. [scene units^-1]
    - `albedo`: the albedo spectrum $r_j$, scalar, `(k,)` or `(n, k)`, in [0, 1]. [1]
    - `phase`: the phase function, an `AbstractPhaseFunction`.
    - `to_world`: 4x4 affine matrix from the grid's local box $[0, 1]^3$ to the scene
        (default: identity). [scene units]
    - `albedo_grid`: an optional grid $a$ `(Z', Y', X')` in [0, 1] multiplying the albedo.
        [1]
    - `max_density`: $\max d$ if already known (default: computed). [1]
    - `to_local`: the inverse of `to_world`, given instead of it (keyword-only). [1/scene
        units]
    - `min_density`: $\min d$ if already known (keyword-only; default: computed). [1]

    Concrete arguments are checked (`ValueError` naming the argument); traced ones are not.

    ```python
    smoke = GridMedium(density=d, sigma_t=jnp.array([2.0, 2.5, 3.0, 3.5]), albedo=0.9,
                       phase=HenyeyGreenstein(0.2), to_world=jnp.diag(jnp.array([2, 2, 2, 1.])))
    T = smoke.transmittance(o, w, t_max, wavelength_nm, u)   # ratio tracking, (n, 4)
    ```

    !!! note "Thesis"
        Chapter 4 (energy transport in a medium; title only in the text) and eq. (1.12).

    ??? cite "References"
        `Jakob2022` (`heterogeneous`, `gridvolume`); `Kutz2017` (spectral tracking);
        `Novak2014` (ratio tracking); `Woodcock1965`; `Pharr2023` §11.4.
    """

    density: Float[Array, "z y x"]
    sigma_t: Float[Array, "..."]
    albedo: Float[Array, "..."]
    phase: AbstractPhaseFunction
    to_local: Float[Array, "4 4"]
    albedo_grid: Float[Array, "z2 y2 x2"] | None
    max_density: Float[Array, ""]
    min_density: Float[Array, ""]
    majorant_grid: Float[Array, "rz ry rx"]
    minorant_grid: Float[Array, "rz ry rx"]

    def __init__(
        self,
        density,
        sigma_t,
        albedo,
        phase: AbstractPhaseFunction,
        to_world=None,
        albedo_grid=None,
        max_density=None,
        *,
        to_local=None,
        min_density=None,
        majorant_resolution=None,
        majorant_grid=None,
        minorant_grid=None,
    ):
        if not isinstance(phase, AbstractPhaseFunction):
            raise TypeError(
                f"`phase` must be an AbstractPhaseFunction, got {type(phase).__name__}."
            )
        density = _check(density, "density")
        if density.ndim != 3 or min(density.shape) < 1:
            raise ValueError(f"`density` must be a (Z, Y, X) grid, got shape {density.shape}.")
        if albedo_grid is not None:
            albedo_grid = _check(albedo_grid, "albedo_grid", upper=1.0)
            if albedo_grid.ndim != 3:
                raise ValueError(
                    f"`albedo_grid` must be a (Z, Y, X) grid, got shape {albedo_grid.shape}."
                )
        m = np.eye(4) if to_world is None else to_world
        if to_local is not None:
            to_local = jnp.asarray(to_local)
        elif isinstance(m, jax.core.Tracer):
            to_local = jnp.linalg.inv(m)
        else:
            m = np.asarray(m, np.float64)
            if m.shape != (4, 4) or not np.all(np.isfinite(m)):
                raise ValueError(f"`to_world` must be a finite 4x4 matrix, got {m.shape}.")
            if abs(np.linalg.det(m[:3, :3])) < 1e-12:
                raise ValueError("`to_world` must be invertible (its 3x3 part is singular).")
            to_local = jnp.asarray(np.linalg.inv(m))
        self.density = density
        self.sigma_t = _check(sigma_t, "sigma_t", unit="scene units^-1")
        self.albedo = _check(albedo, "albedo", upper=1.0)
        self.phase = phase
        self.to_local = to_local
        self.albedo_grid = albedo_grid
        self.max_density = jnp.max(density) if max_density is None else jnp.asarray(max_density)
        self.min_density = jnp.min(density) if min_density is None else jnp.asarray(min_density)
        if (majorant_grid is None) != (minorant_grid is None):
            raise ValueError("give both `majorant_grid` and `minorant_grid`, or neither.")
        if majorant_grid is not None:
            majorant_grid, minorant_grid = jnp.asarray(majorant_grid), jnp.asarray(minorant_grid)
            if majorant_grid.ndim != 3 or minorant_grid.shape != majorant_grid.shape:
                raise ValueError(
                    "`majorant_grid` and `minorant_grid` must be (Rz, Ry, Rx) grids of one "
                    f"shape, got {majorant_grid.shape} and {minorant_grid.shape}."
                )
        elif isinstance(density, jax.core.Tracer) or majorant_resolution in (1, (1, 1, 1)):
            # the global-majorant fallback: one cell
            majorant_grid = jnp.reshape(self.max_density, (1, 1, 1))
            minorant_grid = jnp.reshape(self.min_density, (1, 1, 1))
        else:
            res = majorant_resolution
            if isinstance(res, int):
                res = (res, res, res)
            hi, lo = coarse_majorant_grid(density, res)
            majorant_grid = jnp.asarray(hi, density.dtype)
            minorant_grid = jnp.asarray(lo, density.dtype)
        self.majorant_grid = majorant_grid
        self.minorant_grid = minorant_grid

    def _spectra(self, wavelength_nm):
        lam = as_float_array(wavelength_nm, "wavelength_nm")
        s = jnp.broadcast_to(jnp.asarray(self.sigma_t, lam.dtype), lam.shape)
        r = jnp.broadcast_to(jnp.asarray(self.albedo, lam.dtype), lam.shape)
        return s, r

    def coefficients_at(
        self, points: Float[Array, "n 3"], wavelength_nm: Float[Array, "n k"]
    ) -> tuple[Float[Array, "n k"], Float[Array, "n k"]]:
        """`(sigma_t, sigma_s)` `(n, k)` at scene points `(n, 3)` [scene units] and the
        wavelengths [nm]. [scene units^-1]"""
        s, r = self._spectra(wavelength_nm)
        return self._coefficients(points, s, r)

    def _coefficients(self, points, s, r):
        """`coefficients_at` with the spectra `s`, `r` `(n, k)` already at the wavelengths."""
        p = _affine(self.to_local.astype(points.dtype), points)
        d = trilinear_lookup(self.density, p)
        a = 1.0 if self.albedo_grid is None else trilinear_lookup(self.albedo_grid, p)[:, None]
        st = d[:, None] * s
        return st, st * r * a

    def majorant(self, wavelength_nm: Float[Array, "n k"]) -> Float[Array, " n"]:
        """The grey majorant $\\bar\\mu = \\max d \\cdot \\max_j s_j$ of each path.
        [scene units^-1]"""
        s, _ = self._spectra(wavelength_nm)
        return self.max_density.astype(s.dtype) * jnp.max(s, axis=-1)

    def _walk(self, origins, directions, t_max, wavelength_nm, u, mode: str):
        lam = as_float_array(wavelength_nm, "wavelength_nm")
        n, k = lam.shape
        dtype = origins.dtype
        u = as_float_array(u, "u")
        if u.ndim != 2 or u.shape[0] != n or u.shape[1] < 1:
            raise ValueError(f"`u` must be (n, d) with d >= 1 for n = {n} rays, got {u.shape}.")
        m = self.to_local.astype(dtype)
        o_l = _affine(m, origins)
        w_l = directions @ m[:3, :3].T
        t0, t1 = _box_interval(o_l, w_l)
        d = jnp.asarray(t_max, dtype)
        start = jnp.maximum(t0, 0.0)
        stop = jnp.minimum(t1, d)
        s, r = self._spectra(lam)
        s_max = jnp.max(s, axis=-1)
        hi_g = self.majorant_grid.astype(dtype)
        lo_g = self.minorant_grid.astype(dtype)
        # Tracking rate per cell in density units: max d (spectral tracking) or max d - min d
        # about the control min d (residual ratio tracking); times s_max it is per length.
        rate_g = hi_g - lo_g if mode == "ratio" else hi_g
        ctrl_g = lo_g if mode == "ratio" else jnp.zeros_like(lo_g)
        res_zyx = self.majorant_grid.shape
        res = jnp.asarray(res_zyx[::-1], dtype)[None, :]  # (1, 3): Rx, Ry, Rz
        top = jnp.asarray(res_zyx[::-1], jnp.int32)[None, :] - 1
        safe_w = jnp.where(w_l != 0, w_l, 1.0)
        active0 = (stop > start) & (s_max > 0) & (jnp.max(hi_g) > 0)
        p0 = o_l + jnp.where(active0, start, 0.0)[:, None] * w_l
        cell0 = jnp.clip(jnp.floor(p0 * res).astype(jnp.int32), 0, top)

        def cell_value(g, cell):
            return g[cell[:, 2], cell[:, 1], cell[:, 0]]

        def draw(u, step):
            """Optical depth to the next tentative collision and the variate deciding it."""
            v = _uniforms(u, step, 2)
            return -jnp.log1p(-v[:, 0]), v[:, 1]

        def advance(ray: _Ray, c: _Track) -> _Track:
            """One DDA step (`Amanatides1987`) of every active path not waiting at a
            collision: to its tentative collision if the optical depth `tau` left runs out in
            its cell (it then waits there), else into the next cell."""
            o_l, w_l, fwd, safe_w, stop = ray.o_l, ray.w_l, ray.w_l > 0, ray.safe_w, ray.stop
            moving = c.active & ~c.waiting
            mu = cell_value(rate_g, c.cell) * ray.s_max
            bound = (c.cell + fwd.astype(jnp.int32)).astype(dtype) / res
            t_ax = jnp.where(w_l != 0, (bound - o_l) / safe_w, jnp.inf)
            axis = jnp.argmin(t_ax, axis=-1)
            seg_end = jnp.minimum(jnp.min(t_ax, axis=-1), stop)
            seg = jnp.maximum(seg_end - c.t, 0.0)
            hit = moving & (mu * seg > c.tau)
            cross = moving & ~hit
            t_new = jnp.where(
                hit, c.t + c.tau / jnp.where(mu > 0, mu, 1.0), jnp.where(cross, seg_end, c.t)
            )
            ctrl = c.ctrl + jnp.where(moving, cell_value(ctrl_g, c.cell) * (t_new - c.t), 0.0)
            on_axis = (jnp.arange(3)[None, :] == axis[:, None]) & cross[:, None]
            cell_new = c.cell + jnp.where(on_axis, jnp.where(fwd, 1, -1), 0).astype(jnp.int32)
            out = jnp.any((cell_new < 0) | (cell_new > top), axis=-1)
            left = cross & ((seg_end >= stop) | out)
            return eqx.tree_at(
                lambda c: (c.t, c.cell, c.tau, c.ctrl, c.active, c.waiting),
                c,
                (
                    t_new,
                    jnp.where(left[:, None], c.cell, cell_new),
                    jnp.where(cross, c.tau - mu * seg, c.tau),
                    ctrl,
                    c.active & ~left,
                    c.waiting | hit,
                ),
            )

        def collide(ray: _Ray, c: _Track) -> _Track:
            """The tentative collisions of the waiting paths: the density where they are,
            the estimator's weight, and the optical depth to the next one."""
            hit = c.waiting
            s = ray.s
            mu = cell_value(rate_g, c.cell) * ray.s_max
            mu_s = jnp.where(mu > 0, mu, 1.0)
            x = ray.o + jnp.where(hit, c.t, 0.0)[:, None] * ray.d
            st, ss = self._coefficients(x, s, ray.r)
            weight, scattered = c.weight, c.scattered
            if mode == "ratio":
                sc = cell_value(ctrl_g, c.cell)[:, None] * s
                factor = 1.0 - (st - sc) / mu_s[:, None]
                weight = jnp.where(hit[:, None], weight * factor, weight)
                # Russian roulette once the estimate falls below _RR_BELOW (module
                # docstring): ended with probability _RR_END, else divided by 1 - _RR_END.
                low = jnp.max(weight * jnp.exp(-s * c.ctrl[:, None]), axis=-1) < _RR_BELOW
                roulette = hit & low
                stopped = roulette & (c.v < _RR_END)
                weight = jnp.where(stopped[:, None], 0.0, weight)
                weight = jnp.where((roulette & ~stopped)[:, None], weight / (1.0 - _RR_END), weight)
            else:
                p_real = jnp.clip(jnp.mean(st, axis=-1) / mu_s, 0.0, 1.0)
                stopped = hit & (c.v < p_real)
                w_real = safe_div(ss, (mu * p_real)[:, None])
                w_null = safe_div(mu[:, None] - st, (mu * (1.0 - p_real))[:, None])
                factor = jnp.where(stopped[:, None], w_real, w_null)
                weight = jnp.where(hit[:, None], weight * factor, weight)
                scattered = scattered | stopped
            step = c.step + hit.astype(jnp.uint32)
            tau_next, v_next = draw(ray.u, step)
            return eqx.tree_at(
                lambda c: (c.tau, c.v, c.step, c.active, c.waiting, c.scattered, c.weight),
                c,
                (
                    jnp.where(hit, tau_next, c.tau),
                    jnp.where(hit, v_next, c.v),
                    step,
                    c.active & ~stopped,
                    jnp.zeros_like(hit),
                    scattered,
                    weight,
                ),
            )

        def body(ray: _Ray, c: _Track) -> _Track:
            # Paths advance cell by cell independently and wait at their tentative collisions;
            # the collisions are evaluated together (a density lookup is dear) once half of
            # the active paths wait, or all of them.
            n_waiting = jnp.sum(c.waiting, dtype=jnp.int32)
            n_active = jnp.sum(c.active, dtype=jnp.int32)
            return lax.cond(2 * n_waiting >= n_active, collide, advance, ray, c)

        tau0, v0 = draw(u, jnp.zeros((n,), jnp.uint32))
        init = _Track(
            t=jnp.where(active0, start, 0.0),
            cell=cell0,
            tau=tau0,
            v=v0,
            step=jnp.zeros((n,), jnp.uint32),
            ctrl=jnp.zeros((n,), dtype),
            active=active0,
            waiting=jnp.zeros((n,), bool),
            scattered=jnp.zeros((n,), bool),
            weight=jnp.ones((n, k), dtype),
        )
        ray = _Ray(o=origins, d=directions, o_l=o_l, w_l=w_l, safe_w=safe_w, stop=stop, u=u,
                   s=s, r=r, s_max=s_max)  # fmt: skip
        out = _staged_loop(body, ray, init)
        t, scattered, weight, ctrl = out.t, out.scattered, out.weight, out.ctrl
        if mode == "ratio":
            weight = weight * jnp.exp(-s * ctrl[:, None])
        return t, scattered, weight, d

    def transmittance(
        self,
        origins: Float[Array, "n 3"],
        directions: Float[Array, "n 3"],
        t_max: Float[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        u: Float[Array, "n d"],
    ) -> Float[Array, "n k"]:
        """Residual-ratio-tracking estimate of the transmittance of each segment `(0, t_max)` [scene
        units] `(n, k)`, unbiased at every wavelength [nm]; variates from `u` (module
        docstring). [1]"""
        _, _, weight, _ = self._walk(origins, directions, t_max, wavelength_nm, u, "ratio")
        return weight

    def sample_free_flight(
        self,
        origins: Float[Array, "n 3"],
        directions: Float[Array, "n 3"],
        t_max: Float[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        u: Float[Array, "n d"],
    ) -> MediumInteraction:
        """Spectral tracking (module docstring) on `(0, t_max)` [scene units]: the first
        real interaction or the segment's end, with the weights of `HomogeneousMedium`'s
        convention `(n, k)`."""
        t, scattered, weight, d = self._walk(origins, directions, t_max, wavelength_nm, u, "delta")
        return MediumInteraction(t=jnp.where(scattered, t, d), scattered=scattered, weight=weight)
