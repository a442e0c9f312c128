"""Shapes, ray-triangle intersection and traversal back ends (thesis ch. 8).

One concept per module: `_mesh` (triangle meshes), `_bvh` (the BVH build), `_triangle` (the
watertight test and `Hit`), `_rays` (argument checks, eager-call padding), `_backends` (the
abstract traversal back end), `_traversal` (the JAX back end), `_native` (the native CPU back
end and its C++ kernel in `_csrc/`), `_registry` (the back ends by name), `_brute_force` and
`_queries` (the public queries).
"""

from ._backends import AbstractTraversalBackend as AbstractTraversalBackend
from ._brute_force import (
    intersect_brute_force_any as intersect_brute_force_any,
    intersect_brute_force_closest as intersect_brute_force_closest,
)
from ._bvh import BVH as BVH, build_bvh as build_bvh
from ._mesh import (
    TriangleMesh as TriangleMesh,
    icosphere as icosphere,
    sample_triangle_point as sample_triangle_point,
    triangle_areas as triangle_areas,
    triangle_normals as triangle_normals,
)
from ._native import NativeCPUTraversal as NativeCPUTraversal, native_status as native_status
from ._queries import intersect_any as intersect_any, intersect_closest as intersect_closest
from ._registry import TRAVERSAL_BACKENDS as TRAVERSAL_BACKENDS, resolve_backend as resolve_backend
from ._traversal import JaxTraversal as JaxTraversal
from ._triangle import Hit as Hit
