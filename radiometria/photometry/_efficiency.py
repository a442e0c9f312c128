"""CIE spectral luminous efficiency functions: photopic V(lambda) and scotopic V'(lambda).

Packaged data (`radiometria/photometry/data/`, provenance in `data/provenance.json`):

- `cie_1924_photopic.csv`: CIE 1924 photopic V(lambda), 360-830 nm at 1 nm (471 rows), peak 1
  at 555 nm; sha256 1a8d21ed30b39911804a8ca83a77507b86f8cf1e3ea376b85aadfcd689ee5e22;
- `cie_1951_scotopic.csv`: CIE 1951 scotopic V'(lambda), 380-780 nm at 1 nm (401 rows), peak
  1 at 507 nm; sha256 00edc3469a7205cc6436a41cd4e62a1b1cba48f98eb3248f033d1148c98657ab.

Both were written by `_write_tables` from colour-science 0.4.7
(`colour.colorimetry.SDS_LEFS_PHOTOPIC["CIE 1924 Photopic Standard Observer"]` and
`SDS_LEFS_SCOTOPIC["CIE 1951 Scotopic Standard Observer"]`, BSD-3-Clause), which takes them from
the CVRL database (http://www.cvrl.org/lumindex.htm) of the CIE standard tables (CIE 018:2019,
ISO 23539:2005/CIE S 010/E:2004). Values are stored with Python's shortest round-trip `repr`, so
they equal colour's float64 values bit for bit; the tests check this and the sha256 recorded in
`provenance.json`. Retrieved 2026-11-22.

The tables are loaded once at import as NumPy arrays (no device is touched) and become JAX
arrays inside the functions (style.md section 8).
"""

import hashlib
import json
from pathlib import Path

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .. import constants as _c
from .._checks import as_float_array, lookup
from .._math import interpolation_weights
from .._types import FloatLike

DATA_DIR = Path(__file__).resolve().parent / "data"
_FILES = {"photopic": "cie_1924_photopic.csv", "scotopic": "cie_1951_scotopic.csv"}
# colour-science names of the packaged tables (the source of `_write_tables`).
_COLOUR_NAMES = {
    "photopic": ("SDS_LEFS_PHOTOPIC", "CIE 1924 Photopic Standard Observer"),
    "scotopic": ("SDS_LEFS_SCOTOPIC", "CIE 1951 Scotopic Standard Observer"),
}
# Maximum luminous efficacy of each vision, K_m and K'_m (constants.py).
EFFICACY = {"photopic": _c.K_M, "scotopic": _c.K_M_SCOTOPIC}
VISIONS = tuple(_FILES)


def _read_table(path: Path) -> tuple[np.ndarray, np.ndarray]:
    data = np.loadtxt(path, delimiter=",", skiprows=1, dtype=np.float64)
    return data[:, 0], data[:, 1]


_TABLES: dict[str, tuple[np.ndarray, np.ndarray]] = {
    vision: _read_table(DATA_DIR / name) for vision, name in _FILES.items()
}


def _check_vision(vision: str) -> tuple[np.ndarray, np.ndarray]:
    return lookup(_TABLES, vision, "vision")


def luminous_efficiency_table(
    vision: str = "photopic",
) -> tuple[Float[Array, " n"], Float[Array, " n"]]:
    """The packaged CIE table of V(lambda) (photopic) or V'(lambda) (scotopic).

    **Arguments:**

    - `vision`: `"photopic"` (CIE 1924 V, 360-830 nm) or `"scotopic"` (CIE 1951 V', 380-780 nm).

    **Returns:**

    `(wavelengths_nm, values)`: the 1 nm grid [nm] and the efficiency on it, peak 1
    [dimensionless], as JAX arrays in the default float dtype.

    Provenance: colour-science 0.4.7 (BSD-3-Clause), from CVRL (http://www.cvrl.org/), retrieved
    2026-11-22; files `radiometria/photometry/data/cie_1924_photopic.csv` (sha256 1a8d21ed...)
    and `cie_1951_scotopic.csv` (sha256 00edc346...); full record in `data/provenance.json`.

    !!! note "Thesis"
        Thesis section 2.1 ($V_p(\\lambda)$ and $V_s(\\lambda)$).

    ??? cite "References"
        `CIE2019` (CIE 018:2019); `CVRL2014` (the tables, via colour-science).
    """
    wavelengths, values = _check_vision(vision)
    return jnp.asarray(wavelengths, dtype=float), jnp.asarray(values, dtype=float)


def _efficiency_on(wavelength_nm: Array, vision: str) -> Array:
    """V or V' at `wavelength_nm` (any shape, already a float array): linear, 0 outside."""
    grid_np, values_np = _check_vision(vision)
    grid = jnp.asarray(grid_np, dtype=wavelength_nm.dtype)
    table = jnp.asarray(values_np, dtype=wavelength_nm.dtype)
    i0, i1, t, outside = interpolation_weights(grid, wavelength_nm, "zero")
    return jnp.where(outside, 0.0, (1.0 - t) * table[i0] + t * table[i1])


def luminous_efficiency_function(
    wavelength_nm: FloatLike, *, vision: str = "photopic"
) -> Float[Array, "..."]:
    r"""Spectral luminous efficiency V(lambda) or V'(lambda) at arbitrary wavelengths.

    Linear interpolation of the packaged 1 nm CIE table (exact at whole nanometres), and 0
    outside the tabulated range (360-830 nm photopic, 380-780 nm scotopic), where the CIE
    functions are negligible. The spectral luminous efficacy is `K * V`, with `K` =
    `constants.K_M` (photopic) or `constants.K_M_SCOTOPIC` (scotopic).

    **Arguments:**

    - `wavelength_nm`: wavelengths in standard air (the CIE convention), any shape. [nm]
    - `vision`: `"photopic"` or `"scotopic"`.

    **Returns:**

    The efficiency, in [0, 1], with the shape of `wavelength_nm`. [dimensionless] NaN
    wavelengths give NaN.

    !!! note "Thesis"
        Thesis section 2.1 ($V_p(\lambda)$ and $V_s(\lambda)$).

    ??? cite "References"
        `CIE2019` (CIE 018:2019); `CVRL2014`.
    """
    _check_vision(vision)
    return _efficiency_on(as_float_array(wavelength_nm, "wavelength_nm"), vision)


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _write_tables(directory: Path | str = DATA_DIR, *, retrieved: str) -> dict:
    """Regenerate the packaged CSV tables and `provenance.json` from colour-science (offline).

    Not called at import. Run as
    `python -c "from radiometria.photometry._efficiency import _write_tables as w;
    w(retrieved='YYYY-MM-DD')"`; the tests then check the files against colour-science.
    """
    import colour
    import colour.colorimetry as colorimetry

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    provenance = {}
    for vision, filename in _FILES.items():
        mapping, key = _COLOUR_NAMES[vision]
        sd = getattr(colorimetry, mapping)[key]
        lines = ["wavelength_nm,value"]
        lines += [
            f"{w!r},{v!r}" for w, v in zip(sd.wavelengths.tolist(), sd.values.tolist(), strict=True)
        ]
        path = directory / filename
        tmp = path.with_suffix(".tmp")
        tmp.write_text("\n".join(lines) + "\n")
        tmp.replace(path)
        provenance[filename] = {
            "name": key,
            "vision": vision,
            "source": f"colour-science {colour.__version__}: colour.colorimetry.{mapping}[{key!r}]",
            "original_source": "CVRL, Colour & Vision Research Laboratory, UCL "
            "(http://www.cvrl.org/lumindex.htm): the CIE standard table "
            "(CIE 018:2019; ISO 23539:2005/CIE S 010/E:2004)",
            "url": "https://github.com/colour-science/colour/blob/develop/colour/colorimetry/datasets/lefs.py",
            "licence": "colour-science: BSD-3-Clause. The CIE tables are published standard "
            "reference data, reproduced here as numbers.",
            "retrieved": retrieved,
            "wavelength_range_nm": [sd.wavelengths[0].item(), sd.wavelengths[-1].item()],
            "interval_nm": 1.0,
            "rows": len(sd.wavelengths),
            "sha256": _sha256(path),
        }
    path = directory / "provenance.json"
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(provenance, indent=2) + "\n")
    tmp.replace(path)
    return provenance
