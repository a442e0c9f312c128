r"""Spectra inside the renderer: tabulated spectrum rows and hero-wavelength sampling.

The integrators evaluate the scene's spectral quantities (reflectances, indices of refraction,
emitted radiance) at the four hero wavelengths of each path. All of them arrive as rows of a
`SpectrumTable`, sampled on one uniform 1 nm grid over the visible range [360, 830] nm and
interpolated linearly, as PBRT's `DenselySampledSpectrum` and Mitsuba's `RegularSpectrum`
evaluate spectra: one gather and one lerp per wavelength serve RGB-upsampled, measured and
blackbody spectra alike. `spectrum_values` tabulates a scene parameter.

**RGB conventions (as Mitsuba 3's `scalar_spectral` and PBRT-v4).** A linear-sRGB reflectance
becomes the bounded sigmoid-polynomial spectrum of the Jakob-Hanika sRGB table
(`RGBAlbedoSpectrum`). A linear-sRGB *emitted radiance* becomes
$s\,S_{\mathrm{rgb}/s}(\lambda)\,D_{65}(\lambda)$ with $s = 2\max(\mathrm{rgb})$ and the CIE
D65 SPD scaled to unit luminance (`RGBIlluminantSpectrum`), so that rgb (1, 1, 1) emits D65 with
Y = 1 and renders as linear sRGB (1, 1, 1). Mitsuba's `d65` spectrum does the same with the
constant 1/98.99 for the D65 scale (its Y is 0.999 on its 5 nm CMF table); the two differ by
about 0.1 % in the image means (Cornell box at 256 x 256: within 0.2 % per channel).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from ..montecarlo import sample_visible_wavelengths, visible_wavelengths_pdf

__all__ = [
    "N_HERO_WAVELENGTHS",
    "SPECTRUM_KINDS",
    "WAVELENGTH_MAX_NM",
    "WAVELENGTH_MIN_NM",
    "SpectrumTable",
    "sample_hero_wavelengths",
    "spectrum_values",
    "wavelength_grid_nm",
]

WAVELENGTH_MIN_NM = 360.0  # nm, lower end of PBRT's and Mitsuba's visible range
WAVELENGTH_MAX_NM = 830.0  # nm, upper end
N_HERO_WAVELENGTHS = 4  # wavelengths carried by one path (PBRT's NSpectrumSamples, Mitsuba's)
_GRID_STEP_NM = 1.0


def wavelength_grid_nm() -> np.ndarray:
    """The renderer's tabulation grid: 360, 361, ..., 830 nm (471 points) as float64 NumPy.

    **Returns:**

    The grid `(471,)`. [nm]

    ??? cite "References"
        `Pharr2023` §4.4 (the visible range 360-830 nm).
    """
    n = int(round((WAVELENGTH_MAX_NM - WAVELENGTH_MIN_NM) / _GRID_STEP_NM)) + 1
    return WAVELENGTH_MIN_NM + _GRID_STEP_NM * np.arange(n, dtype=np.float64)


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
    shift = jnp.arange(N_HERO_WAVELENGTHS, dtype=u.dtype) / N_HERO_WAVELENGTHS
    ui = u[..., None] + shift.reshape((1,) * u.ndim + (N_HERO_WAVELENGTHS,))
    ui = jnp.where(ui >= 1.0, ui - 1.0, ui)
    wavelength_nm = sample_visible_wavelengths(ui)
    return wavelength_nm, visible_wavelengths_pdf(wavelength_nm)


# --- Spectra of scene parameters, tabulated on the renderer's grid ----------------------------

SPECTRUM_KINDS = ("albedo", "illuminant", "unbounded")


def _rgb_spectrum(rgb: np.ndarray, kind: str, grid: np.ndarray) -> np.ndarray:
    from ..upsampling import (
        RGBAlbedoSpectrum,
        RGBIlluminantSpectrum,
        RGBUnboundedSpectrum,
        forward_model,
        get_lut,
    )

    if np.any(rgb < 0) or not np.all(np.isfinite(rgb)):
        raise ValueError(f"RGB values must be finite and >= 0, got {rgb.tolist()}.")
    if kind == "albedo" and np.any(rgb > 1):
        raise ValueError(f"An RGB reflectance must lie in [0, 1], got {rgb.tolist()}.")
    cls = {
        "albedo": RGBAlbedoSpectrum,
        "unbounded": RGBUnboundedSpectrum,
        "illuminant": RGBIlluminantSpectrum,
    }[kind]
    # One compiled program per kind (op-by-op dispatch would compile every primitive). The
    # illuminant's constructor reads the colour space's cached forward model with NumPy, so
    # that cache is filled outside the trace first.
    forward_model("sRGB")
    values = _evaluate_rgb_spectrum(cls, get_lut("sRGB"), jnp.asarray(rgb), jnp.asarray(grid))
    return np.asarray(values, np.float64)


@eqx.filter_jit
def _evaluate_rgb_spectrum(cls, lut, rgb, grid):
    return cls(lut, rgb)(grid)


def spectrum_values(spec: dict, kind: str) -> np.ndarray:
    r"""A scene's spectral parameter tabulated on the renderer's grid (`wavelength_grid_nm`).

    **Arguments:**

    - `spec`: one of the forms of `radiometria.render.load_scene`'s scene descriptions:
        `{"rgb": (3,)}` (linear sRGB), `{"spectrum": (wavelengths_nm, values)}` (linear in
        between, zero outside, as the measured Cornell data), `{"blackbody": {"temperature":
        T, "scale": s}}` ($s$ times Planck's law, thesis eq. 1.24) or `{"value": x}`.
    - `kind`: how an RGB triple becomes a spectrum: `"albedo"` (a reflectance in [0, 1]:
        the bounded sigmoid-polynomial spectrum of Jakob & Hanika 2019), `"illuminant"` (an
        emitted radiance: PBRT's `RGBIlluminantSpectrum` and Mitsuba's spectral `rgb` emitter,
        i.e. $s\,S_{\mathrm{rgb}/s}(\lambda)\,D_{65}(\lambda)$ with $s = 2\max(\mathrm{rgb})$
        and the D65 SPD scaled to luminance $Y = 1$, so that white (1, 1, 1) emits D65 and
        renders as linear sRGB (1, 1, 1)) or `"unbounded"` (the same without D65).

    **Returns:**

    Float64 values `(471,)` on the 1 nm grid [the unit of the parameter].

    ??? cite "References"
        `Jakob2019` (sigmoid-polynomial upsampling); `Pharr2023` §4.6.6 (RGB spectra);
        `Jakob2022` (Mitsuba's `d65` spectrum for RGB emitters).
    """
    from .._checks import check_choice

    check_choice(kind, "kind", SPECTRUM_KINDS)
    grid = wavelength_grid_nm()
    if not isinstance(spec, dict) or len(spec) != 1:
        raise ValueError(f"A spectral parameter must be a dict with one key, got {spec!r}.")
    ((form, value),) = spec.items()
    if form == "rgb":
        return _rgb_spectrum(np.asarray(value, np.float64).reshape(3), kind, grid)
    if form == "spectrum":
        wl, v = (np.asarray(a, np.float64) for a in value)
        return np.interp(grid, wl, v, left=0.0, right=0.0)
    if form == "blackbody":
        from ..radiometry import planck

        temperature = float(value["temperature"])
        if not temperature > 0:
            raise ValueError(f"Blackbody temperature must be > 0 [K], got {temperature}.")
        return float(value.get("scale", 1.0)) * np.asarray(planck(grid, temperature), np.float64)
    if form == "value":
        return np.full(grid.shape, float(value))
    raise ValueError(
        f"Unknown spectrum form {form!r}; valid forms are 'rgb', 'spectrum', 'blackbody', 'value'."
    )
