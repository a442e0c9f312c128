"""Lights of the renderer (thesis ch. 8): emitters as plugins, one per file.

`AbstractLight` (`_base.py`) is what the integrators see: sampling an incident direction
towards the light for next-event estimation, its density, and the radiance emitted by a
surface a ray hits. The names scene files use are in `radiometria.render._registry.LIGHTS`.
"""

from ._area import AreaLight as AreaLight
from ._base import AbstractLight as AbstractLight, LightSample as LightSample
