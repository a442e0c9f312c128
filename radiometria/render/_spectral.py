r"""Spectra inside the renderer: tabulated spectrum rows and hero-wavelength sampling.

The integrators evaluate the scene's spectral quantities (reflectances, indices of refraction,
emitted radiance) at the four hero wavelengths of each path. All of them arrive as rows of a
`SpectrumTable`, sampled on one uniform 1 nm grid over the visible range [360, 830] nm and
interpolated linearly, as PBRT's `DenselySampledSpectrum` and Mitsuba's `RegularSpectrum`
evaluate spectra: one gather and one lerp per wavelength serve RGB-upsampled, measured and
blackbody spectra alike. `tabulate_spectrum` tabulates a scene parameter.

**RGB conventions (as Mitsuba 3's `scalar_spectral` and PBRT-v4).** A linear-sRGB reflectance
becomes the bounded sigmoid-polynomial spectrum of the Jakob-Hanika sRGB table
(`RGBAlbedoSpectrum`). A linear-sRGB *emitted radiance* becomes
$s\,S_{\mathrm{rgb}/s}(\lambda)\,D_{65}(\lambda)$ with $s = 2\max(\mathrm{rgb})$ and the CIE
D65 SPD scaled to unit luminance (`RGBIlluminantSpectrum`), so that rgb (1, 1, 1) emits D65 with
Y = 1 and renders as linear sRGB (1, 1, 1). Mitsuba's `d65` spectrum does the same with the
constant 1/98.99 for the D65 scale (its Y is 0.999 on its 5 nm CMF table); the two differ by
about 0.1 % in the image means (Cornell box at 256 x 256: within 0.2 % per channel).
"""

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from .._checks import device_array
from ..constants import VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM
from ..montecarlo import sample_visible_wavelengths_with_pdf
from ..radiometry import AbstractSpectrum, PiecewiseLinearSpectrum
from ..upsampling import (
    RGBAlbedoSpectrum,
    RGBIlluminantSpectrum,
    RGBUnboundedSpectrum,
    get_lut,
    sigmoid_jakob2019,
)

__all__ = [
    "N_HERO_WAVELENGTHS",
    "RGB_LUMINANCE",
    "LinearRGB",
    "SpectrumTable",
    "sample_hero_wavelengths",
    "sigmoid_texel_spectra",
    "tabulate_spectrum",
    "wavelength_grid_nm",
]

N_HERO_WAVELENGTHS = 4  # wavelengths carried by one path (PBRT's NSpectrumSamples, Mitsuba's)
# Y of linear sRGB (Rec. 709 primaries, D65), as Mitsuba's `luminance()`: how scalar
# parameters read colour textures (Mitsuba's `eval_1`).
RGB_LUMINANCE = np.array([0.212671, 0.715160, 0.072169])
_GRID_STEP_NM = 1.0


def wavelength_grid_nm() -> np.ndarray:
    """The renderer's tabulation grid: 360, 361, ..., 830 nm (471 points) as float64 NumPy.

    **Returns:**

    The grid `(471,)`. [nm]

    ??? cite "References"
        `Pharr2023` §4.4 (the visible range 360-830 nm).
    """
    n = int(round((VISIBLE_WAVELENGTH_MAX_NM - VISIBLE_WAVELENGTH_MIN_NM) / _GRID_STEP_NM)) + 1
    return VISIBLE_WAVELENGTH_MIN_NM + _GRID_STEP_NM * np.arange(n, dtype=np.float64)


class SpectrumTable(eqx.Module):
    """Rows of spectra on the renderer's uniform grid (`wavelength_grid_nm`), lerped on lookup.

    **Arguments:**

    - `values`: `(rows, 471)` spectral values on `wavelength_grid_nm()`; their unit is the
        unit of the quantity tabulated (reflectance [1], radiance [W m^-2 sr^-1 nm^-1], ...).

    Calling the table with `row` (integer array) and `wavelength_nm` (`row.shape + (k,)`)
    [nm] returns the values of each row at its wavelengths, shape `row.shape + (k,)`.
    Wavelengths outside [360, 830] nm are clamped to the ends of the table.

    ??? cite "References"
        `Pharr2023` §4.5.1 (`DenselySampledSpectrum`).
    """

    values: Float[Array, "rows n"]

    def __check_init__(self):
        n = wavelength_grid_nm().shape[0]
        if self.values.ndim != 2 or self.values.shape[1] != n:
            raise ValueError(
                f"`values` must have shape (rows, {n}) on the 1 nm grid [360, 830] nm, "
                f"got {self.values.shape}."
            )

    def __call__(
        self, row: Int[Array, "*batch"], wavelength_nm: Float[Array, "*batch k"]
    ) -> Float[Array, "*batch k"]:
        n = self.values.shape[1]
        x = (wavelength_nm - VISIBLE_WAVELENGTH_MIN_NM) / _GRID_STEP_NM
        x = jnp.clip(x, 0.0, n - 1.0)
        i = jnp.minimum(jnp.floor(x).astype(jnp.int32), n - 2)
        t = (x - i.astype(x.dtype)).astype(self.values.dtype)
        flat = self.values.reshape(-1)
        base = row.astype(jnp.int32)[..., None] * n + i
        v0 = jnp.take(flat, base, mode="clip")
        v1 = jnp.take(flat, base + 1, mode="clip")
        return v0 + t * (v1 - v0)


def sigmoid_texel_spectra(
    coeffs: Float[Array, "3 m"], texel: Int[Array, " n"], wavelength_kn: Float[Array, "k n"]
) -> Float[Array, "k n"]:
    r"""The sigmoid-polynomial spectra $s(c_0\lambda^2 + c_1\lambda + c_2)$ of image texels
    at each path's wavelengths, laid out wavelengths first (thesis eq. 2.25-2.26).

    **Arguments:**

    - `coeffs`: `(3, m)` nm coefficients of `m` texels, one row per coefficient
        (`sigmoid_polynomial_jakob2019`'s $c_0, c_1, c_2$). [nm^-2, nm^-1, 1]
    - `texel`: `(n,)` int32 index of each path's texel into the `m`.
    - `wavelength_kn`: `(k, n)` the paths' wavelengths, transposed. [nm]

    **Returns:**

    `(k, n)` spectral values in [0, 1]. [1]

    An environment map blends four texels' spectra per path (bilinear filtering).
    XLA:CPU vectorises elementwise work along an array's last axis only, so the blend runs
    on `(k, n)` arrays and is transposed to the renderer's `(n, k)` once at the end: the
    envmap's bilinear lookup took 46-65 ns per path this way against 96-121 ns on `(n, k)`
    arrays (2048 paths, float32, one core), and the environment-map benchmark renders 4 %
    faster. (The `bitmap` texture keeps `(n, k)`: inside the material blocks the same
    change made the textured benchmark scene 2-3 % slower.) The coefficients are gathered
    one row at a time, `(n,)` each.

    ??? cite "References"
        `Jakob2019` eq. 3 (the model); `Jakob2022` (Mitsuba 3 evaluates texels' spectra and
        interpolates them in its spectral variants).
    """
    c0, c1, c2 = (coeffs[r][texel][None, :] for r in range(3))  # (1, n) each
    lam = wavelength_kn.astype(coeffs.dtype)
    x = (c0 * lam + c1) * lam + c2  # Horner, as `sigmoid_polynomial_jakob2019`
    return sigmoid_jakob2019(x)


def sample_hero_wavelengths(u: Float[Array, "*batch"]) -> tuple[Array, Array]:
    r"""Four stratified hero wavelengths from one uniform variate, with their densities.

    Wavelength $i$ is drawn by inverting PBRT's visible-wavelength density at
    $u_i = (u + i/4) \bmod 1$, so the four are stratified in the density's CDF and each one is
    marginally distributed with that density (PBRT's `SampledWavelengths::SampleVisible`,
    Mitsuba's `sample_shifted` + `sample_rgb_spectrum`).

    **Arguments:**

    - `u`: uniform variates in [0, 1), any shape. [1]

    **Returns:**

    `(wavelength_nm, pdf)`, each of shape `u.shape + (4,)`; `pdf` in [nm^-1].

    ??? cite "References"
        `Wilkie2014` (hero wavelength spectral sampling); `Pharr2023` §4.6.2, §5.4.2.
    """
    # Computed wavelengths first, (4, ...), and moved last at the end: XLA:CPU vectorises
    # along the last axis only.
    shift = jnp.arange(N_HERO_WAVELENGTHS, dtype=u.dtype) / N_HERO_WAVELENGTHS
    ui = u[None] + shift.reshape((N_HERO_WAVELENGTHS,) + (1,) * u.ndim)
    ui = jnp.where(ui >= 1.0, ui - 1.0, ui)
    # u is ours: in [0, 1)
    wavelength_nm, pdf = sample_visible_wavelengths_with_pdf(ui, check=False)
    return jnp.moveaxis(wavelength_nm, 0, -1), jnp.moveaxis(pdf, 0, -1)


# --- Scene parameters tabulated on the renderer's grid ---------------------------------------


@dataclasses.dataclass(frozen=True)
class LinearRGB:
    """A linear sRGB triple as a scene file gives it (Rec. 709 primaries, D65 white).

    Its spectrum depends on the parameter that receives it, as in Mitsuba 3: a reflectance
    becomes an `RGBAlbedoSpectrum`, an index of refraction or a scale factor an
    `RGBUnboundedSpectrum`, an emitted radiance an `RGBIlluminantSpectrum` (thesis 2.2.3).
    The receiving plugin passes that class to `tabulate_spectrum`.

    **Fields:**

    - `rgb`: `(3,)` float64 linear sRGB components. [1, or the parameter's unit]
    """

    rgb: "np.ndarray | list[float] | tuple[float, float, float]"

    def __post_init__(self):
        object.__setattr__(self, "rgb", np.asarray(self.rgb, np.float64).reshape(3))


SpectralValue = LinearRGB | AbstractSpectrum | float
"""What a scene file gives for a spectral parameter: an RGB triple, a spectrum or a number."""

_RGB_SPECTRA = (RGBAlbedoSpectrum, RGBUnboundedSpectrum, RGBIlluminantSpectrum)


def _rgb_spectrum(rgb: np.ndarray, rgb_spectrum: type, grid: np.ndarray) -> np.ndarray:
    if np.any(rgb < 0) or not np.all(np.isfinite(rgb)):
        raise ValueError(f"RGB values must be finite and >= 0, got {rgb.tolist()}.")
    if rgb_spectrum is RGBAlbedoSpectrum and np.any(rgb > 1):
        raise ValueError(f"An RGB reflectance must lie in [0, 1], got {rgb.tolist()}.")
    # The spectrum is built outside `jit`: its table lookup (`upsampling.lookup`, with its
    # Levenberg-Marquardt refinement) is one compiled program whatever the class, and only
    # the evaluation on the grid is compiled per class. (One program per class, lookup
    # inlined, compiled the refinement once per class: 0.36-0.71 s each, 1.5 s for the three
    # classes on a first run, against 0.95 s this way.)
    spectrum = rgb_spectrum(get_lut("sRGB"), device_array(rgb))
    return np.asarray(_evaluate_spectrum(spectrum, device_array(grid)), np.float64)


@eqx.filter_jit
def _evaluate_spectrum(spectrum, grid):
    return spectrum(grid)


def tabulate_spectrum(value: SpectralValue, rgb_spectrum: type) -> np.ndarray:
    r"""A scene's spectral parameter tabulated on the renderer's grid (`wavelength_grid_nm`).

    **Arguments:**

    - `value`: a `LinearRGB` triple, a `radiometria.radiometry.AbstractSpectrum` (for
        example a `PiecewiseLinearSpectrum` of measured data, linear in between and zero
        outside, or a `BlackbodySpectrum`: thesis eq. 1.24), or a number (a constant
        spectrum).
    - `rgb_spectrum`: the class that turns an RGB triple into a spectrum, chosen by the
        parameter's meaning (thesis 2.2.3): `RGBAlbedoSpectrum` (a reflectance in [0, 1]: the
        bounded sigmoid-polynomial spectrum of Jakob & Hanika 2019), `RGBIlluminantSpectrum`
        (an emitted radiance: $s\,S_{\mathrm{rgb}/s}(\lambda)\,D_{65}(\lambda)$ with
        $s = 2\max(\mathrm{rgb})$ and the D65 SPD scaled to luminance $Y = 1$, so that white
        (1, 1, 1) emits D65 and renders as linear sRGB (1, 1, 1)) or `RGBUnboundedSpectrum`
        (the same without D65), all from `radiometria.upsampling`.

    **Returns:**

    Float64 values `(471,)` on the 1 nm grid [the unit of the parameter].

    ??? cite "References"
        `Jakob2019` (sigmoid-polynomial upsampling); `Pharr2023` §4.6.6 (RGB spectra);
        `Jakob2022` (Mitsuba's `d65` spectrum for RGB emitters).
    """
    if rgb_spectrum not in _RGB_SPECTRA:
        raise ValueError(
            f"`rgb_spectrum` must be one of {', '.join(c.__name__ for c in _RGB_SPECTRA)}, "
            f"got {rgb_spectrum!r}."
        )
    grid = wavelength_grid_nm()
    if isinstance(value, LinearRGB):
        return _rgb_spectrum(value.rgb, rgb_spectrum, grid)
    if isinstance(value, PiecewiseLinearSpectrum):
        # NumPy in float64, so that measured data is tabulated exactly, whatever JAX's dtype.
        wl, v = (np.asarray(a, np.float64) for a in (value.wavelengths_nm, value.values))
        return np.interp(grid, wl, v, left=0.0, right=0.0)
    if isinstance(value, AbstractSpectrum):
        return np.asarray(_evaluate_spectrum(value, device_array(grid)), np.float64)
    if isinstance(value, int | float | np.floating | np.integer) and not isinstance(value, bool):
        return np.full(grid.shape, float(value))
    raise TypeError(
        "A spectral parameter must be a LinearRGB, an AbstractSpectrum or a number, got "
        f"{type(value).__name__} {value!r}."
    )
