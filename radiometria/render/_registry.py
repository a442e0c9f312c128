"""The renderer's registries: the names scene files and the command line use, mapped to plugins.

Strings name plugins only at the outer boundary (scene files, command-line flags); inside the
library every plugin is an object. Each registry maps a name to a plugin class, so adding a
plugin is one new file (a subclass of the abstract class of its folder) plus one line here.
"""

from ..camera import (
    BoxFilter,
    GaussianFilter,
    LanczosFilter,
    MitchellFilter,
    OrthographicCamera,
    PinholeCamera,
    TentFilter,
    ThinLensCamera,
)
from ._accelerators import ACCELERATORS
from ._integrators import BDPT, PSSMLT, Direct, Path, PTracer, VolPath, VolPathMIS
from ._lights import (
    AreaLight,
    ConstantLight,
    DirectionalLight,
    EnvironmentLight,
    PointLight,
    ProjectorLight,
    SpotLight,
)
from ._materials import (
    BlendBSDF,
    BumpMap,
    Conductor,
    Dielectric,
    Diffuse,
    Mask,
    NormalMap,
    OrenNayar,
    Plastic,
    Principled,
    PrincipledThin,
    RoughConductor,
    RoughDielectric,
    RoughPlastic,
    ThinDielectric,
)
from ._materials._null import Null
from ._media import GridMediumPlugin, HomogeneousMediumPlugin
from ._samplers import Independent, OwenSobol
from ._textures import (
    BitmapTexture,
    CheckerboardTexture,
    ConstantTexture,
    MeshAttributeTexture,
)

__all__ = [
    "ACCELERATORS",  # from _accelerators
    "CAMERAS",
    "FILTERS",
    "INTEGRATORS",
    "LIGHTS",
    "MATERIALS",
    "MEDIA",
    "SAMPLERS",
    "SAMPLER_ALIASES",
    "TEXTURES",
]


def _by_name(*plugins) -> dict:
    return {p.NAME: p for p in plugins}


# Mitsuba 3's `<bsdf type=...>` names.
MATERIALS = _by_name(
    Diffuse, OrenNayar, Conductor, RoughConductor, Dielectric, RoughDielectric, Null,
    Plastic, RoughPlastic, ThinDielectric, BlendBSDF, Mask, Principled,
    PrincipledThin,
    BumpMap, NormalMap,
)  # fmt: skip
# Mitsuba 3's `<emitter type=...>` names.
LIGHTS = _by_name(
    AreaLight,
    PointLight,
    SpotLight,
    DirectionalLight,
    ConstantLight,
    EnvironmentLight,
    ProjectorLight,
)
# Mitsuba 3's `<integrator type=...>` names; `radiometria render --integrator`.
INTEGRATORS = _by_name(Path, Direct, VolPath, VolPathMIS, PTracer, BDPT, PSSMLT)
# Mitsuba 3's `<medium type=...>` names.
MEDIA = _by_name(HomogeneousMediumPlugin, GridMediumPlugin)
# `radiometria render --sampler`.
SAMPLERS = _by_name(Independent, OwenSobol)
# Mitsuba's stratified and low-discrepancy samplers: Owen-scrambled Sobol points are stratified
# in every elementary interval of each dimension pair (power-of-two counts), the property
# `stratified` and `multijitter` have for square counts, and `ldsampler`'s (0, 2)-sequences.
SAMPLER_ALIASES = {"stratified": "sobol", "multijitter": "sobol", "ldsampler": "sobol"}
SAMPLERS.update({alias: SAMPLERS[name] for alias, name in SAMPLER_ALIASES.items()})
TEXTURES = {
    "constant": ConstantTexture,
    "bitmap": BitmapTexture,
    "checkerboard": CheckerboardTexture,
    "mesh_attribute": MeshAttributeTexture,
}
# Mitsuba 3's `<sensor type=...>` names.
CAMERAS = {
    "perspective": PinholeCamera,
    "thinlens": ThinLensCamera,
    "orthographic": OrthographicCamera,
}
# Mitsuba 3's `<rfilter type=...>` names (`catmullrom` is Mitchell-Netravali with B=0, C=1/2).
FILTERS = {
    "box": BoxFilter,
    "tent": TentFilter,
    "gaussian": GaussianFilter,
    "mitchell": MitchellFilter,
    "catmullrom": MitchellFilter,
    "lanczos": LanczosFilter,
}
# `RenderScene.from_triangles(accelerator=...)` ("auto" picks brute force for tiny scenes) is
# `radiometria.render._accelerators.ACCELERATORS`, re-exported here with the others.
