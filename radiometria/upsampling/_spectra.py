r"""RGB colours as spectra for a spectral renderer: albedo, unbounded, illuminant (pbrt-v4).

The thesis (section 2.2.3, note after eq. 2.27) separates reflectances, bounded in [0, 1], from
illuminants and transmission coefficients, whose RGB can exceed 1: those are normalised before
the table lookup and the scale is kept. Following pbrt-v4, the normalisation divides by
$2\max(r, g, b)$, so the looked-up colour has its largest component at 1/2, which leaves the
sigmoid room on both sides; the spectrum is multiplied back by that scale.

- `RGBAlbedoSpectrum(lut, rgb)`: $S(\lambda)$ from the table, rgb in [0, 1], values in [0, 1];
- `RGBUnboundedSpectrum(lut, rgb)`: $m \cdot S_{rgb/m}(\lambda)$ with $m = 2\max(rgb)$, rgb >= 0;
- `RGBIlluminantSpectrum(lut, rgb, colourspace)`: the unbounded spectrum times the colour
  space's illuminant, normalised to unit relative luminance
  ($\sum I\bar y\,\Delta\lambda = \sum \bar y\,\Delta\lambda$, pbrt's convention), so RGB
  (1, 1, 1) is the space's white light with Y = 1 when XYZ is computed as
  $\int L \bar x\,d\lambda / \int \bar y\,d\lambda$.

**Outside 360-830 nm.** The table is fitted on 360-830 nm (the CMFs' range, where the
forward model integrates), but the spectra accept any wavelength. `RGBAlbedoSpectrum` and
`RGBUnboundedSpectrum` continue the same sigmoid polynomial (as pbrt-v4's
`RGBAlbedoSpectrum::operator()`, which evaluates `RGBSigmoidPolynomial` at any lambda): values
stay in [0, 1] and [0, m] and finite (the stable sigmoid maps a huge polynomial value to 0 or
1), and greys stay exactly flat. No colour constrains those values (the CMFs are 0 there), so a
renderer that samples wavelengths outside 360-830 nm gets a smooth extrapolation, not data.
`RGBIlluminantSpectrum` is 0 outside 360-830 nm, because the illuminant table ends there
(Mitsuba 3 returns 0 for every upsampled spectrum outside the range; its issue #1771).

All three are `radiometry.AbstractSpectrum` Modules holding arrays (nm coefficients,
scales, the illuminant table; and that table's spacing, a static field): batches of colours
are one object, and they pass through `jit`, `vmap` and `grad` (the lookup is
differentiable in rgb).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_last_axis, device_array
from .._math import interp_table, uniform_grid
from ..colorimetry import get_colourspace
from ..radiometry import AbstractSpectrum
from ._forward import forward_model
from ._lut import RGBToSpectrumLUT, _check_rgb_values, lookup
from ._sigmoid_polynomial import _evaluate, common_float_dtype


def _rgb(rgb, upper):
    x = check_last_axis(as_float_array(rgb, "rgb"), "rgb", 3)
    return _check_rgb_values(x, upper=upper)


def _mul(a: Array, b: Array) -> Array:
    """a * b with explicit broadcasting (leading axes padded; rank promotion may be off)."""
    rank = max(a.ndim, b.ndim)
    a = a.reshape((1,) * (rank - a.ndim) + a.shape)
    b = b.reshape((1,) * (rank - b.ndim) + b.shape)
    return a * b


def _scaled(scale: Array, s: Array, scalar_wavelength: bool) -> Array:
    """scale (*batch) times spectrum values s (broadcast((*batch, 1), wl.shape))."""
    scale = scale.astype(s.dtype)
    return _mul(scale, s) if scalar_wavelength else _mul(scale[..., None], s)


def _unbounded(lut: RGBToSpectrumLUT, rgb: Array) -> tuple[Array, Array]:
    """(nm coefficients, scale) of pbrt's RGBUnboundedSpectrum."""
    normalised, scale = _half_brightness(rgb)
    return lookup(lut, normalised), scale


@jax.jit
def _half_brightness(rgb: Array) -> tuple[Array, Array]:
    """(rgb / m, m) with m = 2 max(rgb), black for black: one compiled program (eagerly, as a
    scene's setup runs it, its operations would compile one by one: 0.1-0.2 s)."""
    scale = 2.0 * jnp.max(rgb, axis=-1)
    safe = jnp.where(scale > 0, scale, 1.0)
    return jnp.where((scale > 0)[..., None], rgb / safe[..., None], 0.0), scale


class RGBAlbedoSpectrum(AbstractSpectrum):
    r"""A reflectance spectrum in [0, 1] for a linear RGB colour in [0, 1] (pbrt-v4).

    $S(\lambda) = s(c_0\lambda^2 + c_1\lambda + c_2)$ with the coefficients from the table.

    **Arguments:**

    - `lut`: the `RGBToSpectrumLUT` of the colour space of `rgb`.
    - `rgb`: linear RGB (..., 3), components in [0, 1] (checked; `eqx.error_if` under jit). [-]

    Calling with wavelengths (..., n_lambda) [nm] gives values in [0, 1] of shape
    `broadcast((*batch, 1), wavelength_nm.shape)` [-]; outside 360-830 nm the same sigmoid
    polynomial continued (module docstring).

    !!! note "Thesis"
        Eq. 2.25-2.27, section 2.2.3.

    ??? cite "References"
        `Pharr2023` section 4.6.6 (`RGBAlbedoSpectrum`); `Jakob2019`.
    """

    coeffs: Float[Array, "*batch 3"]

    def __init__(self, lut: RGBToSpectrumLUT, rgb: ArrayLike):
        self.coeffs = lookup(lut, _rgb(rgb, 1.0))

    def __call__(self, wavelength_nm: ArrayLike) -> Array:
        return _evaluate(self.coeffs, as_float_array(wavelength_nm, "wavelength_nm"))


class RGBUnboundedSpectrum(AbstractSpectrum):
    r"""A spectrum for a linear RGB colour with components >= 0 of any size (pbrt-v4).

    $S(\lambda) = m\, s(c(\mathrm{rgb}/m)\cdot(\lambda^2, \lambda, 1))$ with
    $m = 2\max(r, g, b)$: the colour is looked up at half brightness and scaled back, so
    values are in $[0, m]$ (thesis section 2.2.3, the note on values > 1), at any wavelength
    (outside 360-830 nm the polynomial continued, module docstring). Black gives 0.

    **Arguments:**

    - `lut`: the `RGBToSpectrumLUT` of the colour space of `rgb`.
    - `rgb`: linear RGB (..., 3), components finite and >= 0. [-]

    **Fields:** `coeffs` (..., 3) nm coefficients, `scale` (...,) = $m$ [-].

    !!! note "Thesis"
        Section 2.2.3 (values > 1); eq. 2.25-2.27.

    ??? cite "References"
        `Pharr2023` section 4.6.6 (`RGBUnboundedSpectrum`).
    """

    coeffs: Float[Array, "*batch 3"]
    scale: Float[Array, "*batch"]

    def __init__(self, lut: RGBToSpectrumLUT, rgb: ArrayLike):
        self.coeffs, self.scale = _unbounded(lut, _rgb(rgb, None))

    def __call__(self, wavelength_nm: ArrayLike) -> Array:
        wl = as_float_array(wavelength_nm, "wavelength_nm")
        return _scaled(self.scale, _evaluate(self.coeffs, wl), wl.ndim == 0)


class RGBIlluminantSpectrum(AbstractSpectrum):
    r"""An emission spectrum for a linear RGB colour: unbounded spectrum x the space's illuminant.

    $L(\lambda) = m\, S_{\mathrm{rgb}/m}(\lambda)\, I(\lambda)$ with $m = 2\max(rgb)$ and $I$
    the colour space's illuminant (D65 for sRGB) normalised to unit relative luminance, so that
    RGB (1, 1, 1) is exactly the normalised illuminant. Outside 360-830 nm it is 0.

    **Arguments:**

    - `lut`: the `RGBToSpectrumLUT` of the colour space.
    - `rgb`: linear RGB (..., 3), components finite and >= 0. [-]
    - `colourspace`: the colour space (name or `RGBColourspace`); default the table's. It
        must be the table's space.

    **Fields:** `coeffs`, `scale` as `RGBUnboundedSpectrum`; `illuminant_wavelengths_nm`
    (n,) [nm] and `illuminant_values` (n,) [relative], the normalised illuminant on 1 nm.

    !!! note "Thesis"
        Section 2.2.3 (illuminant spectra with values > 1); eq. 2.27 ($W_{D65}$).

    ??? cite "References"
        `Pharr2023` section 4.6.6 (`RGBIlluminantSpectrum`).
    """

    coeffs: Float[Array, "*batch 3"]
    scale: Float[Array, "*batch"]
    illuminant_wavelengths_nm: Float[Array, " n"]
    illuminant_values: Float[Array, " n"]
    illuminant_grid_nm: tuple[float, float] | None = eqx.field(static=True)

    def __init__(self, lut: RGBToSpectrumLUT, rgb: ArrayLike, colourspace=None):
        name = lut.colourspace if colourspace is None else get_colourspace(colourspace).name
        if name != get_colourspace(lut.colourspace).name:
            raise ValueError(
                f"`colourspace` {name!r} does not match the table's colour space "
                f"{lut.colourspace!r}; build or load the table of {name!r}."
            )
        x = _rgb(rgb, None)
        self.coeffs, self.scale = _unbounded(lut, x)
        model = forward_model(name)
        dtype = self.coeffs.dtype
        self.illuminant_wavelengths_nm = device_array(model.wavelengths_nm, dtype)
        self.illuminant_values = device_array(model.illuminant, dtype)
        self.illuminant_grid_nm = uniform_grid(model.wavelengths_nm)

    def illuminant(self, wavelength_nm: ArrayLike) -> Array:
        """The normalised illuminant at `wavelength_nm` [nm] (linear interpolation, 0 outside
        the table). [relative]"""
        wl = as_float_array(wavelength_nm, "wavelength_nm")
        dtype = common_float_dtype(wl, self.illuminant_values)
        return interp_table(
            wl.astype(dtype),
            self.illuminant_wavelengths_nm.astype(dtype),
            self.illuminant_values.astype(dtype),
            self.illuminant_grid_nm,
            left=0.0,
            right=0.0,
        )

    def __call__(self, wavelength_nm: ArrayLike) -> Array:
        wl = as_float_array(wavelength_nm, "wavelength_nm")
        scaled = _scaled(self.scale, _evaluate(self.coeffs, wl), wl.ndim == 0)
        return _mul(scaled, self.illuminant(wl).astype(scaled.dtype))
