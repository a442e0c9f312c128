"""Regenerate the packaged tables: `python -m radiometria.upsampling._make_data [SPACE ...]`.

For each colour space (default: the four of `_data.PACKAGED_FILES`: sRGB, Display P3,
ITU-R BT.2020, ACEScg) this fits the res-64 table with `fit_lut` (default settings, float32,
`throw=False`: wide-gamut spaces have entries that no reflectance reaches, reported as
`RESULTS.out_of_reach`), measures its round-trip CIEDE2000 (in float64) on the standard test
sets and on a dense linear grid of the space's RGB cube, each split into the colours that a
reflectance can have and those it cannot (`_roundtrip.has_reflectance`), and writes
`data/<file>` with `radiometria._io.write_npz_deterministic` in the byte-plane layout described
in `_data.py`, with the fit settings, the residual distribution of the table points and the
statistics in its metadata. Nothing time-dependent goes into the file (the fit's wall time is
printed, not stored), so the same table gives the same bytes. It prints the metadata and the
file's sha256, which goes into `_data.PACKAGED_SHA256` and the `_data.py` docstring.

`python -m radiometria.upsampling._make_data --tails-only [SPACE ...]` runs only `fit_lut`'s
last stage (the infrared-tail refit, `_tails.suppress_infrared_tails`) on the packaged table,
the output of stages 1-3, and rewrites the file with the stage's report in `metadata["fit"]`
and the statistics measured again: the table `fit_lut` gives today, without refitting the
786 432 entries that the stage does not touch.
"""

import hashlib
import importlib.metadata
import json
import sys
from pathlib import Path

import jax
import numpy as np

from .._io import write_npz_deterministic
from ..colorimetry import get_colourspace
from ._data import DATA_DIR, PACKAGED_FILES, encode_planes, read_packaged
from ._fit_lut import fit_lut
from ._io import checksum
from ._layout import column_directions
from ._lut import REFINE_STEPS, RGBToSpectrumLUT
from ._roundtrip import (
    has_reflectance,
    roundtrip_delta_E,
    roundtrip_grid_rgb,
    roundtrip_random_rgb,
    roundtrip_statistics,
)
from ._tails import colour_errors, suppress_infrared_tails

FORMAT = "radiometria-rgb2spec-planes"
LINEAR_GRID = 49  # the dense linear grid of the RGB cube: 49^3 = 117 649 colours


def linear_grid_rgb(n: int = LINEAR_GRID) -> np.ndarray:
    """The n^3 grid of *linear* values i / (n - 1) (float64, (n^3, 3)). [-]"""
    v = np.linspace(0.0, 1.0, n)
    return np.stack(np.meshgrid(v, v, v, indexing="ij"), axis=-1).reshape(-1, 3)


def split_statistics(lut, rgb: np.ndarray) -> dict:
    """Round-trip CIEDE2000 over `rgb`, all colours and split by `has_reflectance`."""
    de, _ = roundtrip_delta_E(lut, rgb)
    ok = has_reflectance(rgb, lut.colourspace)
    out = {
        "all": roundtrip_statistics(de, rgb),
        "fraction_out_of_reach": float(1.0 - ok.mean()),
        "reachable": roundtrip_statistics(de[ok], rgb[ok]),
    }
    if (~ok).any():
        out["out_of_reach"] = roundtrip_statistics(de[~ok], rgb[~ok])
        # The colours that stay reachable when 2 % brighter (not in the solid's last shell).
        inner = ok & has_reflectance(rgb, lut.colourspace, headroom=1.02)
        out["reachable_headroom_1.02"] = roundtrip_statistics(de[inner], rgb[inner])
    return out


def measure(lut) -> dict:
    """The round-trip statistics stored in a packaged table's metadata (float64)."""
    with jax.enable_x64(True):
        return {
            "roundtrip_grid33_encoded": split_statistics(
                lut, roundtrip_grid_rgb(33, lut.colourspace)
            ),
            "roundtrip_random_1e5_linear": split_statistics(
                lut, roundtrip_random_rgb(100_000, seed=0)
            ),
            f"roundtrip_grid{LINEAR_GRID}_linear": split_statistics(lut, linear_grid_rgb()),
        }


def _write(out: Path, scale, coeffs, meta: dict) -> dict:
    arrays = {
        "scale": scale,
        "coeffs_planes": encode_planes(coeffs),
        "metadata": np.asarray(json.dumps(meta, sort_keys=True)),
    }
    write_npz_deterministic(out, arrays, mode=0o644)
    return {**meta, "file_sha256": hashlib.sha256(out.read_bytes()).hexdigest()}


def apply_tail_stage(space="sRGB", out=None) -> dict:
    """Run `fit_lut`'s stage (4) on a packaged table and rewrite it (module docstring)."""
    name = get_colourspace(space).name
    src = DATA_DIR / PACKAGED_FILES[name]
    out = Path(src if out is None else out)
    scale, coeffs, meta = read_packaged(src)
    if meta["fit"].get("infrared_tails", "off") != "off":
        raise ValueError(f"{src}: the tail stage has already run on this table.")
    coeffs_old = coeffs
    stage = suppress_infrared_tails(coeffs, scale, name)
    coeffs = np.asarray(stage.coeffs, np.float32)
    # The file keeps no per-entry fit codes, so the replaced entries are classified as
    # `fit_lut` classifies them: converged (-> `tail_free`) where the stored entry was within
    # the fit's tolerance of its colour, out of reach (stays so) where not; row 0 is exact.
    res = scale.shape[0]
    l_, k_, j_, i_ = np.nonzero(stage.replaced[:, 1:])
    rgb = column_directions(res, np.float64).reshape(3, res, res, 3)[l_, j_, i_]
    rgb = rgb * np.asarray(scale, np.float64)[k_ + 1, None]
    de_old = colour_errors(np.asarray(coeffs_old)[l_, k_ + 1, j_, i_], rgb, name)
    n = int((de_old <= meta["fit"]["tolerance_delta_E_ab"]).sum())
    n += int(stage.replaced[:, 0].sum())
    meta = dict(meta)
    meta["fit"] = {**meta["fit"], "infrared_tails": stage.report}
    summary = dict(meta["fit_summary"])
    summary["converged"] -= n
    summary["tail_free"] = n
    meta["fit_summary"] = summary
    meta["sha256"] = checksum(scale, coeffs)
    lut = RGBToSpectrumLUT(scale, coeffs, name, REFINE_STEPS if summary["out_of_reach"] else 0)
    meta.update(measure(lut))
    meta["created_by"] = f"radiometria {importlib.metadata.version('radiometria')}"
    return _write(out, scale, coeffs, meta)


def build_data(space="sRGB", out=None, *, resolution: int = 64) -> dict:
    """Fit, measure and write one packaged table; return its metadata (plus `file_sha256`)."""
    name = get_colourspace(space).name
    out = Path(DATA_DIR / PACKAGED_FILES[name] if out is None else out)
    # One JAX device per CPU core if the caller made them (`__main__` does); the sharded fit
    # gives the same table bit for bit (tests/upsampling/test_fit_lut_sharded.py).
    devices = jax.devices() if len(jax.devices()) > 1 else None
    fit = fit_lut(name, resolution, devices=devices, throw=False)
    scale = np.asarray(fit.lut.scale, np.float32)
    coeffs = np.asarray(fit.lut.coeffs, np.float32)
    summary = {k: v for k, v in fit.summary().items() if k != "seconds"}
    meta = {
        "format": FORMAT,
        "version": 1,
        "colourspace": name,
        "resolution": resolution,
        "dtype": "float32",
        "sha256": checksum(scale, coeffs),
        "fit": fit.settings,
        "fit_summary": summary,
        **measure(fit.lut),
        "created_by": f"radiometria {importlib.metadata.version('radiometria')}",
    }
    print(f"{name}: fit {fit.seconds:.1f} s", file=sys.stderr)
    return _write(out, scale, coeffs, meta)


if __name__ == "__main__":
    from ._cli import _use_all_cpu_cores

    _use_all_cpu_cores()
    args = sys.argv[1:]
    tails_only = "--tails-only" in args
    spaces = [a for a in args if a != "--tails-only"] or list(PACKAGED_FILES)
    for sp in spaces:
        meta = apply_tail_stage(sp) if tails_only else build_data(sp)
        print(json.dumps({k: meta[k] for k in meta if k != "fit"}, indent=2))
