"""Moved to `radiometria.render._geometry._mesh`; re-exported here until render/ is restructured."""

from ._geometry._mesh import (
    TriangleMesh as TriangleMesh,
    _areas as _areas,
    _corners as _corners,
    icosphere as icosphere,
    merge_meshes as merge_meshes,
    sample_triangle_point as sample_triangle_point,
    triangle_areas as triangle_areas,
    triangle_normals as triangle_normals,
    validate_triangles as validate_triangles,
)
