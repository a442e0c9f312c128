"""Accelerators: the scene geometry as ray-casting structures, one per file (thesis ch. 8).

`AbstractAccelerator` (`_base.py`) is what the integrators query; `BVHAccelerator` (`_bvh.py`)
and `BruteForceAccelerator` (`_brute_force.py`) implement it; `SphereAccelerator`
(`_spheres.py`) wraps one of them together with analytic spheres. `ACCELERATORS` lists them by
name, and `build_accelerator` (`_build.py`) builds the one a scene asks for (or the best for
its size). A new accelerator is one file with a subclass and one line in `ACCELERATORS`.
"""

from ._base import AbstractAccelerator as AbstractAccelerator
from ._brute_force import BruteForceAccelerator as BruteForceAccelerator
from ._build import (
    ACCELERATORS as ACCELERATORS,
    BRUTE_FORCE_MAX_TRIANGLES as BRUTE_FORCE_MAX_TRIANGLES,
    build_accelerator as build_accelerator,
    check_triangle_arrays as check_triangle_arrays,
)
from ._bvh import BVHAccelerator as BVHAccelerator
from ._spheres import SphereAccelerator as SphereAccelerator
