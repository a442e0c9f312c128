"""Reading texture images: PNG, JPEG, BMP (Pillow), OpenEXR and Radiance RGBE, checked before
decoding.

`read_texture_image` returns an image's colours as linear floats `(h, w, 3)`: 8- and 16-bit
images are decoded from sRGB as Mitsuba 3 does (unless `raw`), float images (EXR, RGBE,
32-bit TIFF) are taken as linear; grey images are repeated into three channels and alpha is dropped.
The header is read first and an image of more than `MAX_TEXELS` texels is refused before its
pixels are decoded (a decompression bomb), so that a hostile file cannot exhaust memory.
Every error is an `OSError` or `ValueError` subclass naming the file.
"""

import warnings
from pathlib import Path

import numpy as np
from PIL import Image

from ...camera import read_exr, read_hdr

__all__ = ["MAX_TEXELS", "TextureFileError", "read_texture_image", "srgb_to_linear"]

MAX_TEXELS = 1 << 26  # 67 M texels (8192 x 8192): 0.8 GB of float32 coefficients
_PIL_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tga", ".tif", ".tiff")
_RGBE_SUFFIXES = (".hdr", ".rgbe", ".pic")


class TextureFileError(ValueError):
    """A texture image that cannot be read; the message names the file and what is wrong."""


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    """The sRGB transfer function inverted (IEC 61966-2-1): encoded [0, 1] -> linear [0, 1]."""
    x = np.asarray(x, np.float64)
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def read_texture_image(path, *, raw: bool = False) -> np.ndarray:
    """An image file's texels as linear RGB.

    **Arguments:**

    - `path`: a `.png`, `.jpg`/`.jpeg`, `.bmp`, `.tga`, `.tif`/`.tiff`, `.exr` or Radiance
        `.hdr`/`.rgbe`/`.pic` file. [path]
    - `raw`: keep integer images' stored values (no sRGB decoding), as Mitsuba's `raw`.

    **Returns:**

    `(h, w, 3)` float64 texels, row 0 the top of the image (the file's first row). [1]

    **Raises:**

    `FileNotFoundError` for a missing file; `TextureFileError` (a `ValueError`) naming the
    file for an unsupported format, a corrupt or truncated file,
    an image of more than `MAX_TEXELS` texels (checked in the header, before decoding), an
    unsupported pixel format or non-finite or negative float texels.

    ??? cite "References"
        `Jakob2022` (Mitsuba 3's `bitmap` texture: sRGB decoding of 8-bit images).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"texture file not found: {path}")
    suffix = path.suffix.lower()
    if suffix == ".exr":
        try:
            rgb, _ = read_exr(path)
        except FileNotFoundError:
            raise
        except (OSError, ValueError) as e:
            raise TextureFileError(f"{path}: not a readable RGB OpenEXR texture ({e}).") from None
        rgb = np.asarray(rgb, np.float64)
    elif suffix in _PIL_SUFFIXES:
        rgb = _read_pillow(path, raw)
    elif suffix in _RGBE_SUFFIXES:
        try:
            rgb, _ = read_hdr(path)
        except (OSError, ValueError) as e:
            raise TextureFileError(f"{path}: not a readable Radiance RGBE texture ({e}).") from None
        if rgb.shape[0] * rgb.shape[1] > MAX_TEXELS:
            raise TextureFileError(
                f"{path}: {rgb.shape[1]} x {rgb.shape[0]} texels; textures must have at most "
                f"{MAX_TEXELS} texels."
            )
        rgb = np.asarray(rgb, np.float64)
    else:
        raise TextureFileError(
            f"{path}: unsupported texture format {suffix!r}; supported: "
            f"{sorted({*_PIL_SUFFIXES, *_RGBE_SUFFIXES, '.exr'})}."
        )
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.shape[0] < 1 or rgb.shape[1] < 1:
        raise TextureFileError(f"{path}: expected an image of 3 channels, got shape {rgb.shape}.")
    if not np.all(np.isfinite(rgb)) or np.any(rgb < 0):
        raise TextureFileError(f"{path}: texels must be finite and >= 0.")
    return rgb


def _read_pillow(path: Path, raw: bool) -> np.ndarray:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # Pillow's warnings on odd files become errors
            with Image.open(path) as im:  # reads the header only
                w, h = im.size
                if w < 1 or h < 1 or w * h > MAX_TEXELS:
                    raise TextureFileError(
                        f"{path}: the header declares {w} x {h} texels; textures must have "
                        f"between 1 and {MAX_TEXELS} texels."
                    )
                mode = im.mode
                if mode == "P" or mode == "PA":
                    im = im.convert("RGBA")
                    mode = im.mode
                im.load()
                data = np.asarray(im)
    except TextureFileError:
        raise
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as e:
        raise TextureFileError(f"{path}: image too large ({e}).") from None
    except Warning as e:
        raise TextureFileError(f"{path}: not a readable image ({type(e).__name__}: {e}).") from None
    except (OSError, ValueError, SyntaxError, EOFError) as e:  # Pillow's corrupt-file errors
        raise TextureFileError(f"{path}: not a readable image ({e}).") from None
    if mode in ("1", "L", "LA", "RGB", "RGBA", "RGBX"):
        scale, linear = (1.0 if mode == "1" else 255.0), False
    elif mode in ("I;16", "I;16B", "I;16L", "I;16N"):
        scale, linear = 65535.0, False
    elif mode == "F":
        scale, linear = 1.0, True
    else:
        raise TextureFileError(
            f"{path}: unsupported pixel format {mode!r}; supported: grey, grey + alpha, RGB, "
            "RGBA, palette (8 bit), 16-bit grey, 32-bit float grey."
        )
    x = np.asarray(data, np.float64)
    if x.ndim == 2:
        x = x[:, :, None]
    channels = x.shape[2]
    if channels in (1, 2):
        x = np.repeat(x[:, :, :1], 3, axis=2)
    else:
        x = x[:, :, :3]
    x = x / scale
    if not linear and not raw:
        x = srgb_to_linear(x)
    return x
