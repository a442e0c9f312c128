"""Moved to `radiometria.render._geometry._bvh`; re-exported here until render/ is restructured."""

from ._geometry._bvh import BVH as BVH, EMPTY as EMPTY, build_bvh as build_bvh
