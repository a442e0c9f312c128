r"""Spectral indices of refraction: dispersion formulas and tabulated metals.

Dielectrics (real index $n(\lambda)$, Sellmeier formula):

| name | formula, source | valid range |
|---|---|---|
| `"BK7"` (alias `"N-BK7"`) | Sellmeier, SCHOTT N-BK7 datasheet (`Schott2017`) | 300-2500 nm |
| `"fused silica"` (alias `"SiO2"`) | Sellmeier, `Malitson1965` | 210-6700 nm |
| `"water"` (alias `"H2O"`) | Sellmeier fit at 20.0 °C, `Daimon2007` | 182-1129 nm |

Conductors (complex index $\eta + i k$ relative to vacuum, linear interpolation in wavelength):
`"Au"`, `"Ag"`, `"Cu"`, `"Al"`, 298.8-885.6 nm (Cu: 302.4-885.6 nm); outside the table the
end values are held (constant extrapolation).

**Provenance of the metal tables.** The files in `radiometria/scattering/data/ior/` are copied
byte for byte from the Mitsuba 3 Python package, version 3.9.1
(`mitsuba/data/ior/<metal>.<eta|k>.spd`, the tables behind Mitsuba's `conductor` presets).
Each file's header says "data from www.luxpop.com database" and names the metal; it states no
further source and no licence of its own. The luxpop.com database compiled its metal constants
from the *Handbook of Optical Constants of Solids* (`Palik1985`); Mitsuba's `*_palik` variants
of other materials say so explicitly, these four do not. The same tables ship with pbrt-v3/v4
(`Pharr2023`). The Mitsuba 3 package is distributed under the BSD 3-Clause licence
(Copyright (c) 2017 Wenzel Jakob), reproduced in `data/ior/LICENSE-mitsuba3.txt`; measured
optical constants are facts, so the practical constraint is attribution, which this docstring and
that file provide. Retrieved 2025 from the installed wheel (no network access). The first
column of the files is the vacuum wavelength in nm (the header's "Lambda (A)" is a leftover of the
original format; the values, e.g. 298.76 ... 885.60, are nanometres). SHA-256 of the files:

| file | sha256 |
|---|---|
| Ag.eta.spd | 4e361cd5b7bc611dd4a04284756297cf6830c5825a7543f95bde0cc8a6681e09 |
| Ag.k.spd | 0de4559c0ee5e5f8f3a4d97d2f880d6779277f3e066fa3bbf2d9cc04686e43cb |
| Al.eta.spd | f7d36d501088920e085f904b59519fa30d337378a07dee1cc86af16c6730c36a |
| Al.k.spd | 8c7f764c37c6cc5fac9a75af478e5b887d4ab752ea4b0046f62cbaee986b5b1c |
| Au.eta.spd | d7d14a948e14a4479f1590b88e12736b792d8faa875479b32a186d3ffd7c9d0a |
| Au.k.spd | e3f40e936b0c7aeb0aa6e31ec834397576707ae07a34cc5dce582fb0177b36d2 |
| Cu.eta.spd | a746c36fa81bf9aa99521315f66a0c181278e0d901a1a18a3dd5842473b1aedf |
| Cu.k.spd | a315398fd87806474aa52f3693ad38c2820ef591dbe6ef59ffa60be61480587e |

(refractiveindex.info's CC0 database holds the same kind of data; it was not reachable here.)
"""

from importlib import resources

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax import Array

from .._checks import as_float_array, check_broadcastable, check_choice, check_positive, lookup
from .._math import align_ranks, interp_columns

__all__ = [
    "CONDUCTORS",
    "DIELECTRICS",
    "TabulatedIOR",
    "conductor_ior",
    "dielectric_ior",
    "get_conductor",
    "relative_complex_ior",
    "sellmeier",
]


def sellmeier(wavelength_nm, B, C) -> Array:
    r"""Sellmeier dispersion formula.

    $$n^2(\lambda) = 1 + \sum_j \frac{B_j\lambda^2}{\lambda^2 - C_j}$$

    with $\lambda$ in micrometres inside the formula.

    **Arguments:**

    - `wavelength_nm`: vacuum wavelength, > 0, any shape. [nm]
    - `B`: the dimensionless coefficients $B_j$, a sequence. [dimensionless]
    - `C`: the resonance terms $C_j$, same length. [um^2]

    **Returns:**

    The refractive index $n(\lambda)$, shape of `wavelength_nm`. [dimensionless]

    ??? cite "References"
        `Sellmeier1871`; `Malitson1965`.
    """
    lam = check_positive(as_float_array(wavelength_nm, "wavelength_nm"), "wavelength_nm", "nm")
    B = [float(b) for b in B]
    C = [float(c) for c in C]
    if len(B) != len(C) or not B:
        raise ValueError(
            f"`B` and `C` must be non-empty and of equal length, got {len(B)}, {len(C)}."
        )
    # nm -> um (the Sellmeier coefficients C_j are in um^2)
    l2 = (lam * 1e-3) ** 2
    n2 = 1.0
    for b, c in zip(B, C, strict=True):
        n2 = n2 + b * l2 / (l2 - c)
    return jnp.sqrt(n2)


# Coefficients (B_j; C_j in um^2).
_SELLMEIER = {
    # SCHOTT N-BK7 datasheet (2017); n_d(587.56 nm) = 1.5168.
    "BK7": (
        (1.03961212, 0.231792344, 1.01046945),
        (0.00600069867, 0.0200179144, 103.560653),
    ),
    # Malitson (1965), fused silica at 20 °C; n_d = 1.4585.
    "fused silica": (
        (0.6961663, 0.4079426, 0.8974794),
        (0.0684043**2, 0.1162414**2, 9.896161**2),
    ),
    # Daimon & Masumura (2007), HPLC distilled water at 20.0 °C (4-term fit);
    # n(589.3 nm) = 1.3333.
    "water": (
        (5.684027565e-1, 1.726177391e-1, 2.086189578e-2, 1.130748688e-1),
        (5.101829712e-3, 1.821153936e-2, 2.620722293e-2, 1.069792721e1),
    ),
}
_DIELECTRIC_ALIASES = {"N-BK7": "BK7", "SiO2": "fused silica", "H2O": "water"}
DIELECTRICS: tuple[str, ...] = tuple(_SELLMEIER) + tuple(_DIELECTRIC_ALIASES)


def dielectric_ior(name: str, wavelength_nm) -> Array:
    """Real refractive index of a named dielectric from its dispersion formula.

    **Arguments:**

    - `name`: `"BK7"` (`"N-BK7"`), `"fused silica"` (`"SiO2"`) or `"water"` (`"H2O"`); see
        the module docstring for sources and valid ranges.
    - `wavelength_nm`: vacuum wavelength, > 0. [nm]

    **Returns:**

    $n(\\lambda)$, shape of `wavelength_nm`. [dimensionless] Divide by the index of the outside
    medium to get the relative `eta` of a `DielectricBxDF`.

    !!! note "Thesis"
        Dispersion, footnote 8 of section 3.1.1.
    """
    check_choice(name, "dielectric", DIELECTRICS)
    B, C = _SELLMEIER[_DIELECTRIC_ALIASES.get(name, name)]
    return sellmeier(wavelength_nm, B, C)


# --------------------------------------------------------------------------------------------
# Tabulated conductors


def _read_spd(name: str) -> tuple[np.ndarray, np.ndarray]:
    text = resources.files(__package__).joinpath("data", "ior", name).read_text()
    rows = []
    for lineno, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        parts = line.split()
        if len(parts) != 2:
            raise ValueError(f"data/ior/{name}, line {lineno}: expected 2 columns, got {line!r}.")
        rows.append((float(parts[0]), float(parts[1])))
    arr = np.asarray(rows, dtype=np.float64)
    if arr.shape[0] < 2 or np.any(np.diff(arr[:, 0]) <= 0):
        raise ValueError(f"data/ior/{name}: wavelengths must increase strictly.")
    return arr[:, 0], arr[:, 1]


CONDUCTORS: tuple[str, ...] = ("Ag", "Al", "Au", "Cu")
# Loaded at import as NumPy arrays (style.md section 8): {name: (wl_eta, eta, wl_k, k)}.
_TABLES = {m: (*_read_spd(f"{m}.eta.spd"), *_read_spd(f"{m}.k.spd")) for m in CONDUCTORS}


class TabulatedIOR(eqx.Module):
    """A tabulated complex index of refraction $\\eta(\\lambda) + i k(\\lambda)$ (`Palik1985`).

    Calling it interpolates linearly in wavelength and holds the end values outside the table.

    **Fields:**

    - `name`: the material (static).
    - `wavelengths_eta_nm`, `eta`: the table of the real part. [nm], [dimensionless]
    - `wavelengths_k_nm`, `k`: the table of the extinction coefficient. [nm], [dimensionless]
    """

    name: str = eqx.field(static=True)
    wavelengths_eta_nm: Array
    eta: Array
    wavelengths_k_nm: Array
    k: Array

    def __call__(self, wavelength_nm) -> tuple[Array, Array]:
        """`(eta, k)` at `wavelength_nm` (any shape, > 0 [nm]), each of that shape."""
        lam = as_float_array(wavelength_nm, "wavelength_nm")
        lam = check_positive(lam, "wavelength_nm", "nm")
        dt = lam.dtype
        eta = interp_columns(lam, self.wavelengths_eta_nm.astype(dt), self.eta.astype(dt))
        k = interp_columns(lam, self.wavelengths_k_nm.astype(dt), self.k.astype(dt))
        return eta, k


def get_conductor(name: str) -> TabulatedIOR:
    """The tabulated complex index of `"Au"`, `"Ag"`, `"Cu"` or `"Al"` (`Palik1985`).

    Returns a `TabulatedIOR` (wavelengths [nm], `eta`, `k` [dimensionless]); see the module
    docstring for provenance.
    """
    wl_e, e, wl_k, k = lookup(_TABLES, name, "conductor")
    return TabulatedIOR(name, jnp.asarray(wl_e), jnp.asarray(e), jnp.asarray(wl_k), jnp.asarray(k))


def conductor_ior(name: str, wavelength_nm) -> tuple[Array, Array]:
    """Complex index `(eta, k)` of a tabulated metal at `wavelength_nm`, relative to vacuum.

    **Arguments:**

    - `name`: `"Au"`, `"Ag"`, `"Cu"` or `"Al"`.
    - `wavelength_nm`: vacuum wavelength, > 0, any shape (e.g. 4 hero wavelengths). [nm]

    **Returns:**

    `(eta, k)`, each of the shape of `wavelength_nm`. [dimensionless] For a metal in a medium
    of index $n$, the relative index is $(\\eta + ik)/n$: divide both by $n$.

    !!! note "Thesis"
        Eq. (3.13)-(3.18) take these as $\\eta$, $\\kappa$ (footnote 18).
    """
    return get_conductor(name)(wavelength_nm)


def relative_complex_ior(eta_i, k_i, eta_t, k_t) -> tuple[Array, Array]:
    r"""Relative complex index of refraction $\eta + i\kappa$ of two absorbing media.

    $$\eta + i\kappa = \frac{\eta_t + i\kappa_t}{\eta_i + i\kappa_i},\qquad
      \eta = \frac{\eta_i\eta_t + \kappa_i\kappa_t}{\eta_i^2 + \kappa_i^2},\qquad
      \kappa = \frac{\eta_i\kappa_t - \eta_t\kappa_i}{\eta_i^2 + \kappa_i^2}$$

    The index of the transmitting side (t, e.g. a metal) relative to the incident side (i, e.g.
    a glass or an absorbing liquid), as the Fresnel equations (thesis eq. 3.13-3.18) take it:
    feed the result to `fresnel_conductor(cos_theta_i, eta, k)`. With vacuum on the incident
    side ($\eta_i = 1$, $\kappa_i = 0$) it returns $(\eta_t, \kappa_t)$ unchanged. The relative
    $\kappa$ is negative when the incident medium absorbs more, relative to its index, than the
    transmitting one ($\kappa_i/\eta_i > \kappa_t/\eta_t$); `fresnel_conductor` accepts only
    $\kappa \ge 0$.

    **Arguments:**

    - `eta_i`, `k_i`: refractive index (> 0) and extinction coefficient (>= 0) of the incident
        medium, e.g. `(..., n_lambda)`. [dimensionless]
    - `eta_t`, `k_t`: the same for the transmitting medium. [dimensionless]

    **Returns:**

    `(eta, k)`, broadcast over the inputs. [dimensionless]

    !!! note "Thesis"
        Footnote 18 and the definitions of $\eta$, $\kappa$ under eq. (3.17), section 3.1.1.

    ??? cite "References"
        `Born1999` section 14.2; `Pegoraro2016` section 6.2.
    """
    eta_i = check_positive(as_float_array(eta_i, "eta_i"), "eta_i", "dimensionless")
    eta_t = check_positive(as_float_array(eta_t, "eta_t"), "eta_t", "dimensionless")
    k_i = as_float_array(k_i, "k_i")
    k_t = as_float_array(k_t, "k_t")
    k_i = eqx.error_if(k_i, k_i < 0, "`k_i` (extinction coefficient) must be >= 0; got < 0.")
    k_t = eqx.error_if(k_t, k_t < 0, "`k_t` (extinction coefficient) must be >= 0; got < 0.")
    check_broadcastable(("eta_i", eta_i), ("k_i", k_i), ("eta_t", eta_t), ("k_t", k_t))
    eta_i, k_i, eta_t, k_t = align_ranks(eta_i, k_i, eta_t, k_t)
    # (eta_t + i k_t)(eta_i - i k_i) / |eta_i + i k_i|^2, in real arithmetic.
    inv = 1.0 / (eta_i * eta_i + k_i * k_i)
    return (eta_i * eta_t + k_i * k_t) * inv, (eta_i * k_t - eta_t * k_i) * inv
