"""Bounding volume hierarchy: a binned-SAH build in NumPy, flattened to arrays (thesis ch. 8).

The build is offline and runs level by level: all nodes of one tree level are binned, scored
and split together with vectorised NumPy (`np.minimum.at` over `(node, axis, bin)` keys), so
the Python loop runs once per *level* (about 2 log2(f) times), not once per node. A 10^6
triangle mesh builds in a few seconds.

The result is a binary BVH stored as flat arrays that the traversals read (`_traversal.py`,
`_native.py`):

- `node_boxes (n, 12)`: for each interior node, the boxes of its two *children*
  `[lo0 (3), hi0 (3), lo1 (3), hi1 (3)]` (one row = one cache line in float32), so one gather
  gives everything needed to order and cull both children (`Aila2009`);
- `node_children (n, 2)` int32: a child code: `c >= 0` is an interior node index; `c < 0`
  with `c != EMPTY` is a leaf `~(start << 3 | (count - 1))` covering triangles
  `[start, start + count)` of the reordered triangle array; `EMPTY` is no child;
- `triangles (f, 9)`: corner positions `v0, v1, v2` of each triangle, in leaf order;
- `prim_ids (f,)` int32: the original face index of each reordered triangle.

Node 0 is the root; the scene box is `bounds`.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float, Int

__all__ = ["BVH", "EMPTY", "build_bvh"]

EMPTY = np.int32(np.iinfo(np.int32).min)  # child code of a missing child (its box is empty)
_MAX_LEAF = 8  # leaf counts are stored in 3 bits
_MAX_TRIANGLES = 2**28 - 1  # leaf starts are stored in the remaining 28 bits


class BVH(eqx.Module):
    """A flattened binary bounding volume hierarchy over a triangle mesh (arrays only).

    Build one with `build_bvh`; query it with `intersect_closest` / `intersect_any`. All
    array fields share one floating dtype (float32 by default, float64 for float64 input when
    `jax_enable_x64` is on). See the module docstring of `radiometria.render._geometry._bvh` for the
    layout.

    **Fields:**

    - `node_boxes`: `(n, 12)` children boxes of each interior node. [scene length unit]
    - `node_children`: `(n, 2)` int32 child codes.
    - `triangles`: `(f, 9)` corners of the triangles in leaf order. [scene length unit]
    - `prim_ids`: `(f,)` int32 original face index of each reordered triangle.
    - `bounds`: `(2, 3)` scene box `[lo, hi]`. [scene length unit]
    - `stack_size`: static int, the traversal stack depth (the tree depth).
    - `max_leaf_size`: static int, the largest leaf.

    !!! note "Thesis"
        Ch. 8 (ray casting); BVH with the surface area heuristic (`Goldsmith1987`,
        `MacDonald1990`), binned build (`Wald2007`), layout as in `Pharr2023` §7.3.
    """

    node_boxes: Float[Array, "n 12"]
    node_children: Int[Array, "n 2"]
    triangles: Float[Array, "f 9"]
    prim_ids: Int[Array, " f"]
    bounds: Float[Array, "2 3"]
    stack_size: int = eqx.field(static=True)
    max_leaf_size: int = eqx.field(static=True)

    @property
    def n_triangles(self) -> int:
        """Number of triangles."""
        return int(self.triangles.shape[0])

    @property
    def n_nodes(self) -> int:
        """Number of interior nodes."""
        return int(self.node_boxes.shape[0])


def _box_area(lo, hi):
    d = np.maximum(hi - lo, 0.0)
    return 2.0 * (d[..., 0] * d[..., 1] + d[..., 1] * d[..., 2] + d[..., 2] * d[..., 0])


def _target_dtype(vertices: np.ndarray, dtype) -> np.dtype:
    if dtype is None:
        dtype = vertices.dtype if vertices.dtype.kind == "f" else np.float32
    dtype = np.dtype(dtype)
    if dtype.kind != "f":
        raise TypeError(f"`dtype` must be a floating dtype, got {dtype}.")
    # Without x64, JAX stores float64 as float32: build on the values the traversal will see.
    return np.dtype(jax.dtypes.canonicalize_dtype(dtype))


_SWEEP_MAX = 16  # ranges up to this size are split by an exact sweep, larger ones by bins


def _ranges(start, count):
    """Positions in `order` of the concatenated ranges, and each position's range index."""
    offs = np.concatenate([[0], np.cumsum(count)[:-1]])
    item = np.repeat(np.arange(len(count)), count)
    pos = np.repeat(start - offs, count) + np.arange(item.size)
    return pos, item, offs


def _split_binned(order, start, count, clo, chi, cen, lohi, n_bins):
    """Binned SAH (`Wald2007`) on the widest centroid axis of each range; partitions `order`
    in place (stably) and returns the left counts. Ranges whose centroids coincide are split at
    the median index."""
    pos, item, offs = _ranges(start, count)
    tri = order[pos]
    k = len(count)
    ext_all = chi - clo
    axis = np.argmax(ext_all, axis=1)
    ext = ext_all[np.arange(k), axis]
    scale = np.where(ext > 0, n_bins * (1.0 - 1e-12) / np.where(ext > 0, ext, 1.0), 0.0)
    c = cen[tri, axis[item]]
    b = ((c - clo[np.arange(k), axis][item]) * scale[item]).astype(np.int64)
    np.clip(b, 0, n_bins - 1, out=b)
    keys = item * n_bins + b
    counts = np.bincount(keys, minlength=k * n_bins).reshape(k, n_bins)
    bb = np.full((k * n_bins, 6), np.inf, lohi.dtype)
    np.minimum.at(bb, keys, lohi[tri])
    bb = bb.reshape(k, n_bins, 6)
    left = np.minimum.accumulate(bb, axis=1)[:, :-1]
    right = np.minimum.accumulate(bb[:, ::-1], axis=1)[:, ::-1][:, 1:]
    nl = np.cumsum(counts, axis=1)[:, :-1]
    nr = count[:, None] - nl
    with np.errstate(invalid="ignore", over="ignore"):
        cost = _box_area(left[..., :3], -left[..., 3:]) * nl
        cost += _box_area(right[..., :3], -right[..., 3:]) * nr
    cost = np.where((nl > 0) & (nr > 0), cost, np.inf)
    best = np.argmin(cost, axis=1)
    median = ~np.isfinite(cost[np.arange(k), best])  # all centroids in one bin: ext == 0
    rank = np.arange(item.size) - offs[item]
    go_left = np.where(median[item], rank < count[item] // 2, b <= best[item])
    csum = np.cumsum(go_left)
    before = np.concatenate([[0], csum])[offs]
    n_left = csum[np.concatenate([offs[1:], [item.size]]) - 1] - before
    rank_l = csum - 1 - before[item]
    rank_r = rank - (csum - before[item])
    order[start[item] + np.where(go_left, rank_l, n_left[item] + rank_r)] = tri
    return n_left


def _split_sweep(order, start, count, cen, lohi):
    """Exact sweep SAH over all three axes for small ranges (<= `_SWEEP_MAX` triangles), padded
    to a fixed width so that all ranges of a level are processed at once. Sorts each range along
    its best axis in place and returns the left counts."""
    k = len(count)
    width = int(count.max())
    slot = np.arange(width)
    valid = slot[None, :] < count[:, None]
    pos = np.where(valid, start[:, None] + slot, 0)
    tri = order[pos]
    best_cost = np.full(k, np.inf)
    best_axis = np.zeros(k, np.int64)
    best_pos = np.zeros(k, np.int64)
    nl = slot[None, :-1] + 1
    nr = count[:, None] - nl
    sorted_slots = []
    for a in range(3):
        c = np.where(valid, cen[tri, a], np.inf)
        idx = np.argsort(c, axis=1, kind="stable")
        sorted_slots.append(idx)
        box = np.where(valid[..., None], lohi[tri], np.inf)
        box = np.take_along_axis(box, idx[..., None], axis=1)
        left = np.minimum.accumulate(box, axis=1)[:, :-1]
        right = np.minimum.accumulate(box[:, ::-1], axis=1)[:, ::-1][:, 1:]
        with np.errstate(invalid="ignore", over="ignore"):
            cost = _box_area(left[..., :3], -left[..., 3:]) * nl
            cost += _box_area(right[..., :3], -right[..., 3:]) * nr
        cost = np.where(nr > 0, np.nan_to_num(cost, nan=np.inf), np.inf)
        p = np.argmin(cost, axis=1)
        cp = cost[np.arange(k), p]
        better = cp < best_cost
        best_cost = np.where(better, cp, best_cost)
        best_axis = np.where(better, a, best_axis)
        best_pos = np.where(better, p, best_pos)
    idx = np.stack(sorted_slots)[best_axis, np.arange(k)]
    tri_sorted = np.take_along_axis(tri, idx, axis=1)
    order[pos[valid]] = tri_sorted[valid]
    return best_pos + 1


def build_bvh(
    vertices: ArrayLike,
    faces: ArrayLike,
    *,
    max_leaf_size: int = 4,
    n_bins: int = 16,
    dtype=None,
) -> BVH:
    r"""Build a BVH over a triangle mesh with the binned surface area heuristic (NumPy, offline).

    A node with at most `max_leaf_size` triangles becomes a leaf (small leaves suit the
    lockstep traversal, which tests one triangle per iteration). A larger node is split where
    the surface area heuristic cost $C = A_L N_L + A_R N_R$ is least: nodes of more than 16
    triangles at the best of `n_bins - 1` planes between centroid bins along the widest
    centroid axis (`Wald2007`), smaller ones at the best of all object splits along all three
    axes (an exact sweep). A node whose triangle centroids all coincide is split at the median
    index.

    **Arguments:**

    - `vertices`: `(v, 3)` vertex positions. [scene length unit]
    - `faces`: `(f, 3)` integer vertex indices, `f < 2^28`.
    - `max_leaf_size`: largest leaf, 1 to 8 (default 4).
    - `n_bins`: SAH bins per axis and node, >= 2 (default 16).
    - `dtype`: floating dtype of the stored arrays; defaults to that of `vertices`
        (float32 when JAX's x64 mode is off).

    **Returns:**

    A `BVH`. Degenerate triangles are kept (they are never hit).

    !!! note "Thesis"
        Ch. 8 (ray casting); `Wald2007` (binned SAH), `MacDonald1990` (SAH), `Pharr2023` §7.3.
    """
    v_in = np.asarray(vertices)
    f_in = np.asarray(faces)
    if v_in.ndim != 2 or v_in.shape[1] != 3:
        raise ValueError(f"`vertices` must have shape (v, 3), got {v_in.shape}.")
    if f_in.ndim != 2 or f_in.shape[1] != 3 or f_in.dtype.kind not in "iu":
        raise ValueError(
            f"`faces` must be integers of shape (f, 3), got {f_in.dtype} {f_in.shape}."
        )
    if not (isinstance(max_leaf_size, int) and 1 <= max_leaf_size <= _MAX_LEAF):
        raise ValueError(
            f"`max_leaf_size` must be an int in [1, {_MAX_LEAF}], got {max_leaf_size!r}."
        )
    if not (isinstance(n_bins, int) and n_bins >= 2):
        raise ValueError(f"`n_bins` must be an int >= 2, got {n_bins!r}.")
    n_tri = len(f_in)
    if n_tri > _MAX_TRIANGLES:
        raise ValueError(f"at most {_MAX_TRIANGLES} triangles are supported, got {n_tri}.")
    if n_tri and (f_in.min() < 0 or f_in.max() >= len(v_in)):
        raise ValueError(f"`faces` index vertices outside [0, {len(v_in)}).")
    dt = _target_dtype(v_in, dtype)
    v = v_in.astype(dt)
    corners = v[f_in.astype(np.int64)]  # (f, 3, 3), exact in the target dtype
    if not np.all(np.isfinite(corners)):
        raise ValueError("`vertices` used by `faces` must be finite.")
    lo = corners.min(axis=1)
    hi = corners.max(axis=1)
    cen = 0.5 * (lo.astype(np.float64) + hi.astype(np.float64))
    lohi = np.concatenate([lo, -hi], axis=1)  # min-reduce both bounds at once

    order = np.arange(n_tri, dtype=np.int64)
    max_nodes = max(n_tri, 1)
    boxes = np.empty((max_nodes, 12), dt)
    boxes[:, 0:3] = boxes[:, 6:9] = np.inf
    boxes[:, 3:6] = boxes[:, 9:12] = -np.inf
    children = np.full((max_nodes, 2), EMPTY, np.int32)
    n_nodes = 1  # node 0 (the root) always exists

    # The work list of one level: contiguous ranges of `order` and where their parent points.
    if n_tri:
        q_start = np.array([0])
        q_count = np.array([n_tri])
        q_parent = np.array([-1])
        q_side = np.array([0])
        scene_lo, scene_hi = lo.min(0), hi.max(0)
        q_clo, q_chi = cen.min(0)[None], cen.max(0)[None]
    else:
        q_start = np.zeros(0, np.int64)
        scene_lo = np.full(3, np.inf, dt)
        scene_hi = np.full(3, -np.inf, dt)
    depth = 1
    while len(q_start):
        is_root = q_parent < 0
        leaf = q_count <= max_leaf_size
        if leaf[0] and is_root[0]:  # everything fits in one leaf under an interior root
            children[0, 0] = ~np.int32((q_start[0] << 3) | (q_count[0] - 1))
            boxes[0, 0:3], boxes[0, 3:6] = scene_lo, scene_hi
            break
        # ---- leaves: their parent points to the triangle range ---------------------------
        li = np.nonzero(leaf)[0]
        if len(li):
            codes = ~((q_start[li] << 3) | (q_count[li] - 1)).astype(np.int32)
            children[q_parent[li], q_side[li]] = codes
        # ---- splits: new interior nodes ----------------------------------------------------
        si = np.nonzero(~leaf)[0]
        if not len(si):
            break
        new_ids = np.zeros(len(si), np.int64)
        nonroot = ~is_root[si]
        new_ids[nonroot] = n_nodes + np.arange(int(nonroot.sum()))
        n_nodes += int(nonroot.sum())
        children[q_parent[si][nonroot], q_side[si][nonroot]] = new_ids[nonroot]
        n_left = np.zeros(len(si), np.int64)
        big = q_count[si] > _SWEEP_MAX
        if np.any(big):
            bi = si[big]
            n_left[big] = _split_binned(
                order, q_start[bi], q_count[bi], q_clo[bi], q_chi[bi], cen, lohi, n_bins
            )
        if not np.all(big):
            sm = si[~big]
            n_left[~big] = _split_sweep(order, q_start[sm], q_count[sm], cen, lohi)
        # ---- children ranges, in `order` sequence: [left_0, right_0, left_1, ...] ---------
        cnt = q_count[si]
        c_start = np.stack([q_start[si], q_start[si] + n_left], 1).ravel()
        c_count = np.stack([n_left, cnt - n_left], 1).ravel()
        c_parent = np.repeat(new_ids, 2)
        c_side = np.tile([0, 1], len(si))
        c_offs = np.concatenate([[0], np.cumsum(c_count)[:-1]])
        pos = np.repeat(c_start - c_offs, c_count) + np.arange(int(c_count.sum()))
        tri = order[pos]
        c_lo = np.minimum.reduceat(lo[tri], c_offs)
        c_hi = np.maximum.reduceat(hi[tri], c_offs)
        c_cen = cen[tri]
        q_clo = np.minimum.reduceat(c_cen, c_offs)
        q_chi = np.maximum.reduceat(c_cen, c_offs)
        rows = np.repeat(c_parent, 3)
        cols_lo = (c_side[:, None] * 6 + np.arange(3)).ravel()
        boxes[rows, cols_lo] = c_lo.ravel()
        boxes[rows, cols_lo + 3] = c_hi.ravel()
        q_start, q_count, q_parent, q_side = c_start, c_count, c_parent, c_side
        depth += 1
    tri = corners[order].reshape(n_tri, 9)
    prim = order.astype(np.int32)
    if n_tri == 0:  # one degenerate stand-in keeps the gathers valid; no leaf points at it
        tri, prim = np.zeros((1, 9), dt), np.zeros(1, np.int32)
    return BVH(
        node_boxes=jnp.asarray(boxes[:n_nodes]),
        node_children=jnp.asarray(children[:n_nodes]),
        triangles=jnp.asarray(tri),
        prim_ids=jnp.asarray(prim),
        bounds=jnp.asarray(np.stack([scene_lo, scene_hi]).astype(dt)),
        stack_size=int(depth),
        max_leaf_size=int(max_leaf_size),
    )
