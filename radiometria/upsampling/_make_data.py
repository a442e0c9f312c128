"""Regenerate the packaged sRGB table: `python -m radiometria.upsampling._make_data`.

Fits the res-64 sRGB table with `fit_lut` (default settings, float32), measures its round-trip
CIEDE2000 on the standard test sets (in float64), and writes `data/srgb_64.npz` atomically in
the byte-plane layout described in `_data.py`, with the fit settings, the residual
distribution of the table points and the round-trip statistics in its metadata.
"""

import importlib.metadata
import json
import sys

import jax
import numpy as np

from .._io import atomic_write
from ._data import SRGB_FILE, encode_planes
from ._fit_lut import fit_lut
from ._io import checksum
from ._roundtrip import (
    roundtrip_delta_E,
    roundtrip_grid_rgb,
    roundtrip_random_rgb,
    roundtrip_statistics,
)


def build_data(out=None, *, resolution: int = 64) -> dict:
    """Fit, measure and write the packaged table; return its metadata."""
    out = SRGB_FILE if out is None else out
    fit = fit_lut("sRGB", resolution)
    scale = np.asarray(fit.lut.scale, np.float32)
    coeffs = np.asarray(fit.lut.coeffs, np.float32)
    with jax.enable_x64(True):
        grid = roundtrip_grid_rgb(33)
        rnd = roundtrip_random_rgb(100_000, seed=0)
        de_grid, _ = roundtrip_delta_E(fit.lut, grid)
        de_rnd, _ = roundtrip_delta_E(fit.lut, rnd)
    meta = {
        "format": "radiometria-rgb2spec-planes",
        "version": 1,
        "colourspace": "sRGB",
        "resolution": resolution,
        "dtype": "float32",
        "sha256": checksum(scale, coeffs),
        "fit": fit.settings,
        "fit_summary": fit.summary(),
        "roundtrip_grid33_encoded": roundtrip_statistics(de_grid, grid),
        "roundtrip_random_1e5_linear": roundtrip_statistics(de_rnd, rnd),
        "created_by": f"radiometria {importlib.metadata.version('radiometria')}",
    }

    def write(f):
        planes = encode_planes(coeffs)
        np.savez_compressed(
            f, scale=scale, coeffs_planes=planes, metadata=np.asarray(json.dumps(meta))
        )

    atomic_write(out, write)
    return meta


if __name__ == "__main__":
    meta = build_data(sys.argv[1] if len(sys.argv) > 1 else None)
    print(json.dumps({k: meta[k] for k in meta if k != "fit"}, indent=2))
