"""Brute-force ray queries: every ray against every triangle (thesis ch. 8).

For tests (the reference that the BVH traversal must match) and for tiny scenes such as the
Cornell box, where testing a few dozen triangles beats any traversal. The work runs in a
traversal back end (`_backends.py`): a loop over the triangles in JAX (`_traversal.py`), or
the native CPU kernel vectorised over blocks of rays (`_native.py`).
"""

import functools

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Bool

from ._backends import AbstractTraversalBackend
from ._bvh import BVH
from ._mesh import TriangleMesh
from ._rays import (
    _MIN_TRIANGLES,
    _bucket,
    _check_rays,
    _is_concrete,
    _pad_rays,
    _pad_rows,
    _slice_hit,
)
from ._registry import resolve_backend
from ._triangle import Hit

__all__ = ["intersect_brute_force_any", "intersect_brute_force_closest"]


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


@functools.partial(jax.jit, static_argnames="backend")
def _brute_closest(tri, o, d, tmin, tmax, *, backend: AbstractTraversalBackend) -> Hit:
    return backend.brute_closest(tri, o, d, tmin, tmax)


@functools.partial(jax.jit, static_argnames="backend")
def _brute_any(tri, o, d, tmin, tmax, *, backend: AbstractTraversalBackend):
    return backend.brute_any(tri, o, d, tmin, tmax)


def intersect_brute_force_closest(
    geometry: BVH | TriangleMesh,
    origins: ArrayLike,
    directions: ArrayLike,
    t_max: ArrayLike = float("inf"),
    *,
    t_min: ArrayLike = 0.0,
    backend: str | AbstractTraversalBackend = "auto",
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
        `native_status`; else a JAX loop over the triangles), `"native"` or `"jax"`, or a
        traversal back-end object.

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


def intersect_brute_force_any(
    geometry: BVH | TriangleMesh,
    origins: ArrayLike,
    directions: ArrayLike,
    t_max: ArrayLike = float("inf"),
    *,
    t_min: ArrayLike = 0.0,
    backend: str | AbstractTraversalBackend = "auto",
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
        `native_status`; else a JAX loop over the triangles), `"native"` or `"jax"`, or a
        traversal back-end object.

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
