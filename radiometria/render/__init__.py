"""Light transport (thesis ch. 8-9): meshes, BVH, scenes, integrators and the render driver."""

# --- integrators (helper P) ---
from ._driver import render as render
from ._integrators import (
    direct_radiance as direct_radiance,
    path_radiance as path_radiance,
    sample_dimensions as sample_dimensions,
)
from ._render_scene import RenderScene as RenderScene
from ._spectral import (
    SpectrumTable as SpectrumTable,
    sample_hero_wavelengths as sample_hero_wavelengths,
    wavelength_grid_nm as wavelength_grid_nm,
)
