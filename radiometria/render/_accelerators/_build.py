"""`build_accelerator`: the triangle accelerator a scene asks for, by name (thesis ch. 8)."""

from collections.abc import Mapping
from types import MappingProxyType

import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from ..._checks import check_choice
from ._base import AbstractAccelerator
from ._brute_force import BruteForceAccelerator
from ._bvh import BVHAccelerator

__all__ = [
    "ACCELERATORS",
    "BRUTE_FORCE_MAX_TRIANGLES",
    "build_accelerator",
    "check_triangle_arrays",
]

BRUTE_FORCE_MAX_TRIANGLES = 64
"""`build_accelerator(kind="auto")` uses brute force up to this many triangles, else a BVH."""

ACCELERATORS: Mapping[str, type[AbstractAccelerator]] = MappingProxyType(
    {
        "bvh": BVHAccelerator,
        "brute_force": BruteForceAccelerator,
    }
)
"""The accelerators by name (the `accelerator` option of scenes)."""


def check_triangle_arrays(vertices: ArrayLike, faces: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """`(vertices (v, 3) float64, faces (f, 3) int)` as NumPy arrays, or a `ValueError` naming
    the argument and its shape (static checks, before anything is built)."""
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise ValueError(f"`vertices` must have shape (v, 3), got {vertices.shape}.")
    if faces.ndim != 2 or faces.shape[1] != 3 or faces.dtype.kind not in "iu":
        raise ValueError(f"`faces` must be integer (f, 3), got {faces.dtype} {faces.shape}.")
    return vertices, faces


def build_accelerator(
    vertices: ArrayLike,
    faces: ArrayLike,
    *,
    kind: str = "auto",
    dtype=jnp.float32,
) -> AbstractAccelerator:
    """Build the ray-casting accelerator of a triangle mesh (NumPy work, outside `jit`).

    **Arguments:**

    - `vertices`: `(v, 3)` vertex positions, converted to float64 before the build.
        [scene length unit]
    - `faces`: `(f, 3)` integer vertex indices of each triangle.
    - `kind`: `"auto"` (brute force up to `BRUTE_FORCE_MAX_TRIANGLES` triangles, where it is
        fastest, such as the Cornell box; a BVH above), or a name in `ACCELERATORS`:
        `"bvh"` or `"brute_force"`.
    - `dtype`: floating dtype of the stored triangles (float32 by default).

    **Returns:**

    An `AbstractAccelerator`: a `BVHAccelerator` or a `BruteForceAccelerator`.

    **Raises:**

    `ValueError` for an unknown `kind` (the message lists the valid ones) or for vertex and
    face arrays of the wrong shape.

    !!! note "Thesis"
        Ch. 8 (ray casting).

    ??? cite "References"
        `Pharr2023` §7.3 (bounding volume hierarchies).
    """
    check_choice(kind, "accelerator", ("auto", *ACCELERATORS))
    vertices, faces = check_triangle_arrays(vertices, faces)
    if kind == "auto":
        kind = "brute_force" if faces.shape[0] <= BRUTE_FORCE_MAX_TRIANGLES else "bvh"
    return ACCELERATORS[kind].from_triangles(vertices, faces, dtype=dtype)
