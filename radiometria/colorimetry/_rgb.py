r"""RGB colour spaces built from primaries and a white point, and their transfer functions.

The RGB -> XYZ matrix of every space is *derived* (SMPTE RP 177): with the primaries'
XYZ columns $P = [X_r\,X_g\,X_b]$ at Y = 1 and the white $W$ (Y = 1),
$S = P^{-1} W$ and $M_{RGB\to XYZ} = P\,\mathrm{diag}(S)$, so RGB = (1, 1, 1) maps to the white
with Y = 1. Published rounded matrices (the IEC sRGB one printed in thesis 2.2.2 to 4 decimals,
ROMM's) agree with the derived ones to their printed precision.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_choice, check_last_axis
from ._adaptation import _cat_matrix

# --- Transfer functions (cctf = colour component transfer function) ------------------------


def _spow(x: Array, p: float) -> Array:
    """Sign-preserving power sign(x)|x|^p with a zero gradient at 0 (avoids inf * 0 = NaN)."""
    nz = x != 0
    a = jnp.abs(jnp.where(nz, x, 1.0))
    return jnp.where(nz, jnp.sign(x) * a**p, 0.0)


def srgb_eotf_inverse(L: ArrayLike) -> Array:
    r"""sRGB encoding (inverse EOTF, IEC 61966-2-1): linear -> gamma-encoded.

    $V = 12.92\,L$ for $L \le 0.0031308$, else $1.055\,L^{1/2.4} - 0.055$. Negative values take
    the linear segment (as colour-science). [dimensionless, [0, 1] for in-gamut colours]

    !!! note "Thesis"
        Section 2.2.2 (inverse of the printed gamma expansion).

    ??? cite "References"
        `IEC1999` (IEC 61966-2-1).
    """
    L = as_float_array(L, "L")
    big = L > 0.0031308
    return jnp.where(big, 1.055 * jnp.where(big, L, 1.0) ** (1.0 / 2.4) - 0.055, 12.92 * L)


def srgb_eotf(V: ArrayLike) -> Array:
    r"""sRGB decoding (EOTF / gamma expansion): gamma-encoded -> linear.

    $L = V/12.92$ for $V \le 0.04045$, else $((V + 0.055)/1.055)^{2.4}$ (thesis section 2.2.2).

    !!! note "Thesis"
        Section 2.2.2, "gamma expansion".

    ??? cite "References"
        `IEC1999` (IEC 61966-2-1).

    Arguments: `V` encoded value [dimensionless]. Returns L [dimensionless, linear].
    """
    V = as_float_array(V, "V")
    big = V > 0.04045
    return jnp.where(big, ((jnp.where(big, V, 1.0) + 0.055) / 1.055) ** 2.4, V / 12.92)


def bt709_oetf(L: ArrayLike) -> Array:
    r"""ITU-R BT.709 / BT.2020 (10-bit) OETF: $V = 4.5 L$ for $L < 0.018$, else
    $1.099 L^{0.45} - 0.099$.

    ??? cite "References"
        `ITU2015a` (BT.709-6), `ITU2015b` (BT.2020-2).

    Arguments: `L` scene-linear value [dimensionless]. Returns the signal V [dimensionless].
    """
    L = as_float_array(L, "L")
    big = L >= 0.018
    return jnp.where(big, 1.099 * jnp.where(big, L, 1.0) ** 0.45 - 0.099, 4.5 * L)


def bt709_oetf_inverse(V: ArrayLike) -> Array:
    """Inverse of `bt709_oetf`: L = V/4.5 below V(0.018) = 0.0812, else
    ((V + 0.099)/1.099)^(1/0.45).

    The threshold is the power segment at L = 0.018 (the two segments of the rounded BT.709
    constants differ by 2e-4 there), as in colour-science.

    Arguments: `V` signal [dimensionless]. Returns L [dimensionless].

    ??? cite "References"
        `ITU2015a`, `ITU2015b`.
    """
    V = as_float_array(V, "V")
    big = V >= 1.099 * 0.018**0.45 - 0.099
    return jnp.where(big, ((jnp.where(big, V, 1.0) + 0.099) / 1.099) ** (1.0 / 0.45), V / 4.5)


def gamma_encoding(L: ArrayLike, gamma: float) -> Array:
    """Pure power-law encoding V = sign(L)|L|^(1/gamma) (mirrored for negative values).

    Arguments: `L` linear value [dimensionless]; `gamma` exponent [dimensionless].

    ??? cite "References"
        Thesis section 2.2.2 (v_in = A v_out^gamma); `IEC1999`.
    """
    return _spow(as_float_array(L, "L"), 1.0 / gamma)


def gamma_decoding(V: ArrayLike, gamma: float) -> Array:
    """Pure power-law decoding L = sign(V)|V|^gamma (mirrored for negative values).

    Arguments: `V` encoded value [dimensionless]; `gamma` exponent [dimensionless].

    ??? cite "References"
        `IEC1999` (the pure-power approximation it replaces); thesis section 2.2.2.
    """
    return _spow(as_float_array(V, "V"), gamma)


def romm_encoding(L: ArrayLike) -> Array:
    """ProPhoto (ROMM RGB) encoding: 16 L below 1/512, else L^(1/1.8). `ANSI2005`/ISO 22028-2.

    Arguments: `L` [dimensionless]. Returns V [dimensionless].
    """
    L = as_float_array(L, "L")
    big = L >= 1.0 / 512.0
    return jnp.where(big, jnp.where(big, L, 1.0) ** (1.0 / 1.8), 16.0 * L)


def romm_decoding(V: ArrayLike) -> Array:
    """ProPhoto (ROMM RGB) decoding: V/16 below 1/32, else V^1.8.

    Arguments: `V` [dimensionless]. Returns L [dimensionless].

    ??? cite "References"
        `ANSI2005`.
    """
    V = as_float_array(V, "V")
    big = V >= 16.0 / 512.0
    return jnp.where(big, jnp.where(big, V, 1.0) ** 1.8, V / 16.0)


# Adobe RGB (1998) gamma: 563/256 = 2.19921875 (Adobe RGB (1998) specification, section 4.3.4.2).
_ADOBE_GAMMA = 563.0 / 256.0

_CCTFS = {
    "sRGB": (srgb_eotf_inverse, srgb_eotf),
    "BT.709": (bt709_oetf, bt709_oetf_inverse),
    "Adobe RGB (1998)": (
        lambda x: gamma_encoding(x, _ADOBE_GAMMA),
        lambda x: gamma_decoding(x, _ADOBE_GAMMA),
    ),
    "gamma 2.2": (lambda x: gamma_encoding(x, 2.2), lambda x: gamma_decoding(x, 2.2)),
    "ROMM": (romm_encoding, romm_decoding),
    "linear": (lambda x: as_float_array(x, "x"), lambda x: as_float_array(x, "x")),
}


# --- Matrices -------------------------------------------------------------------------------


def normalised_primary_matrix(primaries, whitepoint):
    """RGB -> XYZ matrix from primaries (3, 2) xy and white point (2,) xy, white Y = 1.

    NumPy in, NumPy out (float64) when both inputs are NumPy/Python values; JAX otherwise, so
    the matrix can be differentiated with respect to the chromaticities.

    ??? cite "References"
        `SMPTE1993` (SMPTE RP 177-1993).

    Arguments: `primaries` (3, 2), `whitepoint` (2,) xy [dimensionless]. Returns (3, 3)
    [dimensionless].
    """
    use_np = not any(isinstance(a, jnp.ndarray) for a in (primaries, whitepoint))
    xp = np if use_np else jnp
    p = xp.asarray(primaries, dtype=float) if use_np else as_float_array(primaries, "primaries")
    w = xp.asarray(whitepoint, dtype=float) if use_np else as_float_array(whitepoint, "whitepoint")
    if p.shape != (3, 2) or w.shape != (2,):
        raise ValueError(
            f"`primaries` must be (3, 2) and `whitepoint` (2,) xy, got {p.shape} and {w.shape}."
        )
    x, y = p[:, 0], p[:, 1]
    P = xp.stack([x / y, xp.ones_like(y), (1.0 - x - y) / y], axis=0)  # columns: primaries XYZ
    W = xp.stack([w[0] / w[1], xp.ones_like(w[0]), (1.0 - w[0] - w[1]) / w[1]])
    S = xp.linalg.solve(P, W)
    return P * S[None, :]


class RGBColourspace(eqx.Module):
    """An additive RGB colour space: primaries, white point and transfer function.

    Built with `RGBColourspace(name, primaries, whitepoint, whitepoint_name, cctf)`; the
    matrices are derived (module docstring), never typed in.

    - `name`: canonical name (static).
    - `primaries`: (3, 2) xy chromaticities of R, G, B. [dimensionless]
    - `whitepoint`: (2,) xy of the white. [dimensionless]
    - `whitepoint_name`: e.g. "D65" (static).
    - `cctf`: transfer-function name (static): "sRGB", "BT.709", "Adobe RGB (1998)",
        "gamma 2.2", "ROMM" or "linear".
    - `matrix_RGB_to_XYZ`, `matrix_XYZ_to_RGB`: (3, 3), white Y = 1.

    ??? cite "References"
        `SMPTE1993` (derivation); thesis section 2.2.2 (sRGB, table 2.2).
    """

    name: str = eqx.field(static=True)
    primaries: Float[ArrayLike, "3 2"]
    whitepoint: Float[ArrayLike, " 2"]
    whitepoint_name: str = eqx.field(static=True)
    cctf: str = eqx.field(static=True)
    matrix_RGB_to_XYZ: Float[ArrayLike, "3 3"]
    matrix_XYZ_to_RGB: Float[ArrayLike, "3 3"]

    def __init__(self, name, primaries, whitepoint, whitepoint_name, cctf="linear"):
        check_choice(cctf, "cctf", _CCTFS)
        self.name = name
        self.whitepoint_name = whitepoint_name
        self.cctf = cctf
        M = normalised_primary_matrix(primaries, whitepoint)
        if isinstance(M, np.ndarray):
            self.primaries = np.asarray(primaries, dtype=float)
            self.whitepoint = np.asarray(whitepoint, dtype=float)
            self.matrix_RGB_to_XYZ = M
            self.matrix_XYZ_to_RGB = np.linalg.inv(M)
        else:
            self.primaries = as_float_array(primaries, "primaries")
            self.whitepoint = as_float_array(whitepoint, "whitepoint")
            self.matrix_RGB_to_XYZ = M
            self.matrix_XYZ_to_RGB = jnp.linalg.inv(M)

    @property
    def whitepoint_XYZ(self):
        """White point XYZ with Y = 1 (NumPy for the built-in spaces)."""
        x, y = self.whitepoint[0], self.whitepoint[1]
        xp = np if isinstance(self.whitepoint, np.ndarray) else jnp
        return xp.stack([x / y, xp.ones_like(y), (1.0 - x - y) / y])

    def cctf_encoding(self, x: ArrayLike) -> Array:
        """Linear -> encoded (non-linear) component values with this space's transfer function."""
        return _CCTFS[self.cctf][0](x)

    def cctf_decoding(self, x: ArrayLike) -> Array:
        """Encoded -> linear component values with this space's transfer function."""
        return _CCTFS[self.cctf][1](x)


# --- The built-in spaces ----------------------------------------------------------------------
# White points, CIE 1931 2 deg xy: D65 and D50 as printed in CIE 15 and the space specs
# (thesis table 2.1); the ACES white (~D60) from SMPTE ST 2065-1.
_D65 = (0.3127, 0.3290)
_D50 = (0.3457, 0.3585)
_ACES_WHITE = (0.32168, 0.33767)


class _ColourspaceDict(dict):
    """A dict of the canonical spaces whose lookups also accept the aliases
    (`RGB_COLOURSPACES["Rec.2020"]`); iteration lists canonical names only."""

    def __missing__(self, key):
        if key in COLOURSPACE_ALIASES:
            return self[COLOURSPACE_ALIASES[key]]
        raise KeyError(
            f"Unknown colourspace {key!r}; valid values are: {', '.join(map(repr, self))} "
            f"(aliases: {', '.join(map(repr, COLOURSPACE_ALIASES))})."
        )

    def __contains__(self, key):
        return dict.__contains__(self, key) or key in COLOURSPACE_ALIASES

    def get(self, key, default=None):
        return self[key] if key in self else default


RGB_COLOURSPACES: dict[str, RGBColourspace] = _ColourspaceDict(
    {
        # IEC 61966-2-1 / ITU-R BT.709 primaries (thesis table 2.2).
        "sRGB": RGBColourspace(
            "sRGB", [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]], _D65, "D65", "sRGB"
        ),
        # Apple Display P3: DCI-P3 primaries, D65, sRGB transfer function.
        "Display P3": RGBColourspace(
            "Display P3", [[0.680, 0.320], [0.265, 0.690], [0.150, 0.060]], _D65, "D65", "sRGB"
        ),
        # ITU-R BT.2020-2.
        "ITU-R BT.2020": RGBColourspace(
            "ITU-R BT.2020", [[0.708, 0.292], [0.170, 0.797], [0.131, 0.046]], _D65, "D65", "BT.709"
        ),
        # SMPTE ST 2065-1 (AP0).
        "ACES2065-1": RGBColourspace(
            "ACES2065-1",
            [[0.73470, 0.26530], [0.00000, 1.00000], [0.00010, -0.07700]],
            _ACES_WHITE,
            "ACES",
            "linear",
        ),
        # Academy S-2014-004 (AP1).
        "ACEScg": RGBColourspace(
            "ACEScg",
            [[0.713, 0.293], [0.165, 0.830], [0.128, 0.044]],
            _ACES_WHITE,
            "ACES",
            "linear",
        ),
        # ANSI/I3A IT10.7666 / ISO 22028-2 (ROMM RGB).
        "ProPhoto RGB": RGBColourspace(
            "ProPhoto RGB",
            [[0.7347, 0.2653], [0.1596, 0.8404], [0.0366, 0.0001]],
            _D50,
            "D50",
            "ROMM",
        ),
        # Adobe RGB (1998) specification.
        "Adobe RGB (1998)": RGBColourspace(
            "Adobe RGB (1998)",
            [[0.64, 0.33], [0.21, 0.71], [0.15, 0.06]],
            _D65,
            "D65",
            "Adobe RGB (1998)",
        ),
    }
)

COLOURSPACE_ALIASES: dict[str, str] = {
    "Rec.2020": "ITU-R BT.2020",
    "BT.2020": "ITU-R BT.2020",
    "Rec. 2020": "ITU-R BT.2020",
    "P3-D65": "Display P3",
    "ACES": "ACES2065-1",
    "ProPhoto": "ProPhoto RGB",
    "ROMM RGB": "ProPhoto RGB",
    "Adobe RGB": "Adobe RGB (1998)",
    "Adobe 1998": "Adobe RGB (1998)",
}


def get_colourspace(colourspace) -> RGBColourspace:
    """The `RGBColourspace` for a name or alias (an `RGBColourspace` passes through).

    Names: "sRGB", "Display P3", "ITU-R BT.2020", "ACES2065-1", "ACEScg", "ProPhoto RGB",
    "Adobe RGB (1998)"; aliases "Rec.2020", "BT.2020", "P3-D65", "ACES", "ProPhoto",
    "ROMM RGB", "Adobe RGB". An unknown name raises `ValueError` listing the valid ones.

    Arguments: `colourspace` name [str] or `RGBColourspace`.

    ??? cite "References"
        `IEC1999`, `ITU2015b`, `SMPTE1993`, `ANSI2005`.
    """
    if isinstance(colourspace, RGBColourspace):
        return colourspace
    if not isinstance(colourspace, str):
        raise TypeError(
            f"`colourspace` must be a name or an RGBColourspace, got {type(colourspace).__name__}."
        )
    name = COLOURSPACE_ALIASES.get(colourspace, colourspace)
    if name not in RGB_COLOURSPACES:
        raise ValueError(
            f"Unknown colourspace {colourspace!r}; valid values are: "
            f"{', '.join(map(repr, RGB_COLOURSPACES))} "
            f"(aliases: {', '.join(map(repr, COLOURSPACE_ALIASES))})."
        )
    return RGB_COLOURSPACES[name]


# --- Conversions ------------------------------------------------------------------------------


def _apply(M, v: Array) -> Array:
    M = jnp.asarray(M, dtype=v.dtype) if isinstance(M, np.ndarray) else M.astype(v.dtype)
    return v @ M.T


def _adaptation_matrix(white_from, white_to, method) -> np.ndarray | Array:
    """von Kries matrix between two Y = 1 whites (NumPy when both are NumPy)."""
    M = _cat_matrix(method)
    if isinstance(white_from, np.ndarray) and isinstance(white_to, np.ndarray):
        gain = (M @ white_to) / (M @ white_from)
        return np.linalg.inv(M) @ (gain[:, None] * M)
    Mj = jnp.asarray(M)
    gain = (Mj @ jnp.asarray(white_to)) / (Mj @ jnp.asarray(white_from))
    return jnp.asarray(np.linalg.inv(M)) @ (gain[:, None] * Mj)


def RGB_to_XYZ(
    RGB: Float[ArrayLike, "*batch 3"],
    colourspace,
    illuminant_XYZ=None,
    chromatic_adaptation_transform: str | None = "CAT02",
    *,
    apply_cctf_decoding: bool = False,
) -> Float[Array, "*batch 3"]:
    """Linear RGB of `colourspace` -> CIE XYZ (white Y = 1).

    **Arguments:**

    - `RGB`: (..., 3) linear values (or encoded values with `apply_cctf_decoding=True`).
    - `colourspace`: name, alias or `RGBColourspace`.
    - `illuminant_XYZ`: white (3,) of the output XYZ; `None` (default) keeps the space's own
        white. When given, the result is adapted from the space's white to it with
        `chromatic_adaptation_transform` ("CAT02", "CAT16", "Bradford", "Von Kries",
        "XYZ Scaling"; `None` skips adaptation).

    **Returns:** XYZ (..., 3). [dimensionless, Y = 1 for RGB = (1, 1, 1)]

    ??? cite "References"
        `SMPTE1993`; `Fairchild2013` chapter 9.
    """
    cs = get_colourspace(colourspace)
    RGB = check_last_axis(as_float_array(RGB, "RGB"), "RGB", 3)
    if apply_cctf_decoding:
        RGB = cs.cctf_decoding(RGB)
    M = cs.matrix_RGB_to_XYZ
    if illuminant_XYZ is not None and chromatic_adaptation_transform is not None:
        wr = check_last_axis(as_float_array(illuminant_XYZ, "illuminant_XYZ"), "illuminant_XYZ", 3)
        M = _adaptation_matrix(cs.whitepoint_XYZ, wr, chromatic_adaptation_transform) @ M
    return _apply(M, RGB)


def XYZ_to_RGB(
    XYZ: Float[ArrayLike, "*batch 3"],
    colourspace,
    illuminant_XYZ=None,
    chromatic_adaptation_transform: str | None = "CAT02",
    *,
    apply_cctf_encoding: bool = False,
) -> Float[Array, "*batch 3"]:
    """CIE XYZ -> linear RGB of `colourspace` (no clipping: out-of-gamut values pass through).

    **Arguments:**

    - `XYZ`: (..., 3), white Y = 1.
    - `colourspace`: name, alias or `RGBColourspace`.
    - `illuminant_XYZ`: white (3,) of the input XYZ; `None` (default) means the space's own
        white. When given, XYZ is first adapted from it to the space's white.
    - `chromatic_adaptation_transform`: see `RGB_to_XYZ`.
    - `apply_cctf_encoding`: apply the space's transfer function to the result.

    ??? cite "References"
        `SMPTE1993`; `Fairchild2013` chapter 9.

    Returns RGB (..., 3) [dimensionless, linear unless `apply_cctf_encoding`].
    """
    cs = get_colourspace(colourspace)
    XYZ = check_last_axis(as_float_array(XYZ, "XYZ"), "XYZ", 3)
    M = cs.matrix_XYZ_to_RGB
    if illuminant_XYZ is not None and chromatic_adaptation_transform is not None:
        w = check_last_axis(as_float_array(illuminant_XYZ, "illuminant_XYZ"), "illuminant_XYZ", 3)
        M = M @ _adaptation_matrix(w, cs.whitepoint_XYZ, chromatic_adaptation_transform)
    RGB = _apply(M, XYZ)
    return cs.cctf_encoding(RGB) if apply_cctf_encoding else RGB


def matrix_RGB_to_RGB(
    input_colourspace, output_colourspace, chromatic_adaptation_transform: str | None = "CAT02"
):
    """The 3x3 matrix of `RGB_to_RGB` (linear), adapting between the two whites.

    Returns the (3, 3) matrix [dimensionless].

    ??? cite "References"
        `SMPTE1993`; `Fairchild2013` chapter 9.
    """
    a = get_colourspace(input_colourspace)
    b = get_colourspace(output_colourspace)
    M = a.matrix_RGB_to_XYZ
    if chromatic_adaptation_transform is not None:
        M = (
            _adaptation_matrix(a.whitepoint_XYZ, b.whitepoint_XYZ, chromatic_adaptation_transform)
            @ M
        )
    return b.matrix_XYZ_to_RGB @ M


def RGB_to_RGB(
    RGB: Float[ArrayLike, "*batch 3"],
    input_colourspace,
    output_colourspace,
    chromatic_adaptation_transform: str | None = "CAT02",
    *,
    apply_cctf_decoding: bool = False,
    apply_cctf_encoding: bool = False,
) -> Float[Array, "*batch 3"]:
    """Convert RGB between two colour spaces through XYZ, adapting white to white.

    **Arguments:**

    - `RGB`: (..., 3) linear values of `input_colourspace` (encoded with
        `apply_cctf_decoding=True`).
    - `input_colourspace`, `output_colourspace`: names, aliases or `RGBColourspace`s.
    - `chromatic_adaptation_transform`: "CAT02" (default), "CAT16", "Bradford", "Von Kries",
        "XYZ Scaling", or `None` for no adaptation (same as colour-science).
    - `apply_cctf_encoding`: encode the result with the output space's transfer function.

    ??? cite "References"
        `SMPTE1993`; `Fairchild2013` chapter 9.

    Returns RGB (..., 3) of the output space [dimensionless, linear unless encoded].
    """
    a = get_colourspace(input_colourspace)
    b = get_colourspace(output_colourspace)
    RGB = check_last_axis(as_float_array(RGB, "RGB"), "RGB", 3)
    if apply_cctf_decoding:
        RGB = a.cctf_decoding(RGB)
    out = _apply(matrix_RGB_to_RGB(a, b, chromatic_adaptation_transform), RGB)
    return b.cctf_encoding(out) if apply_cctf_encoding else out


def sRGB_to_XYZ(rgb: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 3"]:
    """Gamma-encoded sRGB in [0, 1] -> CIE XYZ (D65 white with Y = 1).

    Gamma expansion (IEC 61966-2-1 piecewise EOTF), then the derived sRGB matrix, which equals
    the matrix printed in thesis 2.2.2 to its 4 decimals.

    !!! note "Thesis"
        Section 2.2.2 (gamma expansion and linear transformation).

    ??? cite "References"
        `IEC1999`.
    """
    return RGB_to_XYZ(rgb, "sRGB", apply_cctf_decoding=True)


def XYZ_to_sRGB(XYZ: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 3"]:
    """CIE XYZ (D65 white, Y = 1) -> gamma-encoded sRGB, the inverse of `sRGB_to_XYZ`.

    No clipping: out-of-gamut colours give components outside [0, 1] (clip them for display).

    !!! note "Thesis"
        Section 2.2.2.

    ??? cite "References"
        `IEC1999`.
    """
    return XYZ_to_RGB(XYZ, "sRGB", apply_cctf_encoding=True)
