"""Watertight ray-triangle intersection, brute force and BVH traversal (thesis ch. 8).

The triangle test is Woop, Benthin & Wald (2013): each ray is sheared into a space where it is
the +z axis, the 2D edge functions `U, V, W` are evaluated on the transformed corners, and a
hit needs all three of one sign. Corners shared by adjacent triangles are transformed by
identical arithmetic, and each edge function is evaluated with its two corners in a
canonical order (`_edge`), so a shared edge gives exactly opposite values in the two
triangles even where XLA:CPU contracts `a * b - c * d` into a fused multiply-add. A ray
through an edge or a vertex thus hits at least one of the triangles: no ray leaks through a
closed mesh. Edge values that are exactly 0 count as inside (a tie hits both triangles).
The paper's double-precision fallback for `U = V = W = 0` products is omitted: it refines
which of two tied triangles is reported and is not needed for watertightness.

Ray-box tests follow the robust slab test of Ize (2013): the far distance is enlarged by
`1 + 2 gamma_3` so rounding never culls a box that a ray grazes.

Layout (the measured fact of `design.md`): every test is written structure-of-arrays, one
array per coordinate, so XLA fuses it into one loop. The brute-force query loops over the
triangles and tests all rays against one triangle per step (a running min; see `_brute_loop`).
In the brute force, each triangle's corners are first sorted in a global (lexicographic) order,
so shared edges see identical operands without a per-ray swap.
"""

import functools
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array, ArrayLike, Bool, Float, Int

from ._bvh import BVH, EMPTY
from ._mesh import TriangleMesh
from ._native import native_brute_query, native_query, resolve_backend

__all__ = [
    "Hit",
    "intersect_any",
    "intersect_brute_force_any",
    "intersect_brute_force_closest",
    "intersect_closest",
]


class Hit(eqx.Module):
    """The closest intersection of each ray (a closest-hit query result).

    **Fields:**

    - `t`: ray parameter of the hit, `(n,)`; the hit point is `origin + t * direction`
        (in units of the direction's length). `inf` for a miss. [scene length unit per
        direction length]
    - `prim`: index of the hit triangle in the original face array, `(n,)` int32; -1 for a
        miss.
    - `b1`, `b2`: barycentric coordinates of the hit, `(n,)`, so that the point is
        `(1 - b1 - b2) v0 + b1 v1 + b2 v2`; 0 for a miss. [dimensionless]

    !!! note "Thesis"
        Ch. 8 (ray casting); the triangle parametrisation of `Pharr2023` §6.5.3.
    """

    t: Float[Array, " n"]
    prim: Int[Array, " n"]
    b1: Float[Array, " n"]
    b2: Float[Array, " n"]

    @property
    def valid(self) -> Bool[Array, " n"]:
        """True where the ray hit a triangle."""
        return self.prim >= 0


# ---------------------------------------------------------------------------------------------
# Ray setup and the watertight triangle test (Woop et al. 2013, JCGT 2(1), Listing 1)


class _Ray(NamedTuple):
    # Axis selection masks: the sheared x' axis is world axis 0 where kx0, 1 where kx1, else 2.
    kx0: Array
    kx1: Array
    ky0: Array
    ky1: Array
    kz0: Array
    kz1: Array
    ox: Array  # origin, permuted to (kx, ky, kz)
    oy: Array
    oz: Array
    sx: Array  # shear constants
    sy: Array
    sz: Array


def _pick(m0, m1, a, b, c):
    return jnp.where(m0, a, jnp.where(m1, b, c))


def _setup_rays(origins, directions) -> _Ray:
    """Per-ray constants of the watertight test; inputs `(..., 3)`, outputs `(...,)`."""
    dx, dy, dz = directions[..., 0], directions[..., 1], directions[..., 2]
    ax, ay, az = jnp.abs(dx), jnp.abs(dy), jnp.abs(dz)
    # kz: the dimension where the direction is largest (first one on ties)
    kz0 = (ax >= ay) & (ax >= az)
    kz1 = ~kz0 & (ay >= az)
    kz2 = ~kz0 & ~kz1
    # kx = kz + 1 mod 3, ky = kx + 1 mod 3
    kx0, kx1 = kz2, kz0
    ky0, ky1 = kz1, kz2
    d_kz = _pick(kz0, kz1, dx, dy, dz)
    # The paper swaps kx and ky when d_kz < 0 to keep the winding for back-face culling. Both
    # windings are accepted here, and the swap only negates U, V, W, det and T exactly (t and
    # the barycentrics are unchanged), so it is left out.
    ox, oy, oz = origins[..., 0], origins[..., 1], origins[..., 2]
    d_kx = _pick(kx0, kx1, dx, dy, dz)
    d_ky = _pick(ky0, ky1, dx, dy, dz)
    return _Ray(
        kx0=kx0,
        kx1=kx1,
        ky0=ky0,
        ky1=ky1,
        kz0=kz0,
        kz1=kz1,
        ox=_pick(kx0, kx1, ox, oy, oz),
        oy=_pick(ky0, ky1, ox, oy, oz),
        oz=_pick(kz0, kz1, ox, oy, oz),
        sx=d_kx / d_kz,
        sy=d_ky / d_kz,
        sz=1.0 / d_kz,
    )


def _expand(ray: _Ray) -> _Ray:
    return _Ray(*(f[:, None] for f in ray))


def _edge(p_x, p_y, q_x, q_y):
    """2D edge function `p_x q_y - p_y q_x`, exactly antisymmetric: `_edge(q, p) == -_edge(p, q)`.

    The two corners are put in a canonical (lexicographic) order before the products, so the
    two triangles that share an edge evaluate it with the same operands in the same places.
    Without this, a fused multiply-add (which XLA:CPU emits for `a * b - c * d`) rounds the two
    evaluations differently, and rays exactly through a shared edge leak between them
    (measured: 17 of 1122 rays through the edges of an icosphere in float32).
    """
    swap = (p_x > q_x) | ((p_x == q_x) & (p_y > q_y))
    a_x = jnp.where(swap, q_x, p_x)
    a_y = jnp.where(swap, q_y, p_y)
    b_x = jnp.where(swap, p_x, q_x)
    b_y = jnp.where(swap, p_y, q_y)
    e = a_x * b_y - a_y * b_x
    return jnp.where(swap, -e, e)


def _triangle_test(ray: _Ray, v0, v1, v2, t_min, t_max):
    """Watertight test of rays against triangles given as `(x, y, z)` coordinate tuples.

    Every argument broadcasts: `(n,)` with `(n,)` in the BVH loop, `(n, 1)` with `(f,)` in the
    brute force. Returns `(hit, t, b1, b2)`; a hit needs `t_min < t < t_max`.
    """

    def corner(v):
        # translate to the ray origin, permute to (kx, ky, kz) and shear onto the +z axis
        px = _pick(ray.kx0, ray.kx1, v[0], v[1], v[2]) - ray.ox
        py = _pick(ray.ky0, ray.ky1, v[0], v[1], v[2]) - ray.oy
        pz = _pick(ray.kz0, ray.kz1, v[0], v[1], v[2]) - ray.oz
        return px - ray.sx * pz, py - ray.sy * pz, ray.sz * pz

    a_x, a_y, a_z = corner(v0)
    b_x, b_y, b_z = corner(v1)
    c_x, c_y, c_z = corner(v2)
    # scaled barycentrics: 2D edge functions of the sheared corners
    u = _edge(c_x, c_y, b_x, b_y)
    v = _edge(a_x, a_y, c_x, c_y)
    w = _edge(b_x, b_y, a_x, a_y)
    inside = ((u >= 0) & (v >= 0) & (w >= 0)) | ((u <= 0) & (v <= 0) & (w <= 0))
    det = u + v + w
    ok = inside & (det != 0)
    det_safe = jnp.where(ok, det, 1.0)
    inv_det = 1.0 / det_safe
    t_scaled = u * a_z + v * b_z + w * c_z
    t = t_scaled * inv_det
    hit = ok & (t > t_min) & (t < t_max)
    return hit, t, v * inv_det, w * inv_det


def _columns(tri):
    """`(..., 9)` corners -> three `(x, y, z)` tuples of `(...)` columns."""
    cols = [tri[..., i] for i in range(9)]
    return tuple(cols[0:3]), tuple(cols[3:6]), tuple(cols[6:9])


# ---------------------------------------------------------------------------------------------
# Public entry points


def _check_rays(origins, directions, t_max, dtype, t_min):
    o = jnp.asarray(origins)
    d = jnp.asarray(directions)
    if o.ndim != 2 or o.shape[-1] != 3:
        raise ValueError(f"`origins` must have shape (n, 3), got {o.shape}.")
    if d.shape != o.shape:
        raise ValueError(f"`directions` must have the shape of `origins` {o.shape}, got {d.shape}.")
    for name, x in (("origins", o), ("directions", d)):
        if not jnp.issubdtype(x.dtype, jnp.floating):
            raise TypeError(f"`{name}` must be floating point, got dtype {x.dtype}.")
    n = o.shape[0]
    tmax = jnp.broadcast_to(jnp.asarray(t_max, dtype=dtype), (n,)) if jnp.ndim(t_max) == 0 else None
    if tmax is None:
        tmax = jnp.asarray(t_max)
        if tmax.shape != (n,):
            raise ValueError(f"`t_max` must be a scalar or have shape ({n},), got {tmax.shape}.")
        tmax = tmax.astype(dtype)
    tmin = jnp.asarray(t_min, dtype=dtype)
    if tmin.ndim not in (0,) and tmin.shape != (n,):
        raise ValueError(f"`t_min` must be a scalar or have shape ({n},), got {tmin.shape}.")
    tmin = jnp.broadcast_to(tmin, (n,))
    return o.astype(dtype), d.astype(dtype), tmin, tmax


def _triangles_of(geometry) -> Array:
    """`(f, 9)` corners in original face order."""
    if isinstance(geometry, BVH):
        # back to the original face order, so ties resolve as for the mesh
        inv = (
            jnp.zeros_like(geometry.prim_ids)
            .at[geometry.prim_ids]
            .set(jnp.arange(geometry.prim_ids.shape[0], dtype=jnp.int32))
        )
        return geometry.triangles[inv]
    if isinstance(geometry, TriangleMesh):
        v = geometry.vertices
        return v[geometry.faces].reshape(-1, 9)
    raise TypeError(f"expected a BVH or a TriangleMesh, got {type(geometry).__name__}.")


def _is_concrete(*trees) -> bool:
    """True when no leaf is a tracer (an eager call, outside `jit`/`vmap`)."""
    return not any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(trees))


def _bucket(n: int, minimum: int) -> int:
    """Size bucket for eager calls: a power of two >= `minimum` up to 2^16, then multiples of it.

    Eager calls pad their arrays to the bucket, so that meshes and ray batches of similar
    sizes share one compiled program (each traversal compile costs seconds).
    """
    n = max(n, minimum)
    if n <= 1 << 16:
        return 1 << (n - 1).bit_length()
    return -(-n // (1 << 16)) << 16


def _pad_rows(x, rows: int, value):
    if x.shape[0] == rows:
        return x
    x = np.asarray(x)
    pad = [(0, rows - x.shape[0])] + [(0, 0)] * (x.ndim - 1)
    return jnp.asarray(np.pad(x, pad, constant_values=value))


def _pad_rays(o, d, tmin, tmax):
    """Pad a ray batch to its bucket; padded rays have an empty interval (`t_max = -inf`)."""
    m = _bucket(o.shape[0], _MIN_RAYS)
    return (
        _pad_rows(o, m, 0),
        _pad_rows(d, m, 1),
        _pad_rows(tmin, m, 0),
        _pad_rows(tmax, m, -np.inf),
    )


def _slice_hit(hit: Hit, n: int) -> Hit:
    return Hit(t=hit.t[:n], prim=hit.prim[:n], b1=hit.b1[:n], b2=hit.b2[:n])


_MIN_RAYS = 1024  # smallest ray bucket of eager calls
_MIN_TRIANGLES = 64  # smallest triangle bucket of eager calls


def intersect_brute_force_closest(
    geometry: BVH | TriangleMesh,
    origins: ArrayLike,
    directions: ArrayLike,
    t_max: ArrayLike = float("inf"),
    *,
    t_min: ArrayLike = 0.0,
    backend: str = "auto",
) -> Hit:
    """Closest hit of each ray by testing every triangle (for tests and tiny scenes).

    A loop over the triangles, each step one fused elementwise test of all rays (one array
    per coordinate) that updates the running nearest hit; on an exact tie in `t` the lowest
    face index wins (the same rule as `intersect_closest`). Cost is O(rays x triangles); the
    fastest query for scenes of a few dozen triangles (the Cornell box). On the CPU the same
    loop runs natively by default, over blocks of 256 rays held in cache and vectorised
    across rays. Coplanar overlapping triangles (z-fighting) may resolve differently in the two
    backends, because XLA contracts some products into fused multiply-adds and the native code
    does not.

    **Arguments:**

    - `geometry`: a `TriangleMesh` or a `BVH` (its triangles are used, in face order).
    - `origins`: `(n, 3)` ray origins. [scene length unit]
    - `directions`: `(n, 3)` ray directions, not necessarily unit. [scene length unit]
    - `t_max`: scalar or `(n,)` upper limit of the ray parameter (exclusive).
        [direction lengths]
    - `t_min`: scalar or `(n,)` lower limit (exclusive, default 0). [direction lengths]
    - `backend`: `"auto"` (default: the native CPU kernel, vectorised over blocks of rays,
        when the default JAX backend is the CPU and the kernel is available, see
        `native_status`; else a JAX loop over the triangles), `"native"` or `"jax"`.

    **Returns:**

    A `Hit`, in the dtype of the geometry.

    !!! note "Thesis"
        Ch. 8 (ray casting); watertight test of `Woop2013`.
    """
    tri = _triangles_of(geometry)
    o, d, tmin, tmax = _check_rays(origins, directions, t_max, tri.dtype, t_min)
    backend = resolve_backend(backend)
    if _is_concrete(tri, o, d, tmin, tmax):
        # degenerate padding triangles (all corners 0) are never hit
        n, tri = o.shape[0], _pad_rows(tri, _bucket(tri.shape[0], _MIN_TRIANGLES), 0)
        return _slice_hit(_brute_closest(tri, *_pad_rays(o, d, tmin, tmax), backend=backend), n)
    return _brute_closest(tri, o, d, tmin, tmax, backend=backend)


def _lex_less(p, q):
    """Lexicographic `p < q` of `(x, y, z)` column tuples (a ray-independent vertex order)."""
    return (p[0] < q[0]) | ((p[0] == q[0]) & ((p[1] < q[1]) | ((p[1] == q[1]) & (p[2] < q[2]))))


def _sorted_corners(tri):
    """`(f, 9)` corners -> `(9, f)` rows `a, b, c`: each triangle's corners sorted by `_lex_less`.

    With the corners of every triangle in one global order, an edge shared by two triangles
    has the same first and second corner in both, so its edge function is evaluated on the
    same operands in the same places (bit-identical, whatever fused multiply-adds XLA emits)
    without the per-ray canonical swap of `_edge`. Sorting permutes the corners, which only
    flips the common sign of `U, V, W` and `det` (the test accepts both signs) and leaves `t`
    unchanged.
    """
    a, b, c = _columns(tri)

    def swap(p, q):
        s = _lex_less(q, p)
        lo = tuple(jnp.where(s, y, x) for x, y in zip(p, q, strict=True))
        hi = tuple(jnp.where(s, x, y) for x, y in zip(p, q, strict=True))
        return lo, hi

    a, b = swap(a, b)
    b, c = swap(b, c)
    a, b = swap(a, b)
    return jnp.stack(a + b + c)


def _brute_loop(tri, o, d, tmin, tmax, *, any_hit: bool):
    """Loop over the triangles, each iteration testing every ray against one triangle.

    Each iteration is one fused elementwise kernel over the rays (vectorised and threaded by
    XLA:CPU), and the running minimum needs no `(rays, triangles)` array and no argmin: with
    a strict `t < t_best`, exact ties keep the lowest face index. Measured on the 36-triangle
    Cornell box (float32, 2^18 rays, 2 shared cores): 5-9x faster than the
    `(rays, 1) x (triangles,)` broadcast with two fused reductions, whose reduction over the
    short minor axis XLA:CPU does not vectorise.
    """
    ray = _setup_rays(o, d)
    corners = _sorted_corners(tri)
    n_tri = tri.shape[0]

    def corner(v):
        # translate to the ray origin, permute to (kx, ky, kz) and shear onto the +z axis
        px = _pick(ray.kx0, ray.kx1, v[0], v[1], v[2]) - ray.ox
        py = _pick(ray.ky0, ray.ky1, v[0], v[1], v[2]) - ray.oy
        pz = _pick(ray.kz0, ray.kz1, v[0], v[1], v[2]) - ray.oz
        return px - ray.sx * pz, py - ray.sy * pz, ray.sz * pz

    def body(k, carry):
        q = corners[:, k]
        a_x, a_y, a_z = corner(q[0:3])
        b_x, b_y, b_z = corner(q[3:6])
        c_x, c_y, c_z = corner(q[6:9])
        # edge functions, each with its corners in the global (sorted) order
        e_ab = a_x * b_y - a_y * b_x
        e_bc = b_x * c_y - b_y * c_x
        e_ac = a_x * c_y - a_y * c_x
        u, v, w = -e_bc, e_ac, -e_ab
        inside = (jnp.minimum(jnp.minimum(u, v), w) >= 0) | (jnp.maximum(jnp.maximum(u, v), w) <= 0)
        det = u + v + w
        t = (u * a_z + v * b_z + w * c_z) / jnp.where(det != 0, det, 1.0)
        if any_hit:
            return carry | (inside & (det != 0) & (t > tmin) & (t < tmax))
        t_best, best = carry
        hit = inside & (det != 0) & (t > tmin) & (t < t_best)
        return jnp.where(hit, t, t_best), jnp.where(hit, k, best)

    if any_hit:
        return lax.fori_loop(0, n_tri, body, jnp.zeros(o.shape[0], bool), unroll=4)
    init = (tmax, jnp.full(o.shape[0], -1, jnp.int32))
    return lax.fori_loop(0, n_tri, body, init, unroll=4)


@functools.partial(jax.jit, static_argnames="backend")
def _brute_closest(tri, o, d, tmin, tmax, backend="jax"):
    if backend == "native":
        t, prim, b1, b2 = native_brute_query(
            _sorted_corners(tri), tri, o, d, tmin, tmax, any_hit=False
        )
        return Hit(t=t, prim=prim, b1=b1, b2=b2)
    t_loop, best = _brute_loop(tri, o, d, tmin, tmax, any_hit=False)
    any_hit = best >= 0
    # recompute the chosen triangle per ray for its barycentrics, in the original corner order
    w0, w1, w2 = _columns(tri[jnp.maximum(best, 0)])
    _, _, b1, b2 = _triangle_test(_setup_rays(o, d), w0, w1, w2, tmin, tmax)
    zero = jnp.zeros_like(b1)
    return Hit(
        t=jnp.where(any_hit, t_loop, jnp.inf),
        prim=best,
        b1=jnp.where(any_hit, b1, zero),
        b2=jnp.where(any_hit, b2, zero),
    )


def intersect_brute_force_any(
    geometry: BVH | TriangleMesh,
    origins: ArrayLike,
    directions: ArrayLike,
    t_max: ArrayLike = float("inf"),
    *,
    t_min: ArrayLike = 0.0,
    backend: str = "auto",
) -> Bool[Array, " n"]:
    """Whether each ray hits any triangle with `t_min < t < t_max` (brute force, shadow rays).

    **Arguments:**

    - `geometry`: a `TriangleMesh` or a `BVH`.
    - `origins`: `(n, 3)` ray origins. [scene length unit]
    - `directions`: `(n, 3)` ray directions. [scene length unit]
    - `t_max`: scalar or `(n,)` exclusive upper limit. [direction lengths]
    - `t_min`: scalar or `(n,)` exclusive lower limit (default 0). [direction lengths]
    - `backend`: `"auto"` (default: the native CPU kernel, vectorised over blocks of rays,
        when the default JAX backend is the CPU and the kernel is available, see
        `native_status`; else a JAX loop over the triangles), `"native"` or `"jax"`.

    **Returns:**

    `(n,)` bool, True where the segment is occluded.

    !!! note "Thesis"
        Ch. 8 (visibility for next-event estimation); `Woop2013`.
    """
    tri = _triangles_of(geometry)
    o, d, tmin, tmax = _check_rays(origins, directions, t_max, tri.dtype, t_min)
    backend = resolve_backend(backend)
    if _is_concrete(tri, o, d, tmin, tmax):
        n, tri = o.shape[0], _pad_rows(tri, _bucket(tri.shape[0], _MIN_TRIANGLES), 0)
        return _brute_any(tri, *_pad_rays(o, d, tmin, tmax), backend=backend)[:n]
    return _brute_any(tri, o, d, tmin, tmax, backend=backend)


@functools.partial(jax.jit, static_argnames="backend")
def _brute_any(tri, o, d, tmin, tmax, backend="jax"):
    if backend == "native":
        hit = native_brute_query(_sorted_corners(tri), tri, o, d, tmin, tmax, any_hit=True)
        return hit[1] >= 0
    return _brute_loop(tri, o, d, tmin, tmax, any_hit=True)


# ---------------------------------------------------------------------------------------------
# BVH traversal


def _gamma(n: int, dtype) -> float:
    eps = float(np.finfo(dtype).eps) * 0.5
    return n * eps / (1.0 - n * eps)


def _lane_step(bvh: BVH, state, *, any_hit: bool):
    """One traversal iteration for every lane (see `_traverse`).

    The node step and the triangle step each run inside a `lax.cond` (skipped when no lane
    needs it). Besides the skip, the conditional is a fusion boundary: XLA:CPU otherwise
    duplicates the slab and edge-function arithmetic into every consumer fusion (measured: 8
    copies of the node step, 5x slower); `lax.optimization_barrier` does not survive to
    fusion on CPU.
    """
    dtype = bvh.triangles.dtype
    depth = max(bvh.stack_size, 1)
    empty = jnp.int32(EMPTY)
    grow = 1.0 + 2.0 * _gamma(3, dtype)
    (cur, stack, sp, lcur, lend, t_best, prim, kbest, rid, c) = state
    rows = jnp.arange(cur.shape[0])
    ox, oy, oz, ix, iy, iz, pox, poy, poz, sx, sy, sz, t_lo, t_hi, kzf = c
    # 1. pop the next item when there is none
    do_pop = (cur == empty) & (sp > 0)
    top = jnp.take_along_axis(stack, jnp.maximum(sp - 1, 0)[:, None], axis=1)[:, 0]
    cur = jnp.where(do_pop, top, cur)
    sp = sp - do_pop.astype(jnp.int32)
    # 2. interior node: cull and order both children (robust slab test, Ize 2013)
    inner = cur >= 0

    def node_step(cur, t_best):
        node = jnp.where(inner, cur, 0)
        box = bvh.node_boxes[node]
        ch = bvh.node_children[node]

        def slab(j):
            t0x, t1x = (box[:, j + 0] - ox) * ix, (box[:, j + 3] - ox) * ix
            t0y, t1y = (box[:, j + 1] - oy) * iy, (box[:, j + 4] - oy) * iy
            t0z, t1z = (box[:, j + 2] - oz) * iz, (box[:, j + 5] - oz) * iz
            near = jnp.maximum(
                jnp.maximum(jnp.minimum(t0x, t1x), jnp.minimum(t0y, t1y)),
                jnp.maximum(jnp.minimum(t0z, t1z), t_lo),
            )
            far = jnp.minimum(
                jnp.minimum(jnp.maximum(t0x, t1x), jnp.maximum(t0y, t1y)),
                jnp.maximum(t0z, t1z),
            )
            return near, inner & (near <= jnp.minimum(far * grow, t_best))

        near0, hit0 = slab(0)
        near1, hit1 = slab(6)
        # One int8 output, so the slab tests are computed once: 0 = no child hit, 1 = only
        # child 0, 2 = only child 1, 3 = both and child 0 nearer, 4 = both, child 1 nearer.
        decision = jnp.where(
            hit0 & hit1,
            jnp.where(near1 < near0, 4, 3),
            jnp.where(hit0, 1, jnp.where(hit1, 2, 0)),
        ).astype(jnp.int8)
        return decision, ch[:, 0], ch[:, 1]

    def no_node_step(cur, t_best):
        return jnp.zeros(cur.shape, jnp.int8), cur, cur

    decision, c0, c1 = lax.cond(jnp.any(inner), node_step, no_node_step, cur, t_best)
    nxt = jnp.where(
        (decision == 1) | (decision == 3),
        c0,
        jnp.where((decision == 2) | (decision == 4), c1, empty),
    )
    cur = jnp.where(inner, nxt, cur)
    both = decision >= 3
    far_c = jnp.where(decision == 3, c1, c0)
    stack = stack.at[rows, jnp.where(both, sp, depth)].set(far_c, mode="drop")
    sp = sp + both.astype(jnp.int32)
    # 3. leaf: load its triangle range when the previous one is done
    pending = lcur < lend
    load = (cur < 0) & (cur != empty) & ~pending
    code = ~cur
    start = code >> 3
    lcur = jnp.where(load, start, lcur)
    lend = jnp.where(load, start + (code & 7) + 1, lend)
    cur = jnp.where(load, empty, cur)
    pending = pending | load

    # 4. test one pending triangle (watertight, Woop et al. 2013)
    def tri_step(lcur):
        k = jnp.where(pending, lcur, 0)
        tv = bvh.triangles[k]
        kz0, kz1, kz2 = kzf == 0, kzf == 1, kzf == 2
        lane_ray = _Ray(kz2, kz0, kz1, kz2, kz0, kz1, pox, poy, poz, sx, sy, sz)
        v0, v1, v2 = _columns(tv)
        hit, t, _, _ = _triangle_test(lane_ray, v0, v1, v2, t_lo, t_hi)
        # one float output (NaN = no hit): the edge functions are computed once
        return jnp.where(pending & hit, t, jnp.nan), bvh.prim_ids[k]

    def no_tri_step(lcur):
        return jnp.full(lcur.shape, jnp.nan, dtype), lcur

    t_cand, pid = lax.cond(jnp.any(pending), tri_step, no_tri_step, lcur)
    upd = (t_cand < t_best) | ((t_cand == t_best) & (pid < prim))  # NaN compares False
    t_best = jnp.where(upd, t_cand, t_best)
    prim = jnp.where(upd, pid, prim)
    kbest = jnp.where(upd, lcur, kbest)
    lcur = lcur + pending.astype(jnp.int32)
    if any_hit:  # the first hit ends the ray
        cur = jnp.where(upd, empty, cur)
        sp = jnp.where(upd, 0, sp)
        lend = jnp.where(upd, lcur, lend)
    return (cur, stack, sp, lcur, lend, t_best, prim, kbest, rid, c)


def _traverse(bvh: BVH, o, d, tmin, tmax, *, any_hit: bool, lanes: int, refill_every: int):
    """Stack-based BVH traversal over a batch of rays with persistent lanes.

    `lanes` rays are traced at once, in lockstep, by one `lax.while_loop`; each iteration does,
    for every lane: pop when no item is current; an interior-node step (test both children's
    boxes, continue with the nearer, push the farther on a fixed-depth stack); load a leaf
    into the pending range when none is pending; test one pending triangle. Every
    `refill_every` iterations the lanes whose ray has finished write their result and take
    the next rays of the batch (a prefix sum ranks the free lanes), so a few long rays do not
    hold the whole batch (lockstep alone wastes 5-20x on incoherent rays) and the working
    set stays in cache whatever the batch size.
    """
    n = o.shape[0]
    dtype = bvh.triangles.dtype
    depth = max(bvh.stack_size, 1)
    w = min(lanes, n)
    empty = jnp.int32(EMPTY)
    # ---- per-ray constants, computed once for the batch: one row per ray ------------------
    ray = _setup_rays(o, d)
    tiny = jnp.asarray(np.finfo(dtype).tiny, dtype)
    d_safe = jnp.where(jnp.abs(d) < tiny, jnp.where(d < 0, -tiny, tiny), d)
    inv = 1.0 / d_safe  # slab test; zero components become huge, never 0 * inf = NaN
    kz = jnp.where(ray.kz0, 0, jnp.where(ray.kz1, 1, 2)).astype(dtype)
    table = jnp.stack(
        [o[:, 0], o[:, 1], o[:, 2], inv[:, 0], inv[:, 1], inv[:, 2], ray.ox, ray.oy, ray.oz,
         ray.sx, ray.sy, ray.sz, tmin, tmax, kz],
        axis=1,
    )  # fmt: skip

    def step(state):
        return _lane_step(bvh, state, any_hit=any_hit)

    def busy(state):
        cur, _, sp, lcur, lend = state[:5]
        return (cur != empty) | (sp > 0) | (lcur < lend)

    def write(state, out):
        t_best, prim, kbest, rid = state[5:9]
        idx = jnp.where((rid >= 0) & ~busy(state), rid, n)  # n: dropped
        o_t, o_p, o_k = out
        return (
            o_t.at[idx].set(t_best, mode="drop"),
            o_p.at[idx].set(prim, mode="drop"),
            o_k.at[idx].set(kbest, mode="drop"),
        )

    def refill(state, nxt):
        (cur, stack, sp, lcur, lend, t_best, prim, kbest, rid, c) = state
        free = ~busy(state)
        rank = jnp.cumsum(free.astype(jnp.int32)) - 1
        new = nxt + rank
        take = free & (new < n)
        row = table[jnp.minimum(new, n - 1)]
        c = tuple(jnp.where(take, row[:, i], c[i]) for i in range(len(c)))
        cur = jnp.where(take, 0, cur)  # start at the root
        sp = jnp.where(take, 0, sp)
        lcur = jnp.where(take, 0, lcur)
        lend = jnp.where(take, 0, lend)
        t_best = jnp.where(take, row[:, 13], t_best)
        prim = jnp.where(take, -1, prim)
        rid = jnp.where(take, new, jnp.where(free, -1, rid))
        nxt = jnp.minimum(nxt + jnp.sum(free, dtype=jnp.int32), n)
        return (cur, stack, sp, lcur, lend, t_best, prim, kbest, rid, c), nxt

    def body(carry):
        state, out, nxt = carry
        out = write(state, out)
        state, nxt = refill(state, nxt)
        state = lax.fori_loop(0, refill_every, lambda _, s: step(s), state)
        return state, out, nxt

    def cond(carry):
        state, _, nxt = carry
        return (nxt < n) | jnp.any(busy(state))

    zi = jnp.zeros(w, jnp.int32)
    zf = jnp.zeros(w, dtype)
    state = (
        jnp.full(w, empty),
        jnp.full((w, depth), empty, jnp.int32),
        zi,
        zi,
        zi,
        zf,
        jnp.full(w, -1, jnp.int32),
        zi,
        jnp.full(w, -1, jnp.int32),
        tuple(zf for _ in range(table.shape[1])),
    )
    out = (jnp.full(n, jnp.inf, dtype), jnp.full(n, -1, jnp.int32), jnp.zeros(n, jnp.int32))
    state, out, _ = lax.while_loop(cond, body, (state, out, jnp.int32(0)))
    t_best, prim, kbest = write(state, out)
    found = prim >= 0
    if any_hit:
        zero = jnp.zeros(n, dtype)
        return Hit(t=jnp.where(found, t_best, jnp.inf), prim=prim, b1=zero, b2=zero)
    # barycentrics of the closest hit only, outside the loop: one more test per ray
    v0, v1, v2 = _columns(bvh.triangles[kbest])
    _, _, b1, b2 = _triangle_test(ray, v0, v1, v2, tmin, tmax)
    zero = jnp.zeros_like(b1)
    return Hit(
        t=jnp.where(found, t_best, jnp.inf),
        prim=prim,
        b1=jnp.where(found, b1, zero),
        b2=jnp.where(found, b2, zero),
    )


_LANES = 2048
_REFILL_EVERY = 4


@eqx.filter_jit
def _closest(bvh, o, d, tmin, tmax, backend="jax", lanes=_LANES, refill_every=_REFILL_EVERY):
    if backend == "native":
        t, prim, b1, b2 = native_query(bvh, o, d, tmin, tmax, any_hit=False)
        return Hit(t=t, prim=prim, b1=b1, b2=b2)
    return _traverse(bvh, o, d, tmin, tmax, any_hit=False, lanes=lanes, refill_every=refill_every)


@eqx.filter_jit
def _any(bvh, o, d, tmin, tmax, backend="jax", lanes=_LANES, refill_every=_REFILL_EVERY):
    if backend == "native":
        return native_query(bvh, o, d, tmin, tmax, any_hit=True)[1] >= 0
    hit = _traverse(bvh, o, d, tmin, tmax, any_hit=True, lanes=lanes, refill_every=refill_every)
    return hit.prim >= 0


def _pad_bvh(bvh: BVH) -> BVH:
    """The BVH with its arrays padded to size buckets (for eager calls); unreachable rows.

    Large BVHs (more than 2^16 triangles) are returned as they are: copying them on every
    call would cost more than the compile it saves.
    """
    if bvh.triangles.shape[0] > 1 << 16:
        return bvh
    n_nodes = _bucket(bvh.node_boxes.shape[0], 32)
    n_tri = _bucket(bvh.triangles.shape[0], _MIN_TRIANGLES)
    boxes = np.asarray(bvh.node_boxes)
    empty_box = np.tile(np.r_[[np.inf] * 3, [-np.inf] * 3], 2).astype(boxes.dtype)
    boxes = np.concatenate([boxes, np.broadcast_to(empty_box, (n_nodes - len(boxes), 12))])
    return BVH(
        node_boxes=jnp.asarray(boxes),
        node_children=_pad_rows(bvh.node_children, n_nodes, EMPTY),
        triangles=_pad_rows(bvh.triangles, n_tri, 0),
        prim_ids=_pad_rows(bvh.prim_ids, n_tri, 0),
        bounds=bvh.bounds,
        stack_size=-(-max(bvh.stack_size, 1) // 16) * 16,
        max_leaf_size=8,
    )


def _query(fn, bvh: BVH, o, d, tmin, tmax, backend: str):
    """Run a traversal; eager calls are padded to size buckets and share compiled programs."""
    backend = resolve_backend(backend)
    if not _is_concrete(bvh, o, d, tmin, tmax):
        return fn(bvh, o, d, tmin, tmax, backend)
    out = fn(_pad_bvh(bvh), *_pad_rays(o, d, tmin, tmax), backend)
    n = o.shape[0]
    return _slice_hit(out, n) if isinstance(out, Hit) else out[:n]


def intersect_closest(
    bvh: BVH,
    origins: ArrayLike,
    directions: ArrayLike,
    t_max: ArrayLike = float("inf"),
    *,
    t_min: ArrayLike = 0.0,
    backend: str = "auto",
) -> Hit:
    """Closest hit of each ray, by BVH traversal (near child first, fixed-depth stack).

    Results equal `intersect_brute_force_closest` (same triangle, same `t`): ties in `t` go
    to the lowest face index. Works under `jit` and `vmap` (a batch of rays is already
    vectorised); it is not differentiable through the traversal: recompute the hit point from
    `prim` and the barycentrics to differentiate with respect to the geometry.

    **Arguments:**

    - `bvh`: from `build_bvh`.
    - `origins`: `(n, 3)` ray origins, cast to the BVH dtype. [scene length unit]
    - `directions`: `(n, 3)` directions (any length; `t` is in units of it). [scene length unit]
    - `t_max`: scalar or `(n,)` exclusive upper limit of `t` (default inf).
        [direction lengths]
    - `t_min`: scalar or `(n,)` exclusive lower limit of `t` (default 0). [direction lengths]
    - `backend`: `"auto"` (default: the native CPU kernel when the default JAX backend is the
        CPU and the kernel is available, see `native_status`; else the lockstep JAX
        traversal), `"native"` or `"jax"`. Both give the same hits.

    **Returns:**

    A `Hit` with `t (n,)`, `prim (n,)` int32 (-1 = miss), `b1, b2 (n,)`.

    !!! note "Thesis"
        Ch. 8 (ray casting); `Woop2013` (watertight test), `Ize2013` (robust box test),
        `Aila2009` (traversal loop), `Pharr2023` §7.3.5.
    """
    if not isinstance(bvh, BVH):
        raise TypeError(f"`bvh` must be a BVH (see build_bvh), got {type(bvh).__name__}.")
    o, d, tmin, tmax = _check_rays(origins, directions, t_max, bvh.triangles.dtype, t_min)
    return _query(_closest, bvh, o, d, tmin, tmax, backend)


def intersect_any(
    bvh: BVH,
    origins: ArrayLike,
    directions: ArrayLike,
    t_max: ArrayLike = float("inf"),
    *,
    t_min: ArrayLike = 0.0,
    backend: str = "auto",
) -> Bool[Array, " n"]:
    """Whether each ray segment `t_min < t < t_max` is occluded (any-hit, early exit per ray).

    **Arguments:**

    - `bvh`: from `build_bvh`.
    - `origins`: `(n, 3)` ray origins. [scene length unit]
    - `directions`: `(n, 3)` ray directions. [scene length unit]
    - `t_max`: scalar or `(n,)` exclusive upper limit (e.g. the distance to a light sample).
        [direction lengths]
    - `t_min`: scalar or `(n,)` exclusive lower limit (default 0). [direction lengths]
    - `backend`: `"auto"` (default: the native CPU kernel when the default JAX backend is the
        CPU and the kernel is available, see `native_status`; else the lockstep JAX
        traversal), `"native"` or `"jax"`. Both give the same hits.

    **Returns:**

    `(n,)` bool.

    !!! note "Thesis"
        Ch. 8 (visibility in next-event estimation); `Woop2013`, `Pharr2023` §7.3.5.
    """
    if not isinstance(bvh, BVH):
        raise TypeError(f"`bvh` must be a BVH (see build_bvh), got {type(bvh).__name__}.")
    o, d, tmin, tmax = _check_rays(origins, directions, t_max, bvh.triangles.dtype, t_min)
    return _query(_any, bvh, o, d, tmin, tmax, backend)
