"""Traversal back ends: who runs the four ray queries, as strategy objects (thesis ch. 8).

A back end is a fieldless `equinox.Module`, so it is hashable and can be a static argument of
`jax.jit`; the queries of `_queries.py` and `_brute_force.py` trace `backend.bvh_closest(...)`
and its siblings inside one compiled program. The back ends are registered, in preference
order, in `_registry.TRAVERSAL_BACKENDS`; `resolve_backend("auto")` takes the first one that
runs on the default JAX platform and is available. A new back end (a GPU kernel, say) is one
file with a subclass of `AbstractTraversalBackend` and one line in the registry.

Every back end must give the same hits as the others: the same triangle, `t` and
barycentrics, with the tie rules of `intersect_closest` (ties in `t` go to the lowest face
index), and the arithmetic of `_triangle._triangle_test` operation for operation.
"""

import abc

import equinox as eqx
from jaxtyping import Array, Bool, Float

from ._bvh import BVH
from ._triangle import Hit

__all__ = ["AbstractTraversalBackend"]


class AbstractTraversalBackend(eqx.Module):
    """How the BVH traversal and the brute-force queries run: one implementation of the four.

    Subclasses have no fields (so that equal back ends compare and hash equal) and set the
    class variable `platforms`. Every method is traced inside `jax.jit`; the arrays are
    already checked and cast to the geometry's dtype (`_rays._check_rays`).

    **Arrays of the methods:**

    - `bvh`: a `BVH` (`build_bvh`).
    - `tri`: `(f, 9)` triangle corners `v0, v1, v2` in face order. [scene length unit]
    - `o`, `d`: `(n, 3)` ray origins and directions. [scene length unit]
    - `tmin`, `tmax`: `(n,)` exclusive limits of the ray parameter. [direction lengths]

    The closest-hit methods return a `Hit` (`prim = -1`, `t = inf`, zero barycentrics for a
    miss); the any-hit methods return `(n,)` bool, True where a triangle lies in the interval.

    !!! note "Thesis"
        Ch. 8 (ray casting).

    ??? cite "References"
        `Pharr2023` §7.3.5 (BVH traversal); `Woop2013` (watertight test); `Ize2013` (robust
        box test); `Aila2009` (traversal on wide hardware).
    """

    platforms: eqx.AbstractClassVar[tuple[str, ...]]
    """JAX platforms (`jax.default_backend()`) where `"auto"` may pick this back end; `"*"`
    is every platform."""

    @abc.abstractmethod
    def available(self) -> tuple[bool, str]:
        """`(available, reason)`: whether this back end can run in this process, and why."""

    @abc.abstractmethod
    def bvh_closest(
        self,
        bvh: BVH,
        o: Float[Array, "n 3"],
        d: Float[Array, "n 3"],
        tmin: Float[Array, " n"],
        tmax: Float[Array, " n"],
    ) -> Hit:
        """Closest hit of each ray, by traversing `bvh`."""

    @abc.abstractmethod
    def bvh_any(
        self,
        bvh: BVH,
        o: Float[Array, "n 3"],
        d: Float[Array, "n 3"],
        tmin: Float[Array, " n"],
        tmax: Float[Array, " n"],
    ) -> Bool[Array, " n"]:
        """Whether each ray hits a triangle of `bvh` in `(tmin, tmax)`."""

    @abc.abstractmethod
    def brute_closest(
        self,
        tri: Float[Array, "f 9"],
        o: Float[Array, "n 3"],
        d: Float[Array, "n 3"],
        tmin: Float[Array, " n"],
        tmax: Float[Array, " n"],
    ) -> Hit:
        """Closest hit of each ray, testing every triangle of `tri`."""

    @abc.abstractmethod
    def brute_any(
        self,
        tri: Float[Array, "f 9"],
        o: Float[Array, "n 3"],
        d: Float[Array, "n 3"],
        tmin: Float[Array, " n"],
        tmax: Float[Array, " n"],
    ) -> Bool[Array, " n"]:
        """Whether each ray hits any triangle of `tri` in `(tmin, tmax)`."""
