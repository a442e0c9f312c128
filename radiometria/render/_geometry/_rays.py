"""Argument checks of the ray queries, and the size buckets of eager calls (thesis ch. 8).

Every query casts its rays to the geometry's dtype and broadcasts `t_min`, `t_max` to one value
per ray (`_check_rays`). Outside `jit`, a call pads its rays, triangles and BVH arrays to a
size bucket (`_bucket`), so that meshes and ray batches of similar sizes share one compiled
program (each traversal compile costs seconds); padded rays have an empty interval and padded
triangles and nodes are never reached.
"""

import jax
import jax.numpy as jnp
import numpy as np

from ._bvh import BVH, EMPTY
from ._triangle import Hit

_MIN_RAYS = 1024  # smallest ray bucket of eager calls
_MIN_TRIANGLES = 64  # smallest triangle bucket of eager calls


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
