"""Media of the renderer (thesis ch. 4 and 9): medium plugins bound to shapes and the camera.

Each medium plugin holds the parameters of one or more media of its kind as rows (like a
material plugin) and builds a `radiometria.media.AbstractMedium` for each path's row;
`MediumSet` holds a scene's media and selects per path. The names scene files use are in
`radiometria.render._registry.MEDIA`.
"""

from ._base import AbstractMediumPlugin as AbstractMediumPlugin
from ._grid import GridMediumPlugin as GridMediumPlugin
from ._homogeneous import HomogeneousMediumPlugin as HomogeneousMediumPlugin
from ._set import KEEP_MEDIUM as KEEP_MEDIUM, VACUUM as VACUUM, MediumSet as MediumSet
