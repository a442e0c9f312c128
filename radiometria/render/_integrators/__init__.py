"""Integrators of the renderer (thesis ch. 8-9): light-transport estimators, one per file.

Each subclasses `AbstractIntegrator` (`_base.py`); the names scene files and the command line
use are in `radiometria.render._registry.INTEGRATORS`.
"""

from ._base import AbstractIntegrator as AbstractIntegrator
from ._bdpt import (
    BDPT as BDPT,
    bdpt_mis_weight as bdpt_mis_weight,
    bdpt_sample_dimensions as bdpt_sample_dimensions,
)
from ._direct import Direct as Direct
from ._path import (
    Path as Path,
    path_radiance as path_radiance,
    sample_dimensions as sample_dimensions,
)
from ._pssmlt import PSSMLT as PSSMLT, pssmlt_sample_dimensions as pssmlt_sample_dimensions
from ._ptracer import (
    PTracer as PTracer,
    Splats as Splats,
    ptracer_sample_dimensions as ptracer_sample_dimensions,
)
from ._volpath import (
    VolPath as VolPath,
    volpath_radiance as volpath_radiance,
    volpath_sample_dimensions as volpath_sample_dimensions,
)
from ._volpathmis import VolPathMIS as VolPathMIS
