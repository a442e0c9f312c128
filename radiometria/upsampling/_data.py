r"""The packaged sRGB coefficient table and `get_lut`.

`data/srgb_64.npz` holds the res-64 sRGB table fitted by this package's own `fit_lut`
(float32, default settings; regenerate with `python -m radiometria.upsampling._make_data`). To
keep the wheel small the float32 coefficients are stored *byte-shuffled* (the four byte planes
of every float one after another, `coeffs_planes` of shape (4, 3 res^3 3), uint8) before
zlib compression, which shrinks the file from 8.9 MB to about 6.7 MB; decoding is exact (a
reshape and a view), and the sha256 in `metadata` (of the decoded `scale` and `coeffs`, as in
`.npz` tables) is checked on load. `metadata` also records the fit settings, the residual
distribution of the table points and the round-trip statistics measured when the file was made.

The file is read on the first `get_lut()` call, not at import (the table is 9.4 MB in memory).
"""

import functools
from pathlib import Path

import numpy as np

from ..colorimetry import get_colourspace
from ._fit_lut import fit_lut
from ._io import encode_planes as encode_planes, load_lut
from ._lut import RGBToSpectrumLUT

DATA_DIR = Path(__file__).parent / "data"
SRGB_FILE = DATA_DIR / "srgb_64.npz"


def read_packaged(path: Path = SRGB_FILE) -> tuple[np.ndarray, np.ndarray, dict]:
    """(scale, coeffs, metadata) of a packaged table, validated as `load_lut` validates files
    (shapes, finiteness, sha256)."""
    lut, info = load_lut(path, with_info=True)
    return np.asarray(lut.scale), np.asarray(lut.coeffs), info["metadata"]


@functools.lru_cache(maxsize=8)
def _get_lut_cached(name: str) -> RGBToSpectrumLUT:
    if name == "sRGB":
        return load_lut(SRGB_FILE)
    return fit_lut(name, 64, throw=False).lut


def get_lut(space="sRGB") -> RGBToSpectrumLUT:
    """The res-64 coefficient table of an RGB colour space, cached for the session.

    sRGB comes from the packaged file (fitted by `fit_lut`, see `_data.py`; the first call
    reads and checks it, later calls return the cached table). Any other space of
    `colorimetry.RGB_COLOURSPACES` is fitted on first use with `fit_lut(space, 64,
    throw=False)` (a few seconds) and kept in memory; to keep it across sessions, write it
    with `save_lut` and read it with `load_lut`. Entries of wide-gamut spaces that no
    sigmoid spectrum reaches are least-squares best fits (see `fit_lut`).

    **Arguments:**

    - `space`: colour-space name or alias (default "sRGB"). [-]

    **Returns:**

    The `RGBToSpectrumLUT`.

    !!! note "Thesis"
        Section 2.2.3 (the precomputed lookup table).

    ??? cite "References"
        `Jakob2019`; `Pharr2023` section 4.6.6.
    """
    return _get_lut_cached(get_colourspace(space).name)
