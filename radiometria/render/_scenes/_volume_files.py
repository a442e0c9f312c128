"""Mitsuba's binary `.vol` voxel grids (the `gridvolume` of a `heterogeneous` medium).

Layout (little-endian), as written by Mitsuba 3's `VolumeGrid.write`:

| bytes | content |
| --- | --- |
| 0-2 | the characters `VOL` |
| 3 | file format version, 3 |
| 4-7 | int32 encoding: 1 = float32 (the only one Mitsuba 3 reads) |
| 8-19 | int32 `xres`, `yres`, `zres` |
| 20-23 | int32 channel count (1 or 3 here) |
| 24-47 | float32 bounding box `xmin, ymin, zmin, xmax, ymax, zmax` |
| 48- | float32 data, `((z yres + y) xres + x) channels + c` |

Mitsuba 3 ignores the stored bounding box by default (`use_grid_bbox` false): the grid fills
the unit box of its `to_world`. `read_vol` checks the header before it allocates anything
(the sizes must be positive, at most `MAX_RESOLUTION` per axis and the data must be exactly
what the file length holds) and then the values (finite, >= 0); each problem raises
`SceneError` naming the file, the scene line that referenced it, the field and the valid
range. `write_vol` writes the format (for tests and tools).
"""

import struct
from pathlib import Path

import numpy as np

from ._description import SceneError

__all__ = ["MAX_RESOLUTION", "read_vol", "write_vol"]

MAX_RESOLUTION = 1024  # voxels per axis
_HEADER = struct.Struct("<3sBiiiii6f")  # 48 bytes


def write_vol(path, data, bbox=(0.0, 0.0, 0.0, 1.0, 1.0, 1.0)) -> None:
    """Write a `.vol` grid.

    **Arguments:**

    - `path`: the file to write.
    - `data`: voxels `(Z, Y, X)` or `(Z, Y, X, C)`, written as float32. [any]
    - `bbox`: the stored bounding box (ignored by readers that follow Mitsuba 3's default).
        [scene units]
    """
    a = np.asarray(data, np.float32)
    if a.ndim == 3:
        a = a[..., None]
    if a.ndim != 4:
        raise ValueError(f"`data` must be (Z, Y, X) or (Z, Y, X, C), got shape {a.shape}.")
    z, y, x, c = a.shape
    header = _HEADER.pack(b"VOL", 3, 1, x, y, z, c, *map(float, bbox))
    Path(path).write_bytes(header + np.ascontiguousarray(a).astype("<f4").tobytes())


def read_vol(path, *, where: str = "") -> np.ndarray:
    """Read a `.vol` grid (module docstring) as float32 `(Z, Y, X, C)`, C in {1, 3}.

    **Arguments:**

    - `path`: the file.
    - `where`: the scene file and line that referenced it, prefixed to error messages.

    **Raises:**

    `SceneError` naming the file (and `where`) for an unreadable file, a wrong magic, version
    or encoding, a channel count other than 1 or 3, a resolution outside [1,
    `MAX_RESOLUTION`], a data size that differs from the file's, or a NaN, infinite or
    negative value.

    ??? cite "References"
        `Jakob2022` (`gridvolume`, `VolumeGrid`).
    """
    path = Path(path)
    pre = f"{where}: " if where else ""
    name = f"{pre}volume file {str(path)!r}"
    try:
        size = path.stat().st_size
        with open(path, "rb") as f:
            head = f.read(_HEADER.size)
            if len(head) < _HEADER.size:
                raise SceneError(
                    f"{name}: truncated header ({len(head)} bytes, a .vol header has "
                    f"{_HEADER.size})."
                )
            magic, version, encoding, x, y, z, c, *_ = _HEADER.unpack(head)
            if magic != b"VOL":
                raise SceneError(
                    f"{name}: not a Mitsuba .vol file (magic {magic!r}, expected b'VOL')."
                )
            if version != 3:
                raise SceneError(f"{name}: unsupported .vol version {version} (expected 3).")
            if encoding != 1:
                raise SceneError(
                    f"{name}: unsupported encoding {encoding} (only 1 = float32 is supported)."
                )
            if c not in (1, 3):
                raise SceneError(f"{name}: channel count {c} not supported (expected 1 or 3).")
            for axis, r in (("xres", x), ("yres", y), ("zres", z)):
                if not 1 <= r <= MAX_RESOLUTION:
                    raise SceneError(f"{name}: {axis} = {r} outside [1, {MAX_RESOLUTION}].")
            expected = _HEADER.size + 4 * x * y * z * c
            if expected != size:
                raise SceneError(
                    f"{name}: the header declares {x}x{y}x{z}x{c} float32 values "
                    f"({expected} bytes with the header) but the file has {size} bytes."
                )
            raw = f.read(expected - _HEADER.size)
    except OSError as e:
        raise SceneError(f"{name}: cannot be read ({e.strerror or e}).") from None
    if len(raw) != expected - _HEADER.size:
        raise SceneError(f"{name}: the file changed while it was read.")
    data = np.frombuffer(raw, "<f4").astype(np.float32).reshape(z, y, x, c)
    bad = ~np.isfinite(data) | (data < 0)
    if np.any(bad):
        i = np.argwhere(bad)[0]
        raise SceneError(
            f"{name}: voxel (x={i[2]}, y={i[1]}, z={i[0]}, channel {i[3]}) is "
            f"{float(data[tuple(i)])}; values must be finite and >= 0 ({int(bad.sum())} bad)."
        )
    return data
