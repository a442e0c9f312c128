"""The abstract accelerator: what the path tracer asks of the scene's geometry (thesis ch. 8).

An accelerator holds the triangles of a scene in the layout that one family of ray queries
reads (a BVH, or the plain mesh for brute force) and answers the two queries of a path
tracer: the closest hit of each ray, and whether a shadow ray is occluded. Both are called
inside the jitted integrators, on `(n, 3)` batches of rays.
"""

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Bool, Float, Int

from .._geometry._triangle import Hit

__all__ = ["AbstractAccelerator"]


class AbstractAccelerator(eqx.Module):
    """A ray-casting acceleration structure over a triangle mesh (a pytree of arrays).

    Final subclasses hold their arrays as fields and implement the two queries and
    `from_triangles`. Both queries return the same hits as the brute-force reference
    (`intersect_brute_force_closest`): the same triangle and `t`, ties in `t` to the lowest
    face index.

    !!! note "Thesis"
        Ch. 8 (ray casting in the light transport loop).

    ??? cite "References"
        `Pharr2023` §7.1-7.3 (primitives and aggregates, bounding volume hierarchies).
    """

    @classmethod
    @abc.abstractmethod
    def from_triangles(
        cls,
        vertices: Float[ArrayLike, "v 3"],
        faces: Int[ArrayLike, "f 3"],
        *,
        dtype=jnp.float32,
    ) -> "AbstractAccelerator":
        """Build the accelerator (NumPy work, done once, outside `jit`).

        **Arguments:**

        - `vertices`: `(v, 3)` vertex positions, float64. [scene length unit]
        - `faces`: `(f, 3)` integer vertex indices of each triangle.
        - `dtype`: floating dtype of the stored triangles (float32 by default).
        """

    @abc.abstractmethod
    def intersect_closest(
        self,
        origins: Float[ArrayLike, "n 3"],
        directions: Float[ArrayLike, "n 3"],
        t_max: ArrayLike,
    ) -> Hit:
        """Closest hit of each ray with `0 < t < t_max`.

        **Arguments:**

        - `origins`: `(n, 3)` ray origins. [scene length unit]
        - `directions`: `(n, 3)` ray directions, not necessarily unit. [scene length unit]
        - `t_max`: `(n,)` (or scalar) exclusive upper limit of the ray parameter.
            [direction lengths]

        **Returns:**

        A `Hit`: `t (n,)` (inf for a miss), `prim (n,)` int32 face index (-1 for a miss) and
        the barycentrics `b1, b2 (n,)`.
        """

    @abc.abstractmethod
    def intersect_any(
        self,
        origins: Float[ArrayLike, "n 3"],
        directions: Float[ArrayLike, "n 3"],
        t_max: ArrayLike,
    ) -> Bool[Array, " n"]:
        """Whether anything lies on each ray segment `0 < t < t_max` (shadow rays).

        **Arguments:**

        - `origins`: `(n, 3)` ray origins. [scene length unit]
        - `directions`: `(n, 3)` ray directions. [scene length unit]
        - `t_max`: `(n,)` (or scalar) exclusive upper limit, e.g. the distance to a light
            sample. [direction lengths]

        **Returns:**

        `(n,)` bool, True where the segment is occluded.
        """
