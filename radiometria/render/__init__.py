"""Light transport (thesis ch. 8-9): a spectral path tracer built from plugins.

Every renderer concept is an abstract `equinox` Module with final implementations, one per
file, in a folder that shows the architecture (the model of diffrax's `_solver/`):

- `_integrators/`: `AbstractIntegrator` (`Path`, `Direct`, `VolPath`, `VolPathMIS`, `PTracer`,
  `BDPT`, `PSSMLT`);
- `_samplers/`: `AbstractSampler` (`Independent`, `OwenSobol`);
- `_materials/`: `AbstractMaterial`, BSDF plugins that build `radiometria.scattering` BxDFs
  (`Diffuse`, `OrenNayar`, `Conductor`, `RoughConductor`, `Dielectric`, `RoughDielectric`);
- `_lights/`: `AbstractLight` (`AreaLight`); `_textures/`: `AbstractTexture`
  (`ConstantTexture`);
- `_accelerators/`: `AbstractAccelerator` (`BruteForceAccelerator`, `BVHAccelerator`), with
  the traversal back ends of `_geometry/` (native CPU kernel, JAX) inside;
- cameras are `radiometria.camera.AbstractCamera`s, media and phase functions
  `radiometria.media.AbstractMedium` / `AbstractPhaseFunction`;
- `_scenes/`: scene descriptions, the JSON and Mitsuba 3 XML formats, `compile_scene`;
- `_registry.py`: the names scene files and the command line use, one registry per concept;
- `_driver.py`: `render`, the batched, device-sharded render loop;
- `_bdpt_strategies.py`: `bdpt_strategy_images`, the image of each bidirectional strategy;
- `_cache.py`: `enable_compilation_cache`, JAX's persistent compilation cache on disk.
"""

from ._accelerators import (
    AbstractAccelerator as AbstractAccelerator,
    BruteForceAccelerator as BruteForceAccelerator,
    BVHAccelerator as BVHAccelerator,
    build_accelerator as build_accelerator,
)
from ._bdpt_strategies import bdpt_strategy_images as bdpt_strategy_images
from ._cache import (
    CompilationCacheInfo as CompilationCacheInfo,
    clear_compilation_cache as clear_compilation_cache,
    compilation_cache_dir as compilation_cache_dir,
    compilation_cache_info as compilation_cache_info,
    enable_compilation_cache as enable_compilation_cache,
)
from ._checkpoint import CheckpointError as CheckpointError
from ._driver import RenderInterrupted as RenderInterrupted, render as render
from ._geometry import (
    BVH as BVH,
    AbstractTraversalBackend as AbstractTraversalBackend,
    Hit as Hit,
    JaxTraversal as JaxTraversal,
    NativeCPUTraversal as NativeCPUTraversal,
    TriangleMesh as TriangleMesh,
    build_bvh as build_bvh,
    icosphere as icosphere,
    intersect_any as intersect_any,
    intersect_brute_force_any as intersect_brute_force_any,
    intersect_brute_force_closest as intersect_brute_force_closest,
    intersect_closest as intersect_closest,
    native_status as native_status,
    sample_triangle_point as sample_triangle_point,
    triangle_areas as triangle_areas,
    triangle_normals as triangle_normals,
)
from ._integrators import (
    BDPT as BDPT,
    PSSMLT as PSSMLT,
    AbstractIntegrator as AbstractIntegrator,
    Direct as Direct,
    Path as Path,
    PTracer as PTracer,
    VolPath as VolPath,
    VolPathMIS as VolPathMIS,
    path_radiance as path_radiance,
    sample_dimensions as sample_dimensions,
)
from ._lights import (
    AbstractLight as AbstractLight,
    AreaLight as AreaLight,
    LightSample as LightSample,
)
from ._materials import (
    MITSUBA_IOR as MITSUBA_IOR,
    AbstractMaterial as AbstractMaterial,
    Conductor as Conductor,
    Dielectric as Dielectric,
    Diffuse as Diffuse,
    MaterialSet as MaterialSet,
    OrenNayar as OrenNayar,
    RoughConductor as RoughConductor,
    RoughDielectric as RoughDielectric,
    ScaledBxDF as ScaledBxDF,
)
from ._render_scene import RenderScene as RenderScene
from ._samplers import (
    AbstractSampler as AbstractSampler,
    Independent as Independent,
    OwenSobol as OwenSobol,
    sampler_seed as sampler_seed,
)
from ._scenes import (
    AreaEmitter as AreaEmitter,
    CameraDescription as CameraDescription,
    FilmDescription as FilmDescription,
    Material as Material,
    SceneDescription as SceneDescription,
    SceneError as SceneError,
    SphereShape as SphereShape,
    compile_scene as compile_scene,
    load_mesh as load_mesh,
    load_mitsuba_xml as load_mitsuba_xml,
    load_scene as load_scene,
    scene_integrator as scene_integrator,
)
from ._spectral import (
    LinearRGB as LinearRGB,
    SpectrumTable as SpectrumTable,
    sample_hero_wavelengths as sample_hero_wavelengths,
    tabulate_spectrum as tabulate_spectrum,
    wavelength_grid_nm as wavelength_grid_nm,
)
from ._textures import AbstractTexture as AbstractTexture, ConstantTexture as ConstantTexture
