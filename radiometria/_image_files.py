r"""Image files: OpenEXR (RGB and spectral) and 8-bit sRGB PNG, written atomically; Radiance
RGBE (`.hdr`) pictures read.

Every writer goes through a temporary file in the target's directory and `os.replace`, so a
reader never sees a half-written image and a failed write leaves nothing behind. Writing to a
path that cannot be written raises the usual `OSError` subclass with the path in the message.
IO is NumPy-side: arrays in, NumPy arrays out. This module imports only NumPy and floor-1
helpers (OpenEXR when an EXR is read or written), so that the command line writes the image of
a warm-started render without importing JAX's modules (about 0.3 s); `radiometria.camera`
exports its functions.
"""

import os
import struct
import zlib
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from ._io import atomic_write_path

# Attributes every OpenEXR header has; user metadata may not use these names.
_EXR_STANDARD = frozenset(
    {
        "channels", "compression", "dataWindow", "displayWindow", "lineOrder",
        "pixelAspectRatio", "screenWindowCenter", "screenWindowWidth", "type", "tiles",
        "chunkCount", "name", "version", "view", "multiView",
    }
)  # fmt: skip
SPECTRAL_LAYOUT_VERSION = "1.0"
EMISSIVE_UNITS = "W.m^-2.sr^-1"


def _atomic_write(path, write: Callable[[str], None]) -> Path:
    """`atomic_write_path` with the image file named in every error.

    OpenEXR reports IO failures as `RuntimeError`; they become `OSError` too.
    """
    path = Path(path)
    try:
        return atomic_write_path(path, write)
    except OSError as e:
        raise type(e)(
            e.errno, f"Cannot write image file {str(path)!r}: {e.strerror}", str(path)
        ) from e
    except RuntimeError as e:
        raise OSError(f"Cannot write image file {str(path)!r}: {e}") from e


def _image(rgb, name: str, channels: int | None = 3) -> np.ndarray:
    arr = np.asarray(rgb)
    if arr.dtype.kind not in "fiu":
        raise TypeError(f"`{name}` must be a numeric array, got dtype {arr.dtype}.")
    if channels is not None and (arr.ndim != 3 or arr.shape[-1] != channels):
        raise ValueError(f"`{name}` must have shape (H, W, {channels}), got {arr.shape}.")
    if arr.ndim != 3 or arr.shape[0] < 1 or arr.shape[1] < 1:
        raise ValueError(f"`{name}` must have shape (H, W, C) with H, W >= 1, got {arr.shape}.")
    return arr


def _check_metadata(metadata: Mapping | None) -> dict:
    if metadata is None:
        return {}
    if not isinstance(metadata, Mapping):
        raise TypeError(
            f"`metadata` must be a mapping of str to values, got {type(metadata).__name__}."
        )
    out = {}
    for key, value in metadata.items():
        if not isinstance(key, str) or not key:
            raise TypeError(f"`metadata` keys must be non-empty strings, got {key!r}.")
        if key in _EXR_STANDARD:
            raise ValueError(f"`metadata` key {key!r} is a reserved OpenEXR header attribute.")
        if isinstance(value, bool):
            value = int(value)
        if isinstance(value, str | int | float):
            out[key] = value
        elif isinstance(value, np.integer | np.floating):
            out[key] = value.item()
        elif isinstance(value, list | tuple) and all(isinstance(v, str) for v in value):
            out[key] = list(value)
        elif isinstance(value, np.ndarray | list | tuple) and np.asarray(value).shape in (
            (2,),
            (3,),
            (3, 3),
            (4, 4),
        ):
            out[key] = np.asarray(value, dtype=np.float32)
        else:
            raise TypeError(
                f"`metadata[{key!r}]` has unsupported type {type(value).__name__}: use str, int, "
                "float (stored as float32), a list of str, or a float vector/matrix of shape "
                "(2,), (3,), (3, 3) or (4, 4)."
            )
    return out


def _write_exr_channels(path, channels: dict, header_extra: dict) -> Path:
    import OpenEXR

    def write(tmp: str) -> None:
        # OpenEXR.File takes ownership of (and rewrites) the dicts it gets: pass fresh ones.
        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
        header.update(header_extra)
        OpenEXR.File(header, dict(channels)).write(tmp)

    return _atomic_write(path, write)


def write_exr(path, rgb, metadata: Mapping | None = None) -> Path:
    """Write a linear RGB image as OpenEXR with float32 channels R, G, B (atomically).

    **Arguments:**

    - `path`: output file. [path]
    - `rgb`: image (H, W, 3), linear (no transfer function); stored as float32, row 0 at
        the top. [radiance-like]
    - `metadata`: optional header attributes: str, int, float (stored as float32), list of
        str, or float vectors/matrices of shape (2,), (3,), (3, 3), (4, 4) (stored as float32).
        Names of standard OpenEXR attributes are refused.

    **Returns:**

    The written path. Raises `OSError` naming the path when it cannot be written.

    !!! note "Thesis"
        Thesis section 2.3 (the film's output).

    ??? cite "References"
        `Kainz2004`.
    """
    arr = _image(rgb, "rgb").astype(np.float32)
    extra = _check_metadata(metadata)
    channels = {c: np.ascontiguousarray(arr[..., i]) for i, c in enumerate("RGB")}
    return _write_exr_channels(path, channels, extra)


EXR_MAGIC = b"\x76\x2f\x31\x01"
EXR_MAX_HEADER_BYTES = 1 << 20
# Scanlines per chunk of each OpenEXR compression (index = the `compression` byte); an
# unknown compression gets the largest, so that the offset-table bound below never refuses
# a valid file.
_EXR_LINES_PER_CHUNK = (1, 1, 1, 16, 32, 16, 32, 32, 32, 256)


class _ExrHeaderError(ValueError):
    pass


def _exr_header(path: Path, size: int) -> dict:
    """The attributes of the first header of an OpenEXR file, as raw bytes by name.

    Parsed here (OpenEXR 2 file layout, `Kainz2004`) so that a dataWindow the file cannot hold
    is refused before the binding allocates pixels.
    """
    with open(path, "rb") as fh:
        head = fh.read(min(size, EXR_MAX_HEADER_BYTES))
    if head[:4] != EXR_MAGIC:
        raise _ExrHeaderError(f"not an OpenEXR file (it starts with {head[:4]!r}).")
    if len(head) < 8:
        raise _ExrHeaderError("truncated in its version field.")
    (flags,) = struct.unpack_from("<I", head, 4)
    pos, attrs = 8, {"_flags": flags}
    while True:
        end = head.find(b"\0", pos)
        if end < 0:
            raise _ExrHeaderError(f"truncated header (no end of the attribute at byte {pos}).")
        name = head[pos:end]
        pos = end + 1
        if not name:
            attrs["_end"] = pos
            return attrs
        end = head.find(b"\0", pos)
        if end < 0 or end + 5 > len(head):
            raise _ExrHeaderError(f"truncated header in attribute {name[:64]!r}.")
        (n,) = struct.unpack_from("<i", head, end + 1)
        pos = end + 5
        if n < 0 or pos + n > len(head):
            raise _ExrHeaderError(
                f"attribute {name[:64]!r} claims {n} bytes; the header holds {len(head) - pos}."
            )
        attrs[name.decode("latin-1")] = head[pos : pos + n]
        pos += n


def _exr_channel_count(chlist: bytes) -> int:
    """Entries of a `chlist` attribute: name, NUL, then 16 bytes each; a NUL ends the list."""
    pos, n = 0, 0
    while pos < len(chlist) and chlist[pos] != 0:
        end = chlist.find(b"\0", pos)
        if end < 0 or end + 17 > len(chlist):
            raise _ExrHeaderError("the channel list is truncated.")
        pos, n = end + 17, n + 1
    if n == 0:
        raise _ExrHeaderError("the channel list is empty.")
    return n


def _check_exr_size(attrs: dict, size: int) -> None:
    """Refuse a dataWindow that is empty, inverted, or larger than memory or the file."""
    if attrs["_flags"] & 0x1800:  # multi-part or deep: the binding's own checks apply
        return
    if len(attrs.get("dataWindow", b"")) != 16 or "channels" not in attrs:
        raise _ExrHeaderError("the header lacks a dataWindow or a channel list.")
    x0, y0, x1, y1 = struct.unpack("<4i", attrs["dataWindow"])
    width, height = x1 - x0 + 1, y1 - y0 + 1
    if width < 1 or height < 1:
        raise _ExrHeaderError(f"empty or inverted dataWindow ({x0}, {y0}) - ({x1}, {y1}).")
    n_channels = _exr_channel_count(attrs["channels"])
    need = width * height * n_channels * 4
    try:
        memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # pragma: no cover - non-POSIX
        memory = 1 << 40
    if need > memory:
        raise _ExrHeaderError(
            f"dataWindow {width} x {height} with {n_channels} channel(s) would need "
            f"{need / 2**30:,.1f} GiB as float32, more than this machine's "
            f"{memory / 2**30:,.1f} GiB of memory."
        )
    if not attrs["_flags"] & 0x200:  # scanline file: its offset table must fit in the file
        comp = attrs.get("compression", b"\0")[:1] or b"\0"
        lines = _EXR_LINES_PER_CHUNK[comp[0]] if comp[0] < len(_EXR_LINES_PER_CHUNK) else 256
        chunks = -(-height // lines)
        if attrs["_end"] + 8 * chunks > size:
            raise _ExrHeaderError(
                f"dataWindow height {height} needs {chunks:,} chunk offsets ({8 * chunks:,} "
                f"bytes), but the file has {size - attrs['_end']:,} bytes after its header "
                "(truncated file, or an absurd dataWindow)."
            )


def _read_exr_file(path):
    import OpenEXR

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(2, f"No such image file: {str(path)!r}", str(path))
    size = path.stat().st_size
    try:
        _check_exr_size(_exr_header(path, size), size)
    except _ExrHeaderError as e:
        raise ValueError(f"{str(path)!r} is not a readable OpenEXR file: {e}") from None
    try:
        with OpenEXR.File(str(path), separate_channels=True) as f:
            header = dict(f.header())
            channels = {name: (ch.pixels, ch.type()) for name, ch in f.channels().items()}
    except (RuntimeError, ValueError, TypeError, KeyError, IndexError, MemoryError) as e:
        # The binding reports a corrupt or truncated file as RuntimeError or ValueError.
        raise ValueError(f"{str(path)!r} is not a readable OpenEXR file: {e}") from None
    metadata = {k: v for k, v in header.items() if k not in _EXR_STANDARD}
    return path, channels, metadata


def _float_channel(path: Path, channels: dict, name: str) -> np.ndarray:
    import OpenEXR

    if name not in channels:
        raise ValueError(
            f"{str(path)!r}: missing channel {name!r} "
            f"(has: {', '.join(sorted(channels)) or 'none'})."
        )
    pixels, ptype = channels[name]
    if ptype == OpenEXR.UINT or np.asarray(pixels).dtype.kind != "f":
        raise ValueError(f"{str(path)!r}: channel {name!r} must be FLOAT or HALF, got {ptype}.")
    return np.asarray(pixels, dtype=np.float32)


def read_exr(path) -> tuple[np.ndarray, dict]:
    """Read an RGB OpenEXR file written by `write_exr` (or any with float R, G, B channels).

    **Arguments:**

    - `path`: the file. [path]

    **Returns:**

    `(rgb, metadata)`: the image (H, W, 3) as float32 (HALF channels are widened) and the
    non-standard header attributes. Raises `FileNotFoundError` for a missing file and
    `ValueError` naming the file for a file that is not OpenEXR, lacks one of R, G, B, or
    stores one of them as UINT.

    !!! note "Thesis"
        Thesis section 2.3.

    ??? cite "References"
        `Kainz2004`.
    """
    path, channels, metadata = _read_exr_file(path)
    rgb = np.stack([_float_channel(path, channels, c) for c in "RGB"], axis=-1)
    return rgb, metadata


def spectral_channel_name(wavelength_nm: float, stokes: int = 0) -> str:
    """Channel name of an emissive spectral band in Fichet et al.'s layout, e.g. `S0.550,000000nm`.

    The wavelength is printed with six decimals (C++ `std::to_string`) and a comma as decimal
    separator, because `.` separates layers in OpenEXR channel names.

    **Arguments:**

    - `wavelength_nm`: band centre, > 0. [nm]
    - `stokes`: Stokes component 0-3 (0 for unpolarised radiance). [dimensionless]

    **Returns:**

    The channel name (str).

    !!! note "Thesis"
        Thesis section 2.3.

    ??? cite "References"
        `Fichet2021`.
    """
    if stokes not in (0, 1, 2, 3):
        raise ValueError(f"`stokes` must be 0, 1, 2 or 3, got {stokes!r}.")
    wl = float(wavelength_nm)
    if not np.isfinite(wl) or wl <= 0:
        raise ValueError(f"`wavelength_nm` must be finite and > 0 [nm], got {wl}.")
    return f"S{stokes}." + f"{wl:.6f}".replace(".", ",") + "nm"


def write_spectral_exr(
    path, spectral, wavelengths_nm, *, rgb=None, metadata: Mapping | None = None
) -> Path:
    r"""Write an emissive spectral image in the OpenEXR layout of Fichet et al. (2021).

    One float32 channel per band named `S0.<wavelength>nm` with a decimal comma
    (`spectral_channel_name`), the header attributes `spectralLayoutVersion = "1.0"` and
    `emissiveUnits = "W.m^-2.sr^-1"` (as the paper and pbrt-v4's spectral film write them;
    the channel values are spectral radiance per nm), and optionally an RGB preview in R, G, B.

    **Arguments:**

    - `path`: output file. [path]
    - `spectral`: image (H, W, n) of spectral radiance. [W m^-2 sr^-1 nm^-1]
    - `wavelengths_nm`: the n band centres, distinct and > 0. [nm]
    - `rgb`: optional linear RGB preview (H, W, 3). [radiance-like]
    - `metadata`: extra header attributes, as in `write_exr`.

    **Returns:**

    The written path.

    !!! note "Thesis"
        Thesis section 2.3.

    ??? cite "References"
        `Fichet2021`.
    """
    arr = _image(spectral, "spectral", channels=None).astype(np.float32)
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    if wl.ndim != 1 or wl.shape[0] != arr.shape[-1]:
        raise ValueError(
            f"`wavelengths_nm` must have shape ({arr.shape[-1]},) to match `spectral` {arr.shape}, "
            f"got {wl.shape}."
        )
    names = [spectral_channel_name(w) for w in wl]
    if len(set(names)) != len(names):
        raise ValueError("`wavelengths_nm` must be distinct (at the 1e-6 nm printed precision).")
    channels = {n: np.ascontiguousarray(arr[..., i]) for i, n in enumerate(names)}
    if rgb is not None:
        prev = _image(rgb, "rgb").astype(np.float32)
        if prev.shape[:2] != arr.shape[:2]:
            raise ValueError(f"`rgb` {prev.shape} and `spectral` {arr.shape} differ in size.")
        channels.update({c: np.ascontiguousarray(prev[..., i]) for i, c in enumerate("RGB")})
    extra = _check_metadata(metadata)
    extra["spectralLayoutVersion"] = SPECTRAL_LAYOUT_VERSION
    extra["emissiveUnits"] = EMISSIVE_UNITS
    return _write_exr_channels(path, channels, extra)


def read_spectral_exr(path) -> tuple[np.ndarray, np.ndarray, dict]:
    """Read the unpolarised emissive bands (`S0.*`) of a Fichet et al. (2021) spectral EXR.

    **Arguments:**

    - `path`: the file. [path]

    **Returns:**

    `(spectral, wavelengths_nm, metadata)`: (H, W, n) float32 sorted by wavelength, the
    wavelengths (n,) [nm] and the non-standard header attributes. `ValueError` naming the file
    when it has no `S0.<value>nm` channel or a band is not floating point.

    !!! note "Thesis"
        Thesis section 2.3.

    ??? cite "References"
        `Fichet2021`.
    """
    path, channels, metadata = _read_exr_file(path)
    bands = []
    for name in channels:
        if name.startswith("S0.") and name.endswith("nm"):
            try:
                bands.append((float(name[3:-2].replace(",", ".")), name))
            except ValueError:
                continue
    if not bands:
        raise ValueError(f"{str(path)!r}: no spectral channel 'S0.<wavelength>nm' found.")
    bands.sort()
    spectral = np.stack([_float_channel(path, channels, n) for _, n in bands], axis=-1)
    return spectral, np.asarray([w for w, _ in bands]), metadata


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def _srgb_encode(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB encoding of linear values in [0, 1], in NumPy: the formula of
    `colorimetry.srgb_eotf_inverse` (tested equal)."""
    x = np.asarray(x, np.float64)
    big = x > 0.0031308
    return np.where(big, 1.055 * np.where(big, x, 1.0) ** (1.0 / 2.4) - 0.055, 12.92 * x)


def write_png(path, rgb_linear, exposure: float = 0.0) -> Path:
    r"""Write linear RGB as an 8-bit sRGB-encoded PNG (atomically).

    Each value is scaled by $2^{\mathrm{exposure}}$, clipped to [0, 1], encoded with the sRGB
    transfer function (IEC 61966-2-1) and rounded to 8 bits. The PNG carries an `sRGB` chunk.
    NaN becomes 0.

    **Arguments:**

    - `path`: output file. [path]
    - `rgb_linear`: image (H, W, 3) in linear sRGB. [radiance-like]
    - `exposure`: exposure compensation in stops. [EV]

    **Returns:**

    The written path.

    !!! note "Thesis"
        Thesis section 2.2.2 (sRGB transfer function), section 2.3.

    ??? cite "References"
        `IEC1999`.
    """
    arr = _image(rgb_linear, "rgb_linear").astype(np.float64)
    exposure = float(exposure)
    if not np.isfinite(exposure):
        raise ValueError(f"`exposure` must be finite [EV], got {exposure}.")
    x = np.clip(np.nan_to_num(arr * 2.0**exposure, nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0)
    img = np.floor(_srgb_encode(x) * 255.0 + 0.5).astype(np.uint8)
    h, w = img.shape[:2]
    raw = b"".join(b"\x00" + img[row].tobytes() for row in range(h))  # filter type 0 per row
    png = (
        b"\x89PNG\r\n\x1a\n"
        + _png_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
        + _png_chunk(b"sRGB", b"\x00")  # rendering intent: perceptual
        + _png_chunk(b"IDAT", zlib.compress(raw, 6))
        + _png_chunk(b"IEND", b"")
    )

    def write(tmp: str) -> None:
        with open(tmp, "wb") as f:
            f.write(png)

    return _atomic_write(path, write)


# ---------------------------------------------------------------------------------------------
# Radiance RGBE (.hdr / .pic)

HDR_MAX_HEADER_BYTES = 1 << 16
HDR_MAX_SIDE = 1 << 15  # the new run-length encoding stores a scanline's width in 15 bits


class _HdrError(ValueError):
    pass


def _hdr_header(data: bytes) -> tuple[int, int, int, bool, bool, dict]:
    """Parse a Radiance picture's header and resolution line (Ward 1991's file format).

    Returns `(pixel data offset, height, width, flip rows, flip columns, metadata)`. Only the
    scanline-major orientations (`-Y H +X W`, `+Y H ...`, `... -X W`) are read; the four
    column-major ones (`+X W -Y H`, ...) are refused.
    """
    head = data[:HDR_MAX_HEADER_BYTES]
    if not (head.startswith(b"#?") or head.startswith(b"FORMAT=")):
        raise _HdrError(f"not a Radiance picture (it starts with {head[:10]!r}, not '#?').")
    end = head.find(b"\n\n")
    if end < 0:
        raise _HdrError(f"no end of the header (an empty line) in its first {len(head):,} bytes.")
    metadata: dict[str, str] = {}
    for raw in head[:end].split(b"\n")[1 if head.startswith(b"#?") else 0 :]:
        line = raw.decode("latin-1").strip()
        if not line or line.startswith("#") or "=" not in line:
            continue
        key, _, value = line.partition("=")
        key = key.strip()
        metadata[key] = f"{metadata[key]} {value.strip()}" if key in metadata else value.strip()
    fmt = metadata.get("FORMAT", "32-bit_rle_rgbe")
    if fmt != "32-bit_rle_rgbe":
        raise _HdrError(f"FORMAT={fmt} is not supported; only 32-bit_rle_rgbe (RGB).")
    nl = data.find(b"\n", end + 2, end + 2 + 64)
    if nl < 0:
        raise _HdrError("truncated or missing resolution line after the header.")
    words = data[end + 2 : nl].decode("latin-1").split()
    if len(words) != 4 or words[0][1:] not in "YX" or words[2][1:] not in "YX":
        raise _HdrError(f"malformed resolution line {data[end + 2 : nl][:64]!r}.")
    if words[0][1:] != "Y" or words[2][1:] != "X":
        raise _HdrError(
            f"resolution line {' '.join(words)!r}: column-major pictures are not supported "
            "(only '-Y H +X W' and its flips)."
        )
    if words[0][0] not in "+-" or words[2][0] not in "+-":
        raise _HdrError(f"malformed resolution line {' '.join(words)!r}.")
    try:
        height, width = int(words[1]), int(words[3])
    except ValueError:
        raise _HdrError(f"malformed resolution line {' '.join(words)!r}.") from None
    if not (1 <= height <= HDR_MAX_SIDE and 1 <= width <= HDR_MAX_SIDE):
        raise _HdrError(
            f"resolution {width} x {height}: each side must be between 1 and {HDR_MAX_SIDE}."
        )
    return nl + 1, height, width, words[0][0] == "+", words[2][0] == "-", metadata


def _hdr_scanlines(body: bytes, height: int, width: int) -> np.ndarray:
    """Decode `height` scanlines of RGBE bytes, flat or in the new run-length encoding.

    A scanline starting with bytes 2, 2 and its width (8 <= width < 32768) holds four
    run-length-coded channel streams (a byte n > 128 repeats the next byte n - 128 times,
    n <= 128 copies n literal bytes); anything else is a flat scanline of 4-byte pixels.
    The loop runs over runs, not pixels: runs are sliced whole into the output.
    """
    out = np.empty((height, 4, width), np.uint8)
    src = np.frombuffer(body, np.uint8)
    size, pos = len(body), 0
    for row in range(height):
        if (
            8 <= width < 32768
            and pos + 4 <= size
            and src[pos] == 2
            and src[pos + 1] == 2
            and (int(src[pos + 2]) << 8 | int(src[pos + 3])) == width
        ):
            pos += 4
            for channel in range(4):
                dst, x = out[row, channel], 0
                while x < width:
                    if pos >= size:
                        raise _HdrError(f"truncated in scanline {row} (run-length data).")
                    n = int(src[pos])
                    run = n > 128
                    n -= 128 * run
                    if n == 0 or x + n > width:
                        raise _HdrError(
                            f"a {'run' if run else 'literal'} of {n} bytes at pixel {x} of "
                            f"scanline {row} (width {width})."
                        )
                    if pos + (2 if run else 1 + n) > size:
                        raise _HdrError(f"truncated in scanline {row} (run-length data).")
                    dst[x : x + n] = src[pos + 1] if run else src[pos + 1 : pos + 1 + n]
                    pos += 2 if run else 1 + n
                    x += n
        else:
            if pos + 4 * width > size:
                raise _HdrError(f"truncated in scanline {row} (flat pixels).")
            out[row] = src[pos : pos + 4 * width].reshape(width, 4).T
            pos += 4 * width
    return out


def read_hdr(path) -> tuple[np.ndarray, dict]:
    """Read a Radiance RGBE picture (`.hdr`, `.pic`): flat or run-length-encoded scanlines.

    Each pixel stores three 8-bit mantissas and a shared exponent: a channel is
    `mantissa * 2**(exponent - 136)`, and exponent 0 is black (Ward's `rgbe2float`, as
    Mitsuba 3 reads the format; `EXPOSURE` and other header lines are returned as metadata,
    not applied, as there). Row 0 of the result is the top of the picture for every
    scanline-major orientation (`-Y H +X W` and its flips).

    **Arguments:**

    - `path`: the file. [path]

    **Returns:**

    `(rgb, metadata)`: the image `(H, W, 3)` as float32, and the header's `KEY=value` lines
    as a dict of strings.

    **Raises:**

    `FileNotFoundError` for a missing file; `ValueError` naming the file for a file that is
    not a Radiance picture, an XYZE picture, a column-major orientation, a resolution over
    32768 per side or one the file is too short to hold (checked before decoding), and
    truncated or corrupt run-length data (naming the scanline).

    ??? cite "References"
        `Ward1991` (the RGBE pixel format and the Radiance picture file).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(2, f"No such image file: {str(path)!r}", str(path))
    try:
        data = path.read_bytes()
        start, height, width, flip_y, flip_x, metadata = _hdr_header(data)
        # The smallest encoding of a scanline: four runs of 127 per 2 bytes plus its marker.
        least = height * (4 + 8 * -(-width // 127)) if width >= 8 else height * 4 * width
        if len(data) - start < least:
            raise _HdrError(
                f"resolution {width} x {height} needs at least {least:,} bytes of pixels; "
                f"the file has {len(data) - start:,} (truncated file, or an absurd size)."
            )
        rgbe = _hdr_scanlines(data[start:], height, width)
    except _HdrError as e:
        raise ValueError(f"{str(path)!r} is not a readable Radiance picture: {e}") from None
    exponent = rgbe[:, 3, :].astype(np.int32)
    scale = np.where(exponent > 0, np.ldexp(np.float32(1), exponent - 136), 0).astype(np.float32)
    rgb = np.moveaxis(rgbe[:, :3, :], 1, 2).astype(np.float32) * scale[..., None]
    if flip_y:
        rgb = rgb[::-1]
    if flip_x:
        rgb = rgb[:, ::-1]
    return np.ascontiguousarray(rgb), metadata
