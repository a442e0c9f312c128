"""Offline builder of the CIE tables in `radiometria/colorimetry/data/` (never run at import).

The tables are the CIE tabulations that colour-science ships (`colour.MSDS_CMFS`,
`colour.SDS_ILLUMINANTS`, `SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES`), copied unchanged as
float64 into one `.npz` per family, plus `provenance.json` with the source, licence and sha256 of
each file. The `.npz` files are written deterministically (fixed zip timestamps, sorted keys), so
rebuilding with the same colour-science version gives byte-identical files and the same sha256.

Run `python -m radiometria.colorimetry._make_data` to rebuild; `tests/colorimetry/test_data.py`
checks that the packaged values equal colour-science's.
"""

import datetime
import hashlib
import json
from pathlib import Path

import numpy as np

from .._io import atomic_write_bytes, write_npz_deterministic

DATA_DIR = Path(__file__).parent / "data"

# Packaged name -> colour-science key, per family.
XYZ_CMFS = {
    "CIE 1931 2 Degree Standard Observer": "cie_1931_2",
    "CIE 1964 10 Degree Standard Observer": "cie_1964_10",
    "CIE 2015 2 Degree Standard Observer": "cie_2015_2",
    "CIE 2015 10 Degree Standard Observer": "cie_2015_10",
}
RGB_CMFS = {"Wright & Guild 1931 2 Degree RGB CMFs": "wright_guild_1931_2"}
ILLUMINANTS = ["A", "D50", "D55", "D65", "D75", "E"] + [f"FL{i}" for i in range(1, 13)]
D_SERIES = ["S0", "S1", "S2"]

_CIE_LICENCE = (
    "CIE tabulations (CIE 015:2018 / CIE 015:2004 tables; CIE 170-2:2015 for the 2015 observers), "
    "distributed by the CIE as data tables (https://cie.co.at/data-tables, CC BY-SA 4.0); the copy "
    "used here is the one shipped by colour-science (BSD-3-Clause, "
    "https://github.com/colour-science/colour)."
)

FILES = {
    "cmfs_xyz.npz": {
        "family": "CIE XYZ colour-matching functions, 1 nm",
        "colour_object": "colour.MSDS_CMFS[...] (colour/colorimetry/datasets/cmfs.py)",
        "primary_source": (
            "CIE 015:2018 table (1931 2 deg, 1964 10 deg), via CVRL 'Older CIE Standards' "
            "http://cvrl.ioo.ucl.ac.uk/cie.htm; CIE 170-2:2015 'New CIE XYZ functions transformed "
            "from the CIE (2006) LMS functions' http://cvrl.ioo.ucl.ac.uk/ciexyzpr.htm"
        ),
        "tables": list(XYZ_CMFS),
    },
    "cmfs_rgb.npz": {
        "family": "CIE 1931 RGB colour-matching functions (Wright & Guild), 5 nm",
        "colour_object": (
            "colour.colorimetry.MSDS_CMFS_RGB[...] (colour/colorimetry/datasets/cmfs.py)"
        ),
        "primary_source": (
            "Broadbent, A. D. (2009). Calculation from the original experimental data of the CIE "
            "1931 RGB standard observer spectral chromaticity co-ordinates and color matching "
            "functions. http://www.cis.rit.edu/mcsl/research/1931.php"
        ),
        "tables": list(RGB_CMFS),
    },
    "illuminants.npz": {
        "family": "CIE standard illuminants A, D50, D55, D65, D75, E, FL1-FL12 (relative SPD)",
        "colour_object": (
            "colour.SDS_ILLUMINANTS[...] (colour/colorimetry/datasets/illuminants/sds.py)"
        ),
        "primary_source": (
            "CIE 15:2004 tables, "
            "https://law.resource.org/pub/us/cfr/ibr/003/cie.15.2004.tables.xls "
            "and http://files.cie.co.at/204.xls"
        ),
        "tables": ILLUMINANTS,
    },
    "daylight_basis.npz": {
        "family": "CIE D-series daylight basis functions S0, S1, S2, 5 nm",
        "colour_object": (
            "colour.colorimetry.datasets.illuminants.SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES "
            "(colour/colorimetry/datasets/illuminants/sds_d_illuminant_series.py)"
        ),
        "primary_source": (
            "CIE 15:2004 table T.2 (components of the relative SPD of daylight); "
            "http://www.brucelindbloom.com/Eqn_DIlluminant.html"
        ),
        "tables": D_SERIES,
    },
}


def colour_tables() -> dict[str, dict[str, np.ndarray]]:
    """The tables as colour-science ships them: {file: {key: float64 array}}."""
    import colour
    from colour.colorimetry.datasets.illuminants import SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES

    out: dict[str, dict[str, np.ndarray]] = {f: {} for f in FILES}
    for name, key in XYZ_CMFS.items():
        m = colour.MSDS_CMFS[name]
        out["cmfs_xyz.npz"][f"{key}_wavelengths"] = np.asarray(m.wavelengths, np.float64)
        out["cmfs_xyz.npz"][f"{key}_values"] = np.asarray(m.values, np.float64)
    for name, key in RGB_CMFS.items():
        m = colour.colorimetry.MSDS_CMFS_RGB[name]
        out["cmfs_rgb.npz"][f"{key}_wavelengths"] = np.asarray(m.wavelengths, np.float64)
        out["cmfs_rgb.npz"][f"{key}_values"] = np.asarray(m.values, np.float64)
    for name in ILLUMINANTS:
        s = colour.SDS_ILLUMINANTS[name]
        out["illuminants.npz"][f"{name}_wavelengths"] = np.asarray(s.wavelengths, np.float64)
        out["illuminants.npz"][f"{name}_values"] = np.asarray(s.values, np.float64)
    for name in D_SERIES:
        s = SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES[name]
        out["daylight_basis.npz"][f"{name}_wavelengths"] = np.asarray(s.wavelengths, np.float64)
        out["daylight_basis.npz"][f"{name}_values"] = np.asarray(s.values, np.float64)
    return out


def sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def build_data(out_dir: Path | str = DATA_DIR) -> dict:
    """Write the `.npz` tables and `provenance.json` into `out_dir`; return the provenance dict."""
    import colour

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    tables = colour_tables()
    provenance = {
        "description": "CIE tables packaged with radiometria.colorimetry (float64 .npz files).",
        "licence": _CIE_LICENCE,
        "extracted_with": f"colour-science {colour.__version__}",
        "retrieved": datetime.date.today().isoformat(),
        "files": {},
    }
    for fname, meta in FILES.items():
        write_npz_deterministic(out_dir / fname, tables[fname], mode=0o644)
        provenance["files"][fname] = {**meta, "sha256": sha256(out_dir / fname)}
    text = json.dumps(provenance, indent=2) + "\n"
    atomic_write_bytes(out_dir / "provenance.json", text.encode(), mode=0o644)
    return provenance


if __name__ == "__main__":  # pragma: no cover
    print(json.dumps(build_data(), indent=2))
