"""Brute force as an accelerator: every ray against every triangle (thesis ch. 8).

No structure at all: the mesh itself, and a loop over its triangles per batch of rays. For a
few dozen triangles (the Cornell box) this is the fastest query, faster than any traversal;
`build_accelerator` picks it up to `BRUTE_FORCE_MAX_TRIANGLES` triangles.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..._checks import device_array
from .._geometry._backends import AbstractTraversalBackend
from .._geometry._brute_force import intersect_brute_force_any, intersect_brute_force_closest
from .._geometry._mesh import TriangleMesh
from .._geometry._registry import check_backend
from ._base import AbstractAccelerator

__all__ = ["BruteForceAccelerator"]


class BruteForceAccelerator(AbstractAccelerator):
    """The triangle mesh, queried by brute force (`intersect_brute_force_closest`).

    **Fields:**

    - `mesh`: the `TriangleMesh`, in the dtype of the queries. [scene length unit]
    - `backend`: the traversal back end (static): `"auto"` (resolved when the query is
        traced: the native CPU kernel on the CPU where it is available, else the JAX loop),
        `"native"`, `"jax"` or a back-end object.

    Cost O(rays x triangles).

    !!! note "Thesis"
        Ch. 8 (ray casting); the watertight test of `Woop2013`.

    ??? cite "References"
        `Pharr2023` §7.3 (why aggregates pay off only beyond a few dozen primitives).
    """

    mesh: TriangleMesh
    backend: str | AbstractTraversalBackend = eqx.field(static=True, default="auto")

    def __check_init__(self):
        check_backend(self.backend)

    @classmethod
    def from_triangles(cls, vertices, faces, *, dtype=jnp.float32) -> "BruteForceAccelerator":
        vertices = np.asarray(vertices, dtype=np.float64)
        return cls(mesh=TriangleMesh(device_array(vertices, dtype=dtype), np.asarray(faces)))

    def intersect_closest(self, origins, directions, t_max):
        return intersect_brute_force_closest(
            self.mesh, origins, directions, t_max, backend=self.backend
        )

    def intersect_any(self, origins, directions, t_max):
        return intersect_brute_force_any(
            self.mesh, origins, directions, t_max, backend=self.backend
        )
