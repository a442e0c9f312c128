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
import struct
import zipfile
from pathlib import Path

import numpy as np

from .._io import atomic_write
from ..colorimetry import RGB_COLOURSPACES
from ..constants import VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM
from ._forward import forward_model
from ._lut import RGBToSpectrumLUT

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


def _load_npz(path: Path):
    try:
        with np.load(path, allow_pickle=False) as f:
            files = set(f.files)
            # The packaged tables store the float32 coefficients as byte planes (`_data.py`).
            coeffs_name = "coeffs_planes" if "coeffs_planes" in files else "coeffs"
            missing = {"scale", coeffs_name} - files
            if missing:
                _fail(path, f"missing array(s) {sorted(missing)}; found {sorted(files)}.")
            scale = np.asarray(f["scale"])
            coeffs = np.asarray(f[coeffs_name])
            if coeffs_name == "coeffs_planes":
                res = scale.shape[0] if scale.ndim == 1 else -1
                if coeffs.dtype != np.uint8 or coeffs.shape != (4, 9 * res**3):
                    _fail(
                        path,
                        f"`coeffs_planes` must be uint8 of shape (4, {9 * res**3}) for res "
                        f"{res}, got {coeffs.dtype} {coeffs.shape}.",
                    )
                coeffs = decode_planes(coeffs, (3, res, res, res, 3))
            meta_raw = None
            if "metadata" in files:
                # A 0-d string, or shape (1,) as `radiometria._io.npz_bytes` stores a 0-d array.
                m = np.asarray(f["metadata"])
                meta_raw = str(m.reshape(-1)[0]) if m.size == 1 else str(m[()])
    except LUTFileError:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError) as err:
        _fail(path, f"not a readable .npz file ({type(err).__name__}: {err}).")
    _validate_arrays(path, scale, coeffs)
    meta = {}
    colourspace = "sRGB"
    if meta_raw is not None:
        try:
            meta = json.loads(meta_raw)
        except json.JSONDecodeError as err:
            _fail(path, f"`metadata` is not valid JSON ({err}).")
        expected = meta.get("sha256")
        if expected is not None:
            actual = checksum(scale, coeffs)
            if actual != expected:
                _fail(
                    path,
                    f"checksum mismatch: stored sha256 {expected[:16]}..., data {actual[:16]}...",
                )
        if meta.get("resolution", scale.shape[0]) != scale.shape[0]:
            _fail(
                path,
                f"metadata resolution {meta['resolution']} != array resolution {scale.shape[0]}.",
            )
        colourspace = meta.get("colourspace", colourspace)
    lut = RGBToSpectrumLUT(scale, coeffs, colourspace)
    return lut, {"format": "npz", "colourspace": colourspace, "metadata": meta}


def _load_coeff(path: Path):
    data = path.read_bytes()
    if len(data) < 8 or data[:4] != COEFF_MAGIC:
        _fail(path, f"not an rgb2spec file (header {data[:4]!r}, expected {COEFF_MAGIC!r}).")
    (res,) = struct.unpack_from("<I", data, 4)
    if res < 2 or res > 4096:
        _fail(path, f"implausible resolution {res}.")
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
