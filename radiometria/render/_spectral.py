"""Spectra inside the renderer: tabulated spectrum rows and hero-wavelength sampling.

The integrators evaluate every spectral quantity (BSDF reflectances, emitted radiance, the CIE
colour-matching functions of the film) at the four hero wavelengths of each path. All of them
arrive here as rows of a `SpectrumTable`: one table per kind, sampled on one uniform 1 nm grid over
the visible range [360, 830] nm and interpolated linearly, which is how PBRT's
`DenselySampledSpectrum` and Mitsuba's `RegularSpectrum` evaluate spectra. One gather and one
lerp per wavelength then serve RGB-upsampled, measured and blackbody spectra alike.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

__all__ = [
    "N_HERO_WAVELENGTHS",
    "WAVELENGTH_MAX_NM",
    "WAVELENGTH_MIN_NM",
    "SpectrumTable",
    "sample_hero_wavelengths",
    "wavelength_grid_nm",
]

WAVELENGTH_MIN_NM = 360.0  # nm, lower end of PBRT's and Mitsuba's visible range
WAVELENGTH_MAX_NM = 830.0  # nm, upper end
N_HERO_WAVELENGTHS = 4  # wavelengths carried by one path (PBRT's NSpectrumSamples, Mitsuba's)
_GRID_STEP_NM = 1.0


def wavelength_grid_nm() -> np.ndarray:
    """The renderer's tabulation grid: 360, 361, ..., 830 nm (471 points) as float64 NumPy."""
    n = int(round((WAVELENGTH_MAX_NM - WAVELENGTH_MIN_NM) / _GRID_STEP_NM)) + 1
    return WAVELENGTH_MIN_NM + _GRID_STEP_NM * np.arange(n, dtype=np.float64)


class SpectrumTable(eqx.Module):
    """Rows of spectra on the renderer's uniform grid (`wavelength_grid_nm`), lerped on lookup.

    **Arguments:**

    - `values`: `(rows, 471)` spectral values on `wavelength_grid_nm()`; their unit is the
        unit of the quantity tabulated (reflectance [1], radiance [W m^-2 sr^-1 nm^-1], ...).

    Calling the table with `row` (integer array) and `wavelength_nm` (`row.shape + (k,)`)
    returns the values of each row at its wavelengths, shape `row.shape + (k,)`. Wavelengths
    outside [360, 830] nm are clamped to the ends of the table.
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
        x = (wavelength_nm - WAVELENGTH_MIN_NM) / _GRID_STEP_NM
        x = jnp.clip(x, 0.0, n - 1.0)
        i = jnp.minimum(jnp.floor(x).astype(jnp.int32), n - 2)
        t = (x - i.astype(x.dtype)).astype(self.values.dtype)
        flat = self.values.reshape(-1)
        base = row.astype(jnp.int32)[..., None] * n + i
        v0 = jnp.take(flat, base, mode="clip")
        v1 = jnp.take(flat, base + 1, mode="clip")
        return v0 + t * (v1 - v0)


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
    from ..montecarlo import sample_visible_wavelengths, visible_wavelengths_pdf

    shift = jnp.arange(N_HERO_WAVELENGTHS, dtype=u.dtype) / N_HERO_WAVELENGTHS
    ui = u[..., None] + shift.reshape((1,) * u.ndim + (N_HERO_WAVELENGTHS,))
    ui = jnp.where(ui >= 1.0, ui - 1.0, ui)
    wavelength_nm = sample_visible_wavelengths(ui)
    return wavelength_nm, visible_wavelengths_pdf(wavelength_nm)


# --- Spectra of scene parameters, tabulated on the renderer's grid ----------------------------


def _sigmoid_polynomial(coeffs, wavelength_nm):
    x = coeffs[0] * wavelength_nm**2 + coeffs[1] * wavelength_nm + coeffs[2]
    return 0.5 + x / (2.0 * np.sqrt(1.0 + x * x))


def _rgb_coefficients(rgb) -> np.ndarray:
    # TEMPORARY (helper P): colour-science's Jakob 2019 fit until radiometria.upsampling lands.
    import colour
    from colour.recovery.jakob2019 import find_coefficients_Jakob2019

    xyz = colour.RGB_to_XYZ(np.asarray(rgb, float), "sRGB")
    return np.asarray(find_coefficients_Jakob2019(xyz)[0])


def rgb_albedo_values(rgb) -> np.ndarray:
    """A linear-sRGB reflectance in [0, 1]^3 upsampled to a bounded spectrum on the grid."""
    rgb = np.asarray(rgb, np.float64)
    grid = wavelength_grid_nm()
    if np.all(rgb == rgb[0]):
        return np.full(grid.shape, rgb[0])
    return _sigmoid_polynomial(_rgb_coefficients(rgb), grid)


def _d65_unit_luminance(grid) -> np.ndarray:
    from ..colorimetry import get_cmfs, get_illuminant

    d65 = get_illuminant("D65")
    cmfs = get_cmfs()
    s = np.interp(grid, np.asarray(d65.wavelengths_nm), np.asarray(d65.values))
    ybar = np.interp(grid, np.asarray(cmfs.wavelengths_nm), np.asarray(cmfs.values)[:, 1], 0, 0)
    return s / (np.trapezoid(s * ybar, grid) / np.trapezoid(ybar, grid))


def rgb_illuminant_values(rgb) -> np.ndarray:
    """A linear-sRGB emitted radiance upsampled as PBRT's / Mitsuba's illuminant spectrum."""
    rgb = np.asarray(rgb, np.float64)
    grid = wavelength_grid_nm()
    m = float(rgb.max())
    scale = 2.0 * m
    if m <= 0:
        return np.zeros(grid.shape)
    return scale * rgb_albedo_values(rgb / scale) * _d65_unit_luminance(grid)
