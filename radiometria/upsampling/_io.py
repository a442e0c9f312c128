r"""Coefficient-table files: `.npz` (pbrt layout, with metadata) and rgb2spec `.coeff`.

**`.npz`** (NumPy, compressed). Arrays `scale` (res,) and `coeffs` (3, res, res, res, 3) in
pbrt-v4's `RGBToSpectrumTable` layout (nm coefficients, float32 unless fitted in float64), and
`metadata`, a JSON string (0-d unicode array, so `np.load(..., allow_pickle=False)` reads it):
`format` ("radiometria-rgb2spec"), `version`, `colourspace`, `resolution`, `dtype`, `sha256`
(of the little-endian bytes of `scale` then `coeffs`, C order), `fit` (the fit settings) and
`created_by`.

**`.coeff`** (rgb2spec binary, little-endian), in two generations:

- *rgb2spec 2019* (Jakob & Hanika's original, used by Mitsuba 2 and older Mitsuba 3 releases):
  `b"SPEC"`, `uint32 res`, `float32 scale[res]`, `float32 data[3 res^3 3]`, nothing after.
- *rgb2spec 2026* (the rewrite Mitsuba 3 now bundles; pull request mitsuba-renderer/mitsuba3
  #1907): the same, followed by the *forward-model block* that its `rgb2spec_fetch_opt()` uses
  for a runtime Levenberg-Marquardt refinement: `uint32 nfine`, then `float32` arrays
  `lambda[nfine]` (normalised wavelengths (lambda - 360) / 470, padded with (0 - 360) / 470),
  `rgb_tbl[3][nfine]` (spectrum -> linear RGB quadrature weights, zero in the padding),
  `rgb_to_xyz[9]` (row-major) and `xyz_whitepoint[3]`. Its `rgb2spec_load()` refuses a file
  without the block.

What current Mitsuba reads was established three ways (`Mitsuba2026`; `tests/upsampling`):
the `data/srgb.coeff` that the installed Mitsuba 3.9.1 wheel ships is 9 442 108 bytes, 4 660
more than the 2019 layout for res 64, and the extra bytes parse exactly as the block above
(nfine = 288 = 283 Simpson nodes padded to a multiple of 16; the weights of each channel sum to
1; `rgb_to_xyz` is the sRGB matrix); `libmitsuba.so` exports `rgb2spec_fetch_opt`,
`rgb2spec_lab_jac` and `rgb2spec_fetch_mono`, which only the rewrite has; and Mitsuba 3.9.1
refuses a 2019-layout `data/srgb.coeff` ("Could not load sRGB-to-spectrum upsampling model")
while it loads the files this module writes. The byte layout itself follows the rewrite's
`rgb2spec.c` (`rgb2spec_load`) and `rgb2spec_opt.cpp`. Confidence: high for the layout (the
shipped file, the loader source and the loader's behaviour agree); the precise date of the
rewrite is not established here.

`save_lut` writes the 2026 layout (with this package's forward model in the block: the 1 nm grid,
471 nodes padded to 480); `load_lut` reads both and reports which one it found. Every write is
atomic (a temporary file in the same directory, then `os.replace`); every read validates the
header, sizes, shapes, dtype, finiteness and (for `.npz`) the checksum, and names the file and
the problem when something is wrong.
"""

import hashlib
import importlib.metadata
import json
import math
import re
import struct
import zipfile
import zlib
from pathlib import Path

import numpy as np

from .._io import atomic_write
from ..colorimetry import RGB_COLOURSPACES
from ..constants import VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM
from ._forward import forward_model
from ._lut import REFINE_STEPS, RGBToSpectrumLUT

FORMAT_NAME = "radiometria-rgb2spec"
FORMAT_VERSION = 1
COEFF_MAGIC = b"SPEC"
COEFF_2019 = "rgb2spec-2019"
COEFF_2026 = "rgb2spec-2026"


class LUTFileError(ValueError):
    """A coefficient-table file is missing, truncated, corrupt or inconsistent.

    Raised by `load_lut` for the table files of thesis section 2.2.3; a `ValueError`.
    """


def checksum(scale: np.ndarray, coeffs: np.ndarray) -> str:
    """sha256 of the little-endian C-order bytes of `scale` then `coeffs` (hex)."""
    h = hashlib.sha256()
    for a in (scale, coeffs):
        a = np.ascontiguousarray(a)
        h.update(a.astype(a.dtype.newbyteorder("<"), copy=False).tobytes())
    return h.hexdigest()


def _arrays(lut: RGBToSpectrumLUT) -> tuple[np.ndarray, np.ndarray]:
    scale = np.asarray(lut.scale)
    coeffs = np.asarray(lut.coeffs)
    return scale, coeffs


def save_lut(lut: RGBToSpectrumLUT, path, *, fit_settings: dict | None = None) -> Path:
    """Write a table to `path`: `.npz` (pbrt layout + metadata) or `.coeff` (rgb2spec 2026).

    **Arguments:**

    - `lut`: the table. [nm^-2, nm^-1, -]
    - `path`: file name ending in `.npz` or `.coeff`; written atomically. [-]
    - `fit_settings`: JSON-able fit settings stored in the `.npz` metadata (e.g.
        `LUTFitResult.settings`).

    **Returns:**

    The path written.

    !!! note "Thesis"
        Section 2.2.3 (the precomputed 5-D lookup table).

    ??? cite "References"
        `Jakob2019` (rgb2spec); `Mitsuba2026` (the current `.coeff` layout); `Pharr2023`
        section 4.6.6.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".coeff"):
        raise ValueError(f"Unknown table file type {str(path)!r}: use a .npz or .coeff file name.")
    scale, coeffs = _arrays(lut)
    if not (np.all(np.isfinite(scale)) and np.all(np.isfinite(coeffs))):
        raise ValueError(f"Refusing to write {str(path)!r}: the table has non-finite values.")
    if suffix == ".npz":
        meta = {
            "format": FORMAT_NAME,
            "version": FORMAT_VERSION,
            "colourspace": lut.colourspace,
            "resolution": lut.resolution,
            "dtype": str(coeffs.dtype),
            "layout": "coeffs[l, k, j, i, :] = nm coefficients (c0, c1, c2); l = largest "
            "channel, k = brightness index into scale, i / j = the next two channels (cyclic) "
            "over the largest, times (res - 1) (pbrt-v4 RGBToSpectrumTable)",
            "sha256": checksum(scale, coeffs),
            "fit": fit_settings or {},
            "created_by": f"radiometria {importlib.metadata.version('radiometria')}",
        }

        def write(f):
            np.savez_compressed(
                f, scale=scale, coeffs=coeffs, metadata=np.asarray(json.dumps(meta))
            )

    else:
        block = _forward_block(lut.colourspace)

        def write(f):
            f.write(COEFF_MAGIC)
            f.write(struct.pack("<I", lut.resolution))
            f.write(scale.astype("<f4").tobytes())
            f.write(coeffs.astype("<f4").tobytes())
            f.write(block)

    atomic_write(path, write)
    return path


def _forward_block(colourspace: str) -> bytes:
    """The rgb2spec 2026 forward-model block for this package's forward model."""
    model = forward_model(colourspace)
    lam = np.asarray(model.lambda_normalised)
    w_rgb = np.asarray(model.weights_XYZ) @ np.asarray(model.matrix_XYZ_to_RGB).T  # (n, 3)
    n = lam.size
    nfine = -(-n // 16) * 16
    lam_p = np.full(
        nfine,
        (0.0 - VISIBLE_WAVELENGTH_MIN_NM) / (VISIBLE_WAVELENGTH_MAX_NM - VISIBLE_WAVELENGTH_MIN_NM),
    )
    lam_p[:n] = lam
    tbl = np.zeros((3, nfine))
    tbl[:, :n] = w_rgb.T
    parts = [
        struct.pack("<I", nfine),
        lam_p.astype("<f4").tobytes(),
        tbl.astype("<f4").tobytes(),
        np.asarray(model.matrix_RGB_to_XYZ).astype("<f4").tobytes(),
        np.asarray(model.white_XYZ).astype("<f4").tobytes(),
    ]
    return b"".join(parts)


def _fail(path: Path, what: str):
    raise LUTFileError(f"Coefficient table {str(path)!r}: {what}")


def _validate_arrays(path: Path, scale: np.ndarray, coeffs: np.ndarray) -> None:
    if scale.ndim != 1 or scale.shape[0] < 2:
        _fail(path, f"`scale` must have shape (res,) with res >= 2, found {scale.shape}.")
    res = scale.shape[0]
    if coeffs.shape != (3, res, res, res, 3):
        _fail(
            path,
            f"`coeffs` must have shape {(3, res, res, res, 3)} (res {res}), found {coeffs.shape}.",
        )
    for name, a in (("scale", scale), ("coeffs", coeffs)):
        if a.dtype not in (np.float32, np.float64):
            _fail(path, f"`{name}` must be float32 or float64, found {a.dtype}.")
        if not np.all(np.isfinite(a)):
            _fail(path, f"`{name}` has {int(np.sum(~np.isfinite(a)))} non-finite values.")
    if not np.all(np.diff(scale) > 0) or scale[0] != 0.0 or scale[-1] != 1.0:
        _fail(path, "`scale` must increase strictly from 0 to 1.")


def load_lut(path, *, with_info: bool = False):
    """Read a table written by `save_lut`, by pbrt tools (`.npz` with `scale` / `coeffs`) or
    by rgb2spec (`.coeff`, either generation).

    **Arguments:**

    - `path`: a `.npz` or `.coeff` file. [-]
    - `with_info`: also return a dict with `format` ("npz", "rgb2spec-2019" or
        "rgb2spec-2026"), `colourspace` and, for `.npz`, the stored `metadata`.

    **Returns:**

    The `RGBToSpectrumLUT` (and the info dict). Raises `LUTFileError` (a `ValueError`) naming
    the file and the problem for a missing, truncated or corrupt file or a checksum mismatch;
    `.coeff` files carry no colour-space name and are read as sRGB unless their forward-model
    block says otherwise (then the space with that `rgb_to_xyz` matrix).

    !!! note "Thesis"
        Section 2.2.3 (the precomputed 5-D lookup table).

    ??? cite "References"
        `Jakob2019` (rgb2spec 2019); `Mitsuba2026` (rgb2spec 2026); `Pharr2023` section 4.6.6.
    """
    path = Path(path)
    if not path.is_file():
        raise LUTFileError(f"Coefficient table {str(path)!r}: no such file.")
    suffix = path.suffix.lower()
    if suffix == ".npz":
        lut, info = _load_npz(path)
    elif suffix == ".coeff":
        lut, info = _load_coeff(path)
    else:
        raise LUTFileError(
            f"Coefficient table {str(path)!r}: unknown file type (use .npz or .coeff)."
        )
    return (lut, info) if with_info else lut


def encode_planes(coeffs: np.ndarray) -> np.ndarray:
    """float32 array -> (4, n) uint8 byte planes (little-endian), the packaged `.npz` layout
    `coeffs_planes` (byte-shuffled floats compress better under zlib)."""
    c = np.ascontiguousarray(coeffs, dtype="<f4").reshape(-1)
    return np.ascontiguousarray(c.view(np.uint8).reshape(-1, 4).T)


def decode_planes(planes: np.ndarray, shape) -> np.ndarray:
    """Inverse of `encode_planes`: (4, n) uint8 byte planes -> float32 array of `shape`."""
    b = np.ascontiguousarray(np.asarray(planes, np.uint8).T)
    return b.view("<f4").reshape(shape).astype(np.float32)


MAX_RESOLUTION = 1024  # a res-1024 float32 table is 38.7 GB; nothing larger is read
METADATA_MAX_BYTES = 1 << 20
# A member that inflates more than this ratio and past this size is refused as a zip bomb
# (float tables compress about 1.5:1; a table of zeros that large is not a fitted table).
ZIP_BOMB_RATIO, ZIP_BOMB_MIN_BYTES = 100, 1 << 28


def _npy_header(path: Path, zf: zipfile.ZipFile, name: str) -> tuple[tuple, np.dtype, int]:
    """(shape, dtype, data bytes the member holds) of `name.npy`, read from its header only."""
    info = zf.getinfo(name + ".npy")
    if info.file_size > ZIP_BOMB_MIN_BYTES and info.file_size > ZIP_BOMB_RATIO * max(
        info.compress_size, 1
    ):
        _fail(
            path, f"`{name}` inflates from {info.compress_size:,} to {info.file_size:,} bytes "
            "(a zip bomb?); refused before reading."
        )  # fmt: skip
    with zf.open(info) as fp:
        version = np.lib.format.read_magic(fp)
        if version == (1, 0):
            shape, _, dtype = np.lib.format.read_array_header_1_0(fp)
        elif version == (2, 0):
            shape, _, dtype = np.lib.format.read_array_header_2_0(fp)
        else:
            _fail(path, f"`{name}` uses .npy format version {version}; only 1.0 and 2.0 are read.")
        return shape, dtype, info.file_size - fp.tell()


def _check_declared(path: Path, zf: zipfile.ZipFile, files: set, coeffs_name: str) -> None:
    """Refuse wrong shapes, dtypes and sizes from the .npy headers, before reading any data."""
    declared = {
        n: _npy_header(path, zf, n) for n in ("scale", coeffs_name, "metadata") if n in files
    }
    for name, (shape, dtype, available) in declared.items():
        nbytes = math.prod(shape) * dtype.itemsize
        if nbytes > available:
            _fail(
                path, f"`{name}` declares shape {shape} of {dtype} ({nbytes:,} bytes), but the "
                f"file holds {available:,} bytes for it (truncated or corrupt)."
            )  # fmt: skip
    shape, dtype, _ = declared["scale"]
    if len(shape) != 1 or not 2 <= shape[0] <= MAX_RESOLUTION or dtype.kind != "f":
        _fail(
            path, f"`scale` must be a float array of shape (res,) with 2 <= res <= "
            f"{MAX_RESOLUTION}; its header declares {dtype} {shape}."
        )  # fmt: skip
    res = shape[0]
    shape, dtype, _ = declared[coeffs_name]
    planes = coeffs_name == "coeffs_planes"
    want = (4, 9 * res**3) if planes else (3, res, res, res, 3)
    if shape != want or (dtype != np.uint8 if planes else dtype.kind != "f"):
        _fail(
            path, f"`{coeffs_name}` must be {'uint8' if planes else 'float'} of shape "
            f"{want} (res {res}); its header declares {dtype} {shape}."
        )  # fmt: skip
    if "metadata" in declared:
        shape, dtype, _ = declared["metadata"]
        nbytes = math.prod(shape) * dtype.itemsize
        if dtype.kind not in "US" or math.prod(shape) != 1 or nbytes > METADATA_MAX_BYTES:
            _fail(
                path, "`metadata` must be one JSON string (0-d or shape (1,), at most "
                f"{METADATA_MAX_BYTES:,} bytes); its header declares {dtype} {shape}."
            )  # fmt: skip


def _check_metadata(path: Path, meta, res: int) -> dict:
    """Validate the fields of a `.npz` table's metadata that `load_lut` uses."""
    if not isinstance(meta, dict):
        _fail(path, f"`metadata` must be a JSON object, found {type(meta).__name__}.")
    fmt = meta.get("format")
    if fmt is not None and fmt not in (FORMAT_NAME, FORMAT_NAME + "-planes"):
        _fail(path, f"metadata `format` {fmt!r} is not {FORMAT_NAME!r}.")
    version = meta.get("version", FORMAT_VERSION)
    if not isinstance(version, int) or isinstance(version, bool) or not 1 <= version:
        _fail(path, f"metadata `version` must be an integer >= 1, found {version!r}.")
    if version > FORMAT_VERSION:
        _fail(
            path, f"metadata `version` {version} is newer than this reader's {FORMAT_VERSION}; "
            "update radiometria."
        )  # fmt: skip
    sha = meta.get("sha256")
    if sha is not None and not (isinstance(sha, str) and re.fullmatch(r"[0-9a-f]{64}", sha)):
        _fail(path, f"metadata `sha256` must be 64 lowercase hex digits, found {sha!r:.80}.")
    resolution = meta.get("resolution", res)
    if resolution != res or isinstance(resolution, bool):
        _fail(path, f"metadata `resolution` {resolution!r:.40} != array resolution {res}.")
    cs = meta.get("colourspace", "sRGB")
    if not isinstance(cs, str) or cs not in RGB_COLOURSPACES:
        _fail(
            path, f"metadata `colourspace` {cs!r:.80} is not one of {sorted(RGB_COLOURSPACES)}."
        )  # fmt: skip
    return meta


def _load_npz(path: Path):
    with open(path, "rb") as fh:
        magic = fh.read(4)
    if magic not in (b"PK\x03\x04", b"PK\x05\x06"):
        _fail(
            path, f"not a readable .npz file: it starts with {magic!r}, not a zip archive's "
            "b'PK\\x03\\x04'."
        )  # fmt: skip
    try:
        # The file is opened here, not by np.load, so that it is closed on every error.
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as f:
            files = set(f.files)
            # The packaged tables store the float32 coefficients as byte planes (`_data.py`).
            coeffs_name = "coeffs_planes" if "coeffs_planes" in files else "coeffs"
            missing = {"scale", coeffs_name} - files
            if missing:
                _fail(path, f"missing array(s) {sorted(missing)}; found {sorted(files)}.")
            _check_declared(path, f.zip, files, coeffs_name)
            scale = np.asarray(f["scale"])
            coeffs = np.asarray(f[coeffs_name])
            if coeffs_name == "coeffs_planes":
                res = scale.shape[0]
                coeffs = decode_planes(coeffs, (3, res, res, res, 3))
            meta_raw = None
            if "metadata" in files:
                # A 0-d string, or shape (1,) as `radiometria._io.npz_bytes` stores a 0-d array.
                meta_raw = str(np.asarray(f["metadata"]).reshape(-1)[0])
    except LUTFileError:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError, zlib.error) as err:
        _fail(
            path, f"not a readable .npz file, truncated or corrupt ({type(err).__name__}: {err})."
        )
    _validate_arrays(path, scale, coeffs)
    meta = {}
    colourspace = "sRGB"
    if meta_raw is not None:
        try:
            meta = json.loads(meta_raw)
        except (json.JSONDecodeError, RecursionError) as err:
            _fail(path, f"`metadata` is not valid JSON ({err}).")
        meta = _check_metadata(path, meta, scale.shape[0])
        expected = meta.get("sha256")
        if expected is not None:
            actual = checksum(scale, coeffs)
            if actual != expected:
                _fail(
                    path,
                    f"checksum mismatch: stored sha256 {expected[:16]}..., data {actual[:16]}...",
                )
        colourspace = meta.get("colourspace", colourspace)
    # A fit that met colours no reflectance has: its lookups are refined (`_lut.py`).
    summary = meta.get("fit_summary")
    unreachable = isinstance(summary, dict) and summary.get("out_of_reach", 0) > 0
    lut = RGBToSpectrumLUT(scale, coeffs, colourspace, REFINE_STEPS if unreachable else 0)
    return lut, {"format": "npz", "colourspace": colourspace, "metadata": meta}


def _load_coeff(path: Path):
    data = path.read_bytes()
    if len(data) < 8 or data[:4] != COEFF_MAGIC:
        _fail(path, f"not an rgb2spec file (header {data[:4]!r}, expected {COEFF_MAGIC!r}).")
    (res,) = struct.unpack_from("<I", data, 4)
    if not 2 <= res <= MAX_RESOLUTION:
        _fail(path, f"header resolution {res} is outside [2, {MAX_RESOLUTION}].")
    n_table = 8 + 4 * res + 4 * 9 * res**3
    if len(data) < n_table:
        _fail(path, f"truncated: {len(data)} bytes, the table of res {res} needs {n_table}.")
    scale = np.frombuffer(data, "<f4", res, 8).astype(np.float32)
    coeffs = (
        np.frombuffer(data, "<f4", 9 * res**3, 8 + 4 * res)
        .astype(np.float32)
        .reshape(3, res, res, res, 3)
    )
    _validate_arrays(path, scale, coeffs)
    colourspace = "sRGB"
    if len(data) == n_table:
        fmt = COEFF_2019
        block = None
    else:
        fmt = COEFF_2026
        rest = len(data) - n_table
        if rest < 4:
            _fail(path, f"{rest} trailing bytes: truncated forward-model block.")
        (nfine,) = struct.unpack_from("<I", data, n_table)
        need = 4 + 4 * (4 * nfine + 12)
        if nfine == 0 or rest != need:
            _fail(
                path,
                f"forward-model block of {rest} bytes does not match nfine {nfine} ({need} bytes).",
            )
        block = np.frombuffer(data, "<f4", 4 * nfine + 12, n_table + 4)
        if not np.all(np.isfinite(block)):
            _fail(path, "the forward-model block has non-finite values.")
        colourspace = _colourspace_from_matrix(block[4 * nfine : 4 * nfine + 9].reshape(3, 3))
    lut = RGBToSpectrumLUT(scale, coeffs, colourspace)
    return lut, {"format": fmt, "colourspace": colourspace, "metadata": {}}


def _colourspace_from_matrix(m: np.ndarray) -> str:
    best, err = "sRGB", np.inf
    for name, cs in RGB_COLOURSPACES.items():
        e = float(np.abs(np.asarray(cs.matrix_RGB_to_XYZ) - m).max())
        if e < err:
            best, err = name, e
    return best if err < 1e-3 else "sRGB"
