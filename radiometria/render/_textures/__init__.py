"""Textures of the renderer (thesis ch. 8): spectral parameters that may vary over a surface.

One abstract interface (`AbstractTexture`, in `_base.py`) and one final implementation per
file; the registry of names used by scene files is `radiometria.render._registry.TEXTURES`.
"""

from ._base import AbstractTexture as AbstractTexture
from ._constant import ConstantTexture as ConstantTexture
