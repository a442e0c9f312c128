"""Textures of the renderer (thesis ch. 8): spectral parameters that may vary over a surface.

One abstract interface (`AbstractTexture`, in `_base.py`) and one final implementation per
file; the registry of names used by scene files is `radiometria.render._registry.TEXTURES`.
Textures of several rows of different kinds are joined by `concatenate_textures`.
"""

from ._base import AbstractTexture as AbstractTexture
from ._bitmap import BitmapTexture as BitmapTexture
from ._checkerboard import CheckerboardTexture as CheckerboardTexture
from ._constant import ConstantTexture as ConstantTexture
from ._image import (
    MAX_TEXELS as MAX_TEXELS,
    TextureFileError as TextureFileError,
    read_texture_image as read_texture_image,
)
from ._mesh_attribute import MeshAttributeTexture as MeshAttributeTexture
from ._raw import RawImage as RawImage
from ._spec import TextureSpec as TextureSpec, texture_parameter as texture_parameter
from ._stack import TextureStack as TextureStack, concatenate_textures as concatenate_textures
