r"""The packaged coefficient tables (sRGB, Display P3, Rec.2020, ACEScg) and `get_lut`.

**Files.** `data/` holds one res-64 float32 table per colour space that pbrt-v4 also ships:

- sRGB: `srgb_64.npz`, sha256
  `e624c0b2506ba971ad50fa06ae6eb6e649aeec17bac5212d6aef431668ded58c`;
- Display P3: `display_p3_64.npz`, sha256
  `75671e12e5b238609eeb7fada437f4e38cdfe748a630d21c52465fad356e4aa9`;
- ITU-R BT.2020 (Rec.2020): `rec2020_64.npz`, sha256
  `982aecaabc4d8f64315f6d0728f0ae2f44769bc9ffd9b85c21e7b0f107379edb`;
- ACEScg: `acescg_64.npz`, sha256
  `d362e020078c00b4b38d64d373cc26ba5ba820f6f37343b929b92131c5c8ce1a`.

(`PACKAGED_SHA256` holds the same values; `tests/upsampling/test_wide_gamut.py` checks them.)

**Provenance.** Source: this package's own fit (`fit_lut(space, 64)`, default settings,
float32), regenerated with `python -m radiometria.upsampling._make_data [SPACE ...]`; no
third-party table is copied. The fit's last stage, the infrared-tail refit (`_tails.py`,
pbrt-v4 #82), was added after the tables were first fitted and was run on them with
`_make_data --tails-only` (the stage reads only the finished table, so this is the table
`fit_lut` gives); it replaced 12 212 (sRGB), 11 554 (Display P3), 11 076 (Rec.2020) and
10 732 (ACEScg) entries, and its report is in `metadata["fit"]["infrared_tails"]`. Inputs:
the CIE 1931 2° colour-matching functions and the CIE illuminants D65 (sRGB, Display P3,
Rec.2020) and CIE daylight at 6000 K x 1.4388/1.4380 (ACEScg's ACES white, as pbrt), from
`radiometria.colorimetry`'s packaged CIE tables (see `colorimetry/_data.py` for their source,
licence and sha256); the colour spaces' primaries and whites from
`colorimetry.RGB_COLOURSPACES`. Licence: the package's (Apache-2.0). Created 2026-11-24 (sRGB
earlier in the same release); `metadata["created_by"]` names the version.

**Layout.** To keep the wheel small the float32 coefficients are stored *byte-shuffled* (the
four byte planes of every float one after another, `coeffs_planes` of shape (4, 3 res^3 3),
uint8) before zlib compression, which shrinks a table from 8.9 MB to about 6.7 MB; decoding is
exact (a reshape and a view), and the sha256 in `metadata` (of the decoded `scale` and
`coeffs`, as in `.npz` tables) is checked on load. `metadata` also records the fit settings,
the residual distribution of the table points, the round-trip statistics measured when the
file was made, split into the colours that a reflectance can have and those it cannot
(`object_colour_scale`). The files are written by `radiometria._io.write_npz_deterministic`
(fixed zip timestamps, sorted members, no wall-clock value in `metadata`), so rebuilding them
from the same table gives the same file sha256.

**Accuracy** (round trip RGB -> spectrum -> RGB, CIEDE2000, float64; over the colours of each
cube that a reflectance can have, `_roundtrip.has_reflectance`; "out" is the fraction of the
cube no reflectance reaches; from the files' `metadata`, 49^3 linear grid and 1e5 uniform
random linear colours, max / mean):

| space | out (grid / random) | grid max / mean | random max / mean |
| --- | --- | --- | --- |
| sRGB | 0 / 0 | 0.23 / 0.010 | 0.50 / 0.011 |
| Display P3 | 0.52 % / 0.21 % | 1.77 / 0.014 | 4.78 / 0.017 |
| Rec.2020 | 9.9 % / 8.2 % | 1.93 / 0.025 | 3.61 / 0.029 |
| ACEScg | 14.7 % / 10.8 % | 2.88 / 0.032 | 6.36 / 0.042 |

The worst colours sit in table cells that touch out-of-reach nodes (dark reds with a trace of
green or blue next to Display P3's red, for one). The fits leave 56 (Display P3), 453
(Rec.2020) and 1272 (ACEScg) of 786 432 entries above the tolerance away from a stationary
point (`RESULTS.nonlinear_max_steps_reached`); nearly all are colours no reflectance has.

Each file is read on the first `get_lut(space)` call, not at import (a table is 9.4 MB in
memory).
"""

import functools
import importlib
from pathlib import Path

import numpy as np

from ..colorimetry import get_colourspace
from ._io import encode_planes as encode_planes, load_lut
from ._lut import RGBToSpectrumLUT

DATA_DIR = Path(__file__).parent / "data"
SRGB_FILE = DATA_DIR / "srgb_64.npz"
# Canonical colour-space name -> packaged file (res 64).
PACKAGED_FILES = {
    "sRGB": "srgb_64.npz",
    "Display P3": "display_p3_64.npz",
    "ITU-R BT.2020": "rec2020_64.npz",
    "ACEScg": "acescg_64.npz",
}
# sha256 of each packaged file's bytes (the table in the module docstring).
PACKAGED_SHA256 = {
    "srgb_64.npz": "e624c0b2506ba971ad50fa06ae6eb6e649aeec17bac5212d6aef431668ded58c",
    "display_p3_64.npz": "75671e12e5b238609eeb7fada437f4e38cdfe748a630d21c52465fad356e4aa9",
    "rec2020_64.npz": "982aecaabc4d8f64315f6d0728f0ae2f44769bc9ffd9b85c21e7b0f107379edb",
    "acescg_64.npz": "d362e020078c00b4b38d64d373cc26ba5ba820f6f37343b929b92131c5c8ce1a",
}


def packaged_path(space) -> Path | None:
    """The packaged table file of a colour space (name or alias), or None if none is shipped."""
    name = PACKAGED_FILES.get(get_colourspace(space).name)
    return None if name is None else DATA_DIR / name


def read_packaged(path: Path = SRGB_FILE) -> tuple[np.ndarray, np.ndarray, dict]:
    """(scale, coeffs, metadata) of a packaged table, validated as `load_lut` validates files
    (shapes, finiteness, sha256)."""
    lut, info = load_lut(path, with_info=True)
    return np.asarray(lut.scale), np.asarray(lut.coeffs), info["metadata"]


def fit_lut(*args, **kwargs):
    """`upsampling.fit_lut`, its module imported on the first call: rendering with a packaged
    table does not pay for importing the fitter and its solvers (optimistix, lineax)."""
    return importlib.import_module(f"{__package__}._fit_lut").fit_lut(*args, **kwargs)


@functools.lru_cache(maxsize=8)
def _get_lut_cached(name: str) -> RGBToSpectrumLUT:
    path = packaged_path(name)
    if path is not None:
        return load_lut(path)
    return fit_lut(name, 64, throw=False).lut


def get_lut(space="sRGB") -> RGBToSpectrumLUT:
    r"""The res-64 coefficient table of an RGB colour space, cached for the session.

    sRGB, Display P3, Rec.2020 ("ITU-R BT.2020") and ACEScg come from the packaged files
    (fitted by `fit_lut`; provenance and sha256 in `_data.py`): the first call reads and
    checks the file, later calls return the cached table. Any other space of
    `colorimetry.RGB_COLOURSPACES` is fitted on first use with `fit_lut(space, 64,
    throw=False)` and kept in memory; to keep it across sessions, write it with `save_lut`
    and read it with `load_lut`.

    **Colours no reflectance has.** A reflectance is bounded by 1 at every wavelength, so
    its colour lies in the object-colour solid (whose boundary is the Rösch-MacAdam optimal
    colours); the saturated, bright corners of a wide-gamut cube lie outside it (Rec.2020's
    primaries are monochromatic and Display P3's red is practically on the spectral locus,
    so no multiple of them has a reflectance; `_roundtrip.object_colour_scale`). No spectrum
    reproduces such a colour. At the table's nodes `fit_lut` stored the least-squares best
    fit of eq. 2.27 (`RESULTS.out_of_reach`): a sigmoid spectrum, so in [0, 1], whose colour
    is the nearest reachable one in CIELAB (checked: within 0.01 $\Delta E^*_{ab}$ of the
    nearest optimal colour on the 1 nm grid). Between nodes the wide-gamut lookups are refined
    by the same fit (below), which pulls the colour towards the nearest reachable one as well;
    the spectrum is in [0, 1] and its colour is one a reflectance has. The lookup neither fails
    nor clips for these colours: `rgb` in [0, 1] is all it checks.

    **Accuracy.** Every packaged table meets max CIEDE2000 <= 1 and mean <= 0.03 over the
    colours of its cube that a reflectance has (sRGB over its whole cube). sRGB gets there by
    pbrt's trilinear lookup. The wide-gamut tables' cells next to the object-colour solid's
    boundary mix exact nodes with best-fit nodes, and interpolation alone misses there by up to
    8 CIEDE2000 units, so their lookups finish with 32 Levenberg-Marquardt iterations of eq.
    2.27 (`RGBToSpectrumLUT.refine_steps`; measured max 0.02-0.06, mean < 1e-4; `_lut.py`).
    `lut.with_refinement(0)` gives pbrt's plain lookup.

    **Arguments:**

    - `space`: colour-space name or alias (default "sRGB"). [-]

    **Returns:**

    The `RGBToSpectrumLUT`.

    !!! note "Thesis"
        Section 2.2.3 (the precomputed lookup table).

    ??? cite "References"
        `Jakob2019`; `Pharr2023` section 4.6.6; `Wyszecki2000` (optimal object colours).
    """
    return _get_lut_cached(get_colourspace(space).name)
