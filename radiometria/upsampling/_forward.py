r"""The colorimetric forward model of the fit: reflectance spectrum -> XYZ -> CIELAB.

Everything the residual of thesis eq. 2.27 needs from `radiometria.colorimetry` is gathered
here once, as NumPy float64 arrays, so the fitter sees a small interface:

- `wavelengths_nm` (n,): the quadrature grid, 360-830 nm at 1 nm by default (471 samples);
- `weights_XYZ` (n, 3): $W_{ik}$ with $XYZ_k = \sum_i S(\lambda_i) W_{ik}$ for a reflectance
  $S$ under the colour space's illuminant (`colorimetry.tristimulus_weights`: CIE 1931 2°
  CMFs, the illuminant interpolated linearly, rectangle rule, perfect reflector Y = 1), then
  white-balanced (below);
- `matrix_RGB_to_XYZ`, `matrix_XYZ_to_RGB`, `white_XYZ`: the colour space's derived matrices
  and white (Y = 1);
- `illuminant` (n,): the illuminant normalised to unit relative luminance,
  $\sum_i I(\lambda_i)\bar y(\lambda_i)\Delta\lambda = \sum_i \bar y(\lambda_i)\Delta\lambda$.

**White balance.** The tabulated illuminant's chromaticity differs from the colour space's
nominal white in the fifth decimal (D65 from the CIE table at 1 nm is xy = (0.31272, 0.32903),
sRGB's white is (0.3127, 0.3290)), so a perfect reflector would come out as linear sRGB
(1.00016, 0.99998, 0.99976) instead of (1, 1, 1). The model divides each RGB channel of the
weights by its sum (a von Kries gain in the space's own RGB, `rgb_gain`, |gain - 1| < 3e-4 for
the built-in spaces), so that a flat spectrum maps exactly to the space's white and a colour
space's own white round-trips exactly. Renderers that want the same bit-for-bit agreement
convert XYZ to RGB with `matrix_XYZ_to_RGB_balanced`.

The illuminant is `colorimetry.get_illuminant(whitepoint_name)`; the ACES spaces, whose white is
"ACES" (about D60), use CIE daylight at 6000 K x 1.4388/1.4380 (`colorimetry.daylight_spd`),
as pbrt does.
"""

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from ..colorimetry import daylight_spd, get_cmfs, get_colourspace, get_illuminant
from ..constants import K_M, VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM

DEFAULT_OBSERVER = "CIE 1931 2 Degree Standard Observer"
# CCT of the ACES white: CIE daylight at 6000 K on the pre-1968 temperature scale.
ACES_WHITE_CCT = 6000.0 * 1.4388 / 1.4380  # K


class ForwardModel(eqx.Module):
    """Colorimetric forward model of the upsampling fit for one RGB colour space.

    Build it with `forward_model(colourspace)`. All arrays are NumPy float64 (static data);
    the fitter casts them to its working dtype.

    - `colourspace`: canonical colour-space name (static).
    - `wavelengths_nm` (n,), `lambda_normalised` (n,) = (lambda - 360) / 470. [nm], [-]
    - `weights_XYZ` (n, 3): reflectance -> XYZ weights, white-balanced. [-]
    - `matrix_RGB_to_XYZ`, `matrix_XYZ_to_RGB` (3, 3): the space's derived matrices. [-]
    - `matrix_XYZ_to_RGB_balanced` (3, 3): `diag(rgb_gain) @ matrix_XYZ_to_RGB`. [-]
    - `white_XYZ` (3,): the space's white, Y = 1. [-]
    - `rgb_gain` (3,): the white-balance gains (module docstring). [-]
    - `illuminant` (n,): the space's illuminant, unit relative luminance. [relative]
    - `step_nm`: grid spacing (static). [nm]

    !!! note "Thesis"
        Eq. 2.27, section 2.2.3.
    """

    colourspace: str = eqx.field(static=True)
    step_nm: float = eqx.field(static=True)
    wavelengths_nm: np.ndarray
    lambda_normalised: np.ndarray
    weights_XYZ: np.ndarray
    matrix_RGB_to_XYZ: np.ndarray
    matrix_XYZ_to_RGB: np.ndarray
    matrix_XYZ_to_RGB_balanced: np.ndarray
    white_XYZ: np.ndarray
    rgb_gain: np.ndarray
    illuminant: np.ndarray

    def description(self) -> dict:
        """The fit settings this model stands for, as plain JSON-able values."""
        return {
            "colourspace": self.colourspace,
            "observer": DEFAULT_OBSERVER,
            "wavelength_range_nm": [float(self.wavelengths_nm[0]), float(self.wavelengths_nm[-1])],
            "wavelength_step_nm": self.step_nm,
            "quadrature": "rectangle rule (colorimetry.tristimulus_weights)",
            "white_balance_rgb_gain": [float(g) for g in self.rgb_gain],
        }


def _space(colourspace):
    return get_colourspace(colourspace)


def _illuminant_values(whitepoint_name: str, wl: np.ndarray) -> np.ndarray:
    """The space's illuminant on the grid `wl` [nm], float64 NumPy: a tabulated CIE
    illuminant interpolated linearly (constant beyond its table, as `jnp.interp`), or for the
    ACES white CIE daylight (`colorimetry.daylight_spd`, in float64)."""
    with jax.enable_x64(True):  # the tables as packaged (float64), not JAX's default float32
        if whitepoint_name == "ACES":
            return np.asarray(daylight_spd(ACES_WHITE_CCT, jnp.asarray(wl)), np.float64)
        ill = get_illuminant(whitepoint_name)
    return np.interp(wl, np.asarray(ill.wavelengths_nm), np.asarray(ill.values))


def _tristimulus_weights(wl: np.ndarray, illuminant: np.ndarray | None) -> np.ndarray:
    """`colorimetry.tristimulus_weights(wl, illuminant)` (CIE 1931 2°) in float64 NumPy.

    The same rectangle rule (cell widths: the first and last steps at the ends, the mean of
    the two neighbouring steps inside) and linear CMF interpolation, zero outside the table;
    evaluated with NumPy because a process that renders needs these weights once, and JAX
    would trace, lower and load a program for them (about 0.1 s of every render's start-up).
    `tests/upsampling/test_forward.py` checks it against the JAX function.
    """
    with jax.enable_x64(True):  # the table as packaged (float64)
        cmfs = get_cmfs(DEFAULT_OBSERVER)
    cmf_wl, cmf_v = np.asarray(cmfs.wavelengths_nm), np.asarray(cmfs.values)
    table = np.stack(
        [np.interp(wl, cmf_wl, cmf_v[:, k], left=0.0, right=0.0) for k in range(3)], axis=-1
    )
    d = np.diff(wl)
    w = table * np.concatenate([d[:1], 0.5 * (d[:-1] + d[1:]), d[-1:]])[:, None]
    if illuminant is None:
        return K_M * w
    w = illuminant[:, None] * w
    return w / np.sum(w[:, 1])


@functools.lru_cache(maxsize=16)
def _forward_model_cached(name: str, step_nm: float) -> ForwardModel:
    cs = _space(name)
    n = int(round((VISIBLE_WAVELENGTH_MAX_NM - VISIBLE_WAVELENGTH_MIN_NM) / step_nm)) + 1
    wl_np = np.linspace(VISIBLE_WAVELENGTH_MIN_NM, VISIBLE_WAVELENGTH_MAX_NM, n)
    ill = _illuminant_values(cs.whitepoint_name, wl_np)
    w_xyz = _tristimulus_weights(wl_np, ill)
    w_emissive = _tristimulus_weights(wl_np, None)
    to_xyz = np.asarray(cs.matrix_RGB_to_XYZ, dtype=np.float64)
    to_rgb = np.asarray(cs.matrix_XYZ_to_RGB, dtype=np.float64)
    w_rgb = w_xyz @ to_rgb.T
    gain = 1.0 / w_rgb.sum(axis=0)
    w_bal = (w_rgb * gain) @ to_xyz.T
    # Unit relative luminance: sum(I ybar dl) = sum(ybar dl) (pbrt's normalisation).
    ill_n = ill * w_emissive[:, 1].sum() / (ill * w_emissive[:, 1]).sum()
    model = ForwardModel(
        colourspace=cs.name,
        step_nm=float(step_nm),
        wavelengths_nm=wl_np,
        lambda_normalised=(wl_np - VISIBLE_WAVELENGTH_MIN_NM)
        / (VISIBLE_WAVELENGTH_MAX_NM - VISIBLE_WAVELENGTH_MIN_NM),
        weights_XYZ=w_bal,
        matrix_RGB_to_XYZ=to_xyz,
        matrix_XYZ_to_RGB=to_rgb,
        matrix_XYZ_to_RGB_balanced=gain[:, None] * to_rgb,
        white_XYZ=to_xyz.sum(axis=1),
        rgb_gain=gain,
        illuminant=ill_n,
    )
    return model


def forward_model(colourspace="sRGB", *, step_nm: float = 1.0) -> ForwardModel:
    r"""The colorimetric forward model of the upsampling fit (thesis eq. 2.27) for a space.

    **Arguments:**

    - `colourspace`: a name or alias of `colorimetry.RGB_COLOURSPACES` ("sRGB",
        "Display P3", "Rec.2020", "ACES2065-1", "ProPhoto RGB", ...) or an `RGBColourspace`
        registered there.
    - `step_nm`: quadrature step; 470 / step_nm must be an integer. [nm]

    **Returns:**

    A `ForwardModel` (cached per space and step), see the module docstring.

    !!! note "Thesis"
        Eq. 2.27, section 2.2.3 (the integral and $W_{D65}$).

    ??? cite "References"
        `Jakob2019` section 4; `CIE2018` section 7.
    """
    if not isinstance(step_nm, int | float) or step_nm <= 0:
        raise ValueError(f"`step_nm` must be a positive number [nm], got {step_nm!r}.")
    n = (VISIBLE_WAVELENGTH_MAX_NM - VISIBLE_WAVELENGTH_MIN_NM) / step_nm
    if abs(n - round(n)) > 1e-9:
        raise ValueError(f"`step_nm` must divide 470 nm evenly, got {step_nm!r}. [nm]")
    name = _space(colourspace).name
    return _forward_model_cached(name, float(step_nm))


# --- CIELAB and the model's XYZ, in JAX ---------------------------------------------------

_DELTA = 6.0 / 29.0


def lab_f(t: Array) -> Array:
    """CIE 1976 f(t): cube root above (6/29)^3, linear below (defined for t <= 0 too)."""
    big = t > _DELTA**3
    return jnp.where(big, jnp.cbrt(jnp.where(big, t, 1.0)), t / (3.0 * _DELTA**2) + 4.0 / 29.0)


def XYZ_to_Lab_white(XYZ: Array, white_XYZ: Array) -> Array:
    """CIELAB of XYZ (..., 3) relative to `white_XYZ` (3,); the formula of
    `colorimetry.XYZ_to_Lab`, without its argument checks (it runs in the fitter's loop)."""
    f = lab_f(XYZ / white_XYZ.reshape((1,) * (XYZ.ndim - 1) + (3,)))
    fx, fy, fz = f[..., 0], f[..., 1], f[..., 2]
    return jnp.stack([116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)], axis=-1)
