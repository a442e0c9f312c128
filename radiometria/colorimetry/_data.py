"""Packaged CIE tables: colour-matching functions, standard illuminants, daylight basis.

The tables live in `radiometria/colorimetry/data/` as one float64 `.npz` per family and are
loaded at import as **NumPy** arrays (style.md section 8); the accessors below turn them into
JAX arrays. They are the CIE tabulations that colour-science 0.4.7 ships, copied unchanged by
`radiometria.colorimetry._make_data.build_data`; `data/provenance.json` records, per file, the
primary source, the licence, the retrieval date and the sha256:

- `cmfs_xyz.npz`: CIE 1931 2°, CIE 1964 10° (360-830 nm) and CIE 2015 2°, 10° (390-830 nm)
  XYZ CMFs at 1 nm; sha256
  `a651608807bbbd1eeef16446ea8b16c5a768c8971be0d4b9203202ff3f359936`.
- `cmfs_rgb.npz`: Wright & Guild 1931 2° CIE RGB CMFs, 380-780 nm at 5 nm; sha256
  `0cf0455ed476617ebef14aa04eea96201775c88f4da814c6c86613f5e5d52d88`.
- `illuminants.npz`: CIE A, D50, D55, D65, D75 (300-780 nm), E (360-830 nm), FL1-FL12
  (380-780 nm), all at 5 nm; sha256
  `fe334b007f7b1ddce6cbab3470aa282670e5eeaae52b3659a5d0606e0832db95`.
- `daylight_basis.npz`: CIE D-series basis S0, S1, S2, 300-830 nm at 5 nm; sha256
  `488168b8bd757aafb13833e87f08782810cfdd27798916c7d6ecdd238de4147d`.

Sources: CIE 015:2018 / CIE 15:2004 tables (`CIE2018`, `CIE2004`), CIE 170-2:2015 via CVRL
(http://cvrl.ioo.ucl.ac.uk), Broadbent (2009) for the Wright & Guild RGB CMFs; CIE data tables
(https://cie.co.at/data-tables, CC BY-SA 4.0) as redistributed by colour-science (BSD-3-Clause).
Extracted on 2026-11-22 from colour-science 0.4.7. `tests/colorimetry/test_data.py` checks the
values against colour-science and the sha256 against this list and `provenance.json`.
"""

import json
from pathlib import Path

import equinox as eqx
import numpy as np
from jaxtyping import Array, Float

from .._checks import as_float_array, check_choice, device_array
from .._math import interp_columns
from ..radiometry import AbstractSpectrum

_DATA_DIR = Path(__file__).parent / "data"
PROVENANCE: dict = json.loads((_DATA_DIR / "provenance.json").read_text())


def _load(fname: str) -> dict[str, np.ndarray]:
    with np.load(_DATA_DIR / fname, allow_pickle=False) as f:
        return {k: np.asarray(f[k], dtype=np.float64) for k in f.files}


_XYZ = _load("cmfs_xyz.npz")
_RGB = _load("cmfs_rgb.npz")
_ILL = _load("illuminants.npz")
_DAY = _load("daylight_basis.npz")

# Canonical observer name -> (wavelengths (n,), values (n, 3)), NumPy float64.
CMFS_XYZ: dict[str, tuple[np.ndarray, np.ndarray]] = {
    name: (_XYZ[f"{key}_wavelengths"], _XYZ[f"{key}_values"])
    for name, key in {
        "CIE 1931 2 Degree Standard Observer": "cie_1931_2",
        "CIE 1964 10 Degree Standard Observer": "cie_1964_10",
        "CIE 2015 2 Degree Standard Observer": "cie_2015_2",
        "CIE 2015 10 Degree Standard Observer": "cie_2015_10",
    }.items()
}
CMFS_RGB: dict[str, tuple[np.ndarray, np.ndarray]] = {
    "Wright & Guild 1931 2 Degree RGB CMFs": (
        _RGB["wright_guild_1931_2_wavelengths"],
        _RGB["wright_guild_1931_2_values"],
    )
}
ILLUMINANTS_SD: dict[str, tuple[np.ndarray, np.ndarray]] = {
    name: (_ILL[f"{name}_wavelengths"], _ILL[f"{name}_values"])
    for name in ["A", "D50", "D55", "D65", "D75", "E"] + [f"FL{i}" for i in range(1, 13)]
}
DAYLIGHT_BASIS_WAVELENGTHS: np.ndarray = _DAY["S0_wavelengths"]
DAYLIGHT_BASIS: np.ndarray = np.stack([_DAY[f"S{i}_values"] for i in range(3)], axis=-1)  # (n, 3)
del _XYZ, _RGB, _ILL, _DAY

# Aliases -> canonical names. colour's short keys and the degree-sign spelling.
OBSERVER_ALIASES: dict[str, str] = {
    "cie_2_1931": "CIE 1931 2 Degree Standard Observer",
    "cie_10_1964": "CIE 1964 10 Degree Standard Observer",
    "CIE 1931 2°": "CIE 1931 2 Degree Standard Observer",
    "CIE 1964 10°": "CIE 1964 10 Degree Standard Observer",
    "CIE 2015 2°": "CIE 2015 2 Degree Standard Observer",
    "CIE 2015 10°": "CIE 2015 10 Degree Standard Observer",
    "CIE 1931 RGB": "Wright & Guild 1931 2 Degree RGB CMFs",
}
DEFAULT_OBSERVER = "CIE 1931 2 Degree Standard Observer"


class TabulatedSpectra(AbstractSpectrum):
    """One or more spectra tabulated on a common wavelength grid.

    - `wavelengths_nm`: strictly increasing sample wavelengths, shape (n,). [nm]
    - `values`: samples, shape (n,) for one spectrum or (n, k) for k spectra (e.g. the three
      CMFs x̄, ȳ, z̄ in the last axis). [the table's unit; CMFs and illuminants are relative]
    - `name`: the table's canonical name (static).

    Calling the object interpolates linearly: `spectra(wavelength_nm)` has shape
    `wavelength_nm.shape` (one spectrum) or `wavelength_nm.shape + (k,)`: a
    `radiometry.AbstractSpectrum` whose channel axis, unlike a batch axis, comes last
    (colour's convention for multi-spectral tables).

    ??? cite "References"
        `CIE2018` (the tabulated CMFs and illuminants); provenance in the module docstring.
    """

    wavelengths_nm: Float[Array, " n"]
    values: Float[Array, " n *k"]
    name: str = eqx.field(static=True, default="")

    def __check_init__(self):
        if self.wavelengths_nm.ndim != 1 or self.values.shape[:1] != self.wavelengths_nm.shape:
            raise ValueError(
                f"`values` {self.values.shape} must have the length of `wavelengths_nm` "
                f"{self.wavelengths_nm.shape} on its first axis."
            )

    def __call__(self, wavelength_nm, *, extrapolation: str = "zero") -> Array:
        """Linear interpolation at `wavelength_nm` [nm]; outside the table `extrapolation`
        is "zero" (a CMF is 0 where it is not tabulated) or "constant" (edge value, colour's
        default extrapolator)."""
        check_choice(extrapolation, "extrapolation", ["zero", "constant"])
        wl = as_float_array(wavelength_nm, "wavelength_nm")
        return interpolate_table(self.wavelengths_nm, self.values, wl, extrapolation=extrapolation)


def interpolate_table(
    table_wavelengths, table_values, wavelength_nm: Array, *, extrapolation: str = "zero"
) -> Array:
    """Linear interpolation of a table (n,) or (n, k) at `wavelength_nm` (any shape), in the
    dtype of `wavelength_nm`. Outside the table: 0 ("zero") or the edge value ("constant")."""
    dtype = wavelength_nm.dtype
    xp = device_array(table_wavelengths, dtype=dtype)
    fp = device_array(table_values, dtype=dtype)
    left = right = 0.0 if extrapolation == "zero" else None
    return interp_columns(wavelength_nm, xp, fp, left=left, right=right)


def resolve_observer(observer: str, *, allow_rgb: bool = True) -> str:
    """Canonical observer name for `observer` (aliases allowed); ValueError listing the valid."""
    if not isinstance(observer, str):
        raise TypeError(f"`observer` must be a name (str), got {type(observer).__name__}.")
    name = OBSERVER_ALIASES.get(observer, observer)
    if not allow_rgb and name in CMFS_RGB:
        raise ValueError(
            f"`observer` must be an XYZ observer here; {observer!r} has r, g, b colour-matching "
            "functions (CIE 1931 RGB tristimulus values come from `sd_to_CIE_RGB`)."
        )
    valid = list(CMFS_XYZ) + (list(CMFS_RGB) if allow_rgb else [])
    aliases = [a for a, c in OBSERVER_ALIASES.items() if c in valid]
    if name not in valid:
        raise ValueError(
            f"Unknown observer {observer!r}; valid values are: {', '.join(map(repr, valid))} "
            f"(aliases: {', '.join(map(repr, aliases))})."
        )
    return name


def get_cmfs(observer: str = DEFAULT_OBSERVER) -> TabulatedSpectra:
    """The colour-matching functions of a CIE standard observer, as a `TabulatedSpectra`.

    **Arguments:**

    - `observer`: one of "CIE 1931 2 Degree Standard Observer" (default),
        "CIE 1964 10 Degree Standard Observer", "CIE 2015 2 Degree Standard Observer",
        "CIE 2015 10 Degree Standard Observer" (x̄, ȳ, z̄, 1 nm) or
        "Wright & Guild 1931 2 Degree RGB CMFs" (r̄, ḡ, b̄ of the CIE 1931 RGB system, 5 nm).
        Aliases: "CIE 1931 2°", "CIE 1964 10°", "CIE 2015 2°", "CIE 2015 10°", "CIE 1931 RGB",
        and colour's "cie_2_1931", "cie_10_1964".

    **Returns:**

    `TabulatedSpectra` with `wavelengths_nm` (n,) [nm] and `values` (n, 3) [dimensionless],
    in the default JAX float dtype.

    !!! note "Thesis"
        Figure 2.1 and eq. 2.7-2.14, section 2.2.

    ??? cite "References"
        `CIE2018` (CIE 015:2018) tables; `Broadbent2009` (Wright & Guild RGB). Provenance and
        sha256: see the module docstring and `data/provenance.json`.
    """
    name = resolve_observer(observer)
    wl, v = {**CMFS_XYZ, **CMFS_RGB}[name]
    return TabulatedSpectra(device_array(wl), device_array(v), name)


def resolve_illuminant(name: str) -> str:
    if not isinstance(name, str):
        raise TypeError(f"`illuminant` name must be a str, got {type(name).__name__}.")
    return check_choice(name, "illuminant", ILLUMINANTS_SD.keys())


def get_illuminant(name: str) -> TabulatedSpectra:
    """The relative spectral power distribution of a CIE standard illuminant.

    **Arguments:**

    - `name`: "A", "D50", "D55", "D65", "D75", "E" or "FL1" ... "FL12".

    **Returns:**

    `TabulatedSpectra` with `wavelengths_nm` (n,) [nm] and `values` (n,) [relative, 100 at
    560 nm for A and the D series], as tabulated by the CIE: A and D at 300-780 nm, E at
    360-830 nm, FL at 380-780 nm, all at 5 nm.

    !!! note "Thesis"
        Table 2.1, section 2.2.1.

    ??? cite "References"
        `CIE2004` (CIE 15:2004 tables), `CIE2018`. Provenance and sha256: module docstring.
    """
    name = resolve_illuminant(name)
    wl, v = ILLUMINANTS_SD[name]
    return TabulatedSpectra(device_array(wl), device_array(v), name)
