"""Ray queries against a BVH: closest hit and any hit (thesis ch. 8).

`intersect_closest` and `intersect_any` check the rays, choose a traversal back end
(`_registry.resolve_backend`), and run it in one compiled program. Eager calls (outside
`jit`) pad the BVH and the rays to size buckets first (`_rays.py`), so that scenes and ray
batches of similar sizes share one compiled program.
"""

import equinox as eqx
from jaxtyping import Array, ArrayLike, Bool

from ._backends import AbstractTraversalBackend
from ._bvh import BVH
from ._rays import _check_rays, _is_concrete, _pad_bvh, _pad_rays, _slice_hit
from ._registry import resolve_backend
from ._triangle import Hit

__all__ = ["intersect_any", "intersect_closest"]


@eqx.filter_jit
def _closest(bvh, o, d, tmin, tmax, backend: AbstractTraversalBackend) -> Hit:
    return backend.bvh_closest(bvh, o, d, tmin, tmax)


@eqx.filter_jit
def _any(bvh, o, d, tmin, tmax, backend: AbstractTraversalBackend):
    return backend.bvh_any(bvh, o, d, tmin, tmax)


def _query(fn, bvh: BVH, o, d, tmin, tmax, backend: str | AbstractTraversalBackend):
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
    backend: str | AbstractTraversalBackend = "auto",
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
        traversal), `"native"` or `"jax"`, or a traversal back-end object. All give the same
        hits.

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
    backend: str | AbstractTraversalBackend = "auto",
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
        traversal), `"native"` or `"jax"`, or a traversal back-end object. All give the same
        hits.

    **Returns:**

    `(n,)` bool.

    !!! note "Thesis"
        Ch. 8 (visibility in next-event estimation); `Woop2013`, `Pharr2023` §7.3.5.
    """
    if not isinstance(bvh, BVH):
        raise TypeError(f"`bvh` must be a BVH (see build_bvh), got {type(bvh).__name__}.")
    o, d, tmin, tmax = _check_rays(origins, directions, t_max, bvh.triangles.dtype, t_min)
    return _query(_any, bvh, o, d, tmin, tmax, backend)
