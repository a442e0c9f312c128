"""Atomic file writes, deterministic `.npz` files and content hashes of arrays (floor 1:
imports nothing from radiometria).

Every file the package writes (images, coefficient tables, figures, packaged data, compiled
kernels) goes through `atomic_write`, `atomic_write_bytes` or `atomic_write_path`: the content
is written to a hidden temporary file in the target's directory, flushed to disk, given the
usual permissions (`0o666 & ~umask` unless `mode` says otherwise) and renamed onto the target
with `os.replace`. A reader sees the old file or the whole new one, never a half-written one,
and a failure (an exception, or `KeyboardInterrupt`) removes the temporary file and leaves any
previous file intact (design.md, "Bad input").

`write_npz_deterministic` writes the same bytes for the same arrays (sorted keys, fixed zip
timestamps and attributes, no pickle), so packaged data files can be rebuilt and checked by
their sha256.
"""

import errno
import io
import os
import tempfile
import zipfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import BinaryIO

import numpy as np

__all__ = [
    "hash_array",
    "atomic_write",
    "atomic_write_bytes",
    "atomic_write_path",
    "cache_root",
    "default_file_mode",
    "npz_bytes",
    "write_npz_deterministic",
]

# Zip entry date of every deterministic .npz member: the earliest date zip can store.
NPZ_DATE_TIME = (1980, 1, 1, 0, 0, 0)
# Unix permissions recorded in each member's external attributes (rw-r--r--).
NPZ_MEMBER_MODE = 0o644


def cache_root() -> Path:
    """`$XDG_CACHE_HOME/radiometria`, else `~/.cache/radiometria` (XDG base directories; a
    relative `$XDG_CACHE_HOME` is invalid and ignored): where the command line's step entries,
    JAX's compiled programs and the native kernels' library are kept."""
    base = os.environ.get("XDG_CACHE_HOME") or ""
    root = Path(base) if os.path.isabs(base) else Path.home() / ".cache"
    return root / "radiometria"


def default_file_mode(*, executable: bool = False) -> int:
    """The permissions `open()` would give a new file: `0o666 & ~umask` (`0o777` if executable).

    The umask can only be read by setting it, so it is set and restored at once.
    """
    mask = os.umask(0o022)
    os.umask(mask)
    return (0o777 if executable else 0o666) & ~mask


def _temporary(path: Path) -> str:
    """Create a hidden temporary file next to `path` (same suffix) and return its name."""
    if not path.parent.exists():
        raise FileNotFoundError(
            errno.ENOENT, f"directory {str(path.parent)!r} does not exist", str(path)
        )
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    return tmp


def _fsync(name: str) -> None:
    fd = os.open(name, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def atomic_write_path(path, write: Callable[[str], None], *, mode: int | None = None) -> Path:
    """Atomically create `path` by calling `write(tmp)` on the name of a temporary file.

    For writers that need a file *name*: OpenEXR, `matplotlib.savefig` (the temporary file has
    the target's suffix, so the format is inferred from it), a compiler's `-o`. `write` may
    replace the file rather than write into it. The result gets `mode` (default
    `default_file_mode()`) and is renamed onto `path`; on any exception the temporary file is
    removed and the exception propagates. A missing directory raises `FileNotFoundError`
    naming it. Returns `path` as a `Path`.
    """
    path = Path(path)
    tmp = _temporary(path)
    try:
        write(tmp)
        _fsync(tmp)
        os.chmod(tmp, default_file_mode() if mode is None else mode)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def atomic_write(path, write: Callable[[BinaryIO], None], *, mode: int | None = None) -> Path:
    """Atomically create `path` by calling `write(f)` on a binary file object.

    As `atomic_write_path`, for writers that take an open file (`np.savez`, `f.write`).
    Returns `path` as a `Path`.
    """

    def write_file(tmp: str) -> None:
        with open(tmp, "wb") as f:
            write(f)

    return atomic_write_path(path, write_file, mode=mode)


def atomic_write_bytes(path, data: bytes, *, mode: int | None = None) -> Path:
    """Atomically write the bytes `data` to `path` (see `atomic_write_path`); returns `path`."""
    return atomic_write(path, lambda f: f.write(data), mode=mode)


def npz_bytes(arrays: Mapping[str, np.ndarray]) -> bytes:
    """The bytes of a deterministic compressed `.npz` of `arrays` (readable by `np.load`).

    Members `<key>.npy` in sorted key order, deflate-compressed, dated 1980-01-01 with mode
    0o644, each array C-contiguous in NumPy's `.npy` format without pickle (object arrays are
    refused). Equal arrays give equal bytes.
    """
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name in sorted(arrays):
            member = io.BytesIO()
            np.lib.format.write_array(
                member, np.ascontiguousarray(arrays[name]), allow_pickle=False
            )
            info = zipfile.ZipInfo(f"{name}.npy", date_time=NPZ_DATE_TIME)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = NPZ_MEMBER_MODE << 16
            zf.writestr(info, member.getvalue())
    return buf.getvalue()


def write_npz_deterministic(
    path, arrays: Mapping[str, np.ndarray], *, mode: int | None = None
) -> Path:
    """Atomically write `npz_bytes(arrays)` to `path`; returns `path` as a `Path`."""
    return atomic_write_bytes(path, npz_bytes(arrays), mode=mode)


def hash_array(h, array) -> None:
    """Feed an array into the hash `h` (a `hashlib` object) by content: its dtype and shape,
    then its bytes in C order, so that equal arrays hash equally whatever their layout."""
    a = np.asarray(array)
    h.update(f"{a.dtype}{a.shape}".encode())
    h.update(np.ascontiguousarray(a).tobytes())
