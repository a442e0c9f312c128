"""Lights of the renderer (thesis ch. 8): emitters as plugins, one per file.

`AbstractLight` (`_base.py`) is what the integrators see: sampling an incident direction
towards the light for next-event estimation, its density, the radiance emitted by a surface a
ray hits and the radiance arriving along a ray that leaves the scene. `LightSet` (`_set.py`)
combines plugins of several kinds and picks one per sample by power. The names scene files
use are in `radiometria.render._registry.LIGHTS`.
"""

from ._area import AreaLight as AreaLight
from ._base import (
    AbstractLight as AbstractLight,
    EmissionSample as EmissionSample,
    LightSample as LightSample,
)
from ._constant import ConstantLight as ConstantLight
from ._directional import DirectionalLight as DirectionalLight
from ._envmap import EnvironmentLight as EnvironmentLight, read_envmap as read_envmap
from ._point import PointLight as PointLight
from ._projector import ProjectorLight as ProjectorLight
from ._set import LightSet as LightSet
from ._spot import SpotLight as SpotLight, spot_falloff as spot_falloff
