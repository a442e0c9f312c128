"""Scene input (thesis ch. 8): descriptions, the JSON and Mitsuba 3 XML formats, mesh files,
the built-in scenes, and the compilation of a description into the renderer's plugins."""

from ._compile import (
    clear_compiled_scenes as clear_compiled_scenes,
    compile_scene as compile_scene,
    compile_scene_cached as compile_scene_cached,
    scene_filter as scene_filter,
    scene_integrator as scene_integrator,
    scene_sampler as scene_sampler,
)
from ._description import (
    AreaEmitter as AreaEmitter,
    CameraDescription as CameraDescription,
    FilmDescription as FilmDescription,
    Material as Material,
    SceneDescription as SceneDescription,
    SceneError as SceneError,
    SphereShape as SphereShape,
)
from ._load import BUILTIN_SCENES as BUILTIN_SCENES, load_scene as load_scene
from ._mesh_files import load_mesh as load_mesh
from ._mitsuba_xml import load_mitsuba_xml as load_mitsuba_xml
