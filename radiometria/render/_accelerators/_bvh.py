"""A bounding volume hierarchy as an accelerator (thesis ch. 8).

The binned-SAH BVH of `build_bvh`, traversed near child first with a fixed-depth stack
(`intersect_closest`, `intersect_any`): O(log f) triangle tests per ray instead of O(f).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._geometry._backends import AbstractTraversalBackend
from .._geometry._bvh import BVH, build_bvh
from .._geometry._queries import intersect_any, intersect_closest
from .._geometry._registry import check_backend
from ._base import AbstractAccelerator

__all__ = ["BVHAccelerator"]


class BVHAccelerator(AbstractAccelerator):
    """A BVH over the triangles, queried by traversal (`intersect_closest`).

    **Fields:**

    - `bvh`: the `BVH` (`build_bvh`), in the dtype of the queries. [scene length unit]
    - `backend`: the traversal back end (static): `"auto"` (resolved when the query is
        traced: the native CPU traversal on the CPU where it is available, else the lockstep
        JAX traversal), `"native"`, `"jax"` or a back-end object.

    !!! note "Thesis"
        Ch. 8 (ray casting).

    ??? cite "References"
        `Pharr2023` §7.3 (bounding volume hierarchies); `Wald2007` (binned SAH build);
        `Aila2009` (traversal); `Woop2013`; `Ize2013`.
    """

    bvh: BVH
    backend: str | AbstractTraversalBackend = eqx.field(static=True, default="auto")

    def __check_init__(self):
        check_backend(self.backend)

    @classmethod
    def from_triangles(cls, vertices, faces, *, dtype=jnp.float32) -> "BVHAccelerator":
        vertices = np.asarray(vertices, dtype=np.float64)
        return cls(bvh=build_bvh(vertices.astype(np.dtype(dtype)), np.asarray(faces)))

    def intersect_closest(self, origins, directions, t_max):
        return intersect_closest(self.bvh, origins, directions, t_max, backend=self.backend)

    def intersect_any(self, origins, directions, t_max):
        return intersect_any(self.bvh, origins, directions, t_max, backend=self.backend)
