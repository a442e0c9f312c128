"""Light transport (thesis ch. 8-9): meshes, BVH, scenes, integrators and the render driver."""

# --- geometry (helper G) ---
from ._bvh import BVH as BVH, build_bvh as build_bvh
from ._intersect import (
    Hit as Hit,
    intersect_any as intersect_any,
    intersect_brute_force_any as intersect_brute_force_any,
    intersect_brute_force_closest as intersect_brute_force_closest,
    intersect_closest as intersect_closest,
)
from ._loaders import load_mesh as load_mesh, load_mitsuba_xml as load_mitsuba_xml
from ._mesh import (
    TriangleMesh as TriangleMesh,
    icosphere as icosphere,
    sample_triangle_point as sample_triangle_point,
    triangle_areas as triangle_areas,
    triangle_normals as triangle_normals,
)
from ._native import native_status as native_status
from ._scene import (
    AreaEmitter as AreaEmitter,
    CameraDescription as CameraDescription,
    FilmDescription as FilmDescription,
    Material as Material,
    SceneDescription as SceneDescription,
    SceneError as SceneError,
    load_scene as load_scene,
)

# isort: split

# --- integrators (helper P) ---
from ._driver import render as render
from ._integrators import (
    direct_radiance as direct_radiance,
    path_radiance as path_radiance,
    sample_dimensions as sample_dimensions,
)
from ._materials import MaterialTables as MaterialTables
from ._render_scene import RenderScene as RenderScene, compile_scene as compile_scene
from ._spectral import (
    SpectrumTable as SpectrumTable,
    sample_hero_wavelengths as sample_hero_wavelengths,
    spectrum_values as spectrum_values,
    wavelength_grid_nm as wavelength_grid_nm,
)
