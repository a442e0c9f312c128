"""Materials of the renderer (thesis ch. 3 and 8): BSDF plugins, one per file.

Each plugin subclasses `AbstractMaterial` (`_base.py`), owns its parameter table (one row per
material of its kind) and builds a `radiometria.scattering` BxDF at the hero wavelengths of a
batch of paths; `MaterialSet` (`_set.py`) holds a scene's plugins. The names scene files use
are in `radiometria.render._registry.MATERIALS`.
"""

from ._base import AbstractMaterial as AbstractMaterial, ScaledBxDF as ScaledBxDF
from ._composite import BlendBSDF as BlendBSDF, Mask as Mask
from ._conductor import Conductor as Conductor
from ._dielectric import Dielectric as Dielectric
from ._diffuse import Diffuse as Diffuse
from ._ior import MITSUBA_IOR as MITSUBA_IOR
from ._oren_nayar import OrenNayar as OrenNayar
from ._perturbed import (
    BumpMap as BumpMap,
    HitGeometry as HitGeometry,
    NormalMap as NormalMap,
    PerturbedBxDF as PerturbedBxDF,
)
from ._plastic import Plastic as Plastic, RoughPlastic as RoughPlastic
from ._principled import Principled as Principled, PrincipledThin as PrincipledThin
from ._rough_conductor import RoughConductor as RoughConductor
from ._rough_dielectric import RoughDielectric as RoughDielectric
from ._set import MaterialSet as MaterialSet
from ._thin_dielectric import ThinDielectric as ThinDielectric
