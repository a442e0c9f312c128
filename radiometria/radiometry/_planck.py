"""Blackbody radiation: Planck's law, Stefan-Boltzmann's law and Wien's displacement law.

Thesis section 1.5, eq. (1.22)-(1.24).

Numerics. Planck's law is a prefactor over `expm1(x)` with `x = c_2 / (lambda T)`. Over the
promised domain (wavelength 1 nm to 1 mm, temperature 1 K to 1e6 K) `x` spans 1.4e-5 to 1.4e7,
so `exp(x)` overflows float32 from x = 88.7 and float64 from x = 709, while the radiance itself
is still representable well past those points. `_prefactor_over_expm1` therefore evaluates

- the direct form `A / expm1(x)` for `x <= x_s` (where `expm1` is accurate and neither it nor
  its square, which appears in the derivative, can overflow), and
- the Wien form `exp(log A - x)` beyond, which underflows gracefully to 0 instead of dividing
  by `inf`. The switch `x_s` (37 in float64, 18 in float32) is where `exp(-x)` drops below half
  an ulp of 1, so the dropped factor `1 / (1 - exp(-x))` of the exact law rounds to 1 anyway.

Each branch only ever sees an `x` clamped into its own half (the double-where trick), so the
branch that `jnp.where` discards has finite values and finite derivatives: gradients are finite
everywhere in the domain, in float32 and float64. Per point that is two exponentials; the
prefactor and its logarithm depend on the wavelength only and are computed before broadcasting
against the temperatures, so a spectrum-by-temperature grid pays for them once per wavelength.
Wavelengths enter in nm and stay in nm: the nm-to-m conversion is folded once into the
Python-float constants below, so no intermediate (like `lambda^5` in m^5 = 1e-45) leaves the
float32 range.
"""

import math

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .. import constants as _c
from .._checks import as_float_array, check_positive
from .._types import FloatLike

# --- Constants in the units of the public API (the one place where nm and m meet) ----------
# Planck's law per wavelength, eq. (1.24): L = c_1L / lambda^5 / expm1(c_2 / (lambda T)) in
# W sr^-1 m^-2 per metre of wavelength with lambda in m. With lambda = lambda_nm * 1e-9 m and a
# density per nm (one nm is 1e-9 m): L_nm = c_1L * 1e-9 / (1e-45 * lambda_nm^5) / expm1(...)
#                                         = (c_1L * 1e36) / lambda_nm^5 / expm1(...).
_C1L_NM = _c.C1L * _c.M_PER_NM / _c.M_PER_NM**5  # W sr^-1 m^-2 nm^-1 nm^5, about 1.19e20
_LOG_C1L_NM = math.log(_C1L_NM)
_C2_NM = _c.C2 * _c.NM_PER_M  # nm K, about 1.4388e7

# Planck's law per frequency: L_nu = (2 h / c^2) nu^3 / expm1(h nu / (k T)). nu^3 overflows
# float32 above 7e12 Hz, so nu is scaled to THz inside, and the factor 1e36 joins the constant.
_HZ_PER_THZ = 1e12
_C1L_THZ = 2.0 * _c.PLANCK / _c.SPEED_OF_LIGHT**2 * _HZ_PER_THZ**3  # W sr^-1 m^-2 Hz^-1 THz^-3
_LOG_C1L_THZ = math.log(_C1L_THZ)
_H_OVER_K = _c.PLANCK / _c.BOLTZMANN  # K s (K Hz^-1)

# Branch points of `_prefactor_over_expm1`, per dtype: exp(-x_s) < eps / 2, and exp(x_s)^2 (in
# the derivative of the direct form) is far from overflow (float32: exp(36) = 4e15).
_X_SWITCH_F64 = 37.0
_X_SWITCH_F32 = 18.0


_WIEN_FREQUENCY_DISPLACEMENT = _c.WIEN_FREQUENCY_DISPLACEMENT  # Hz K^-1
_WIEN_DISPLACEMENT_NM = _c.WIEN_DISPLACEMENT * _c.NM_PER_M  # nm K, about 2.8978e6


def _same_rank(a: Array, b: Array) -> tuple[Array, Array]:
    """`a` and `b` with leading unit axes added to the lower-rank one (NumPy broadcasting made
    explicit, so it also holds under `jax_numpy_rank_promotion="raise"`), shapes unchanged."""
    nd = max(a.ndim, b.ndim)
    return a.reshape((1,) * (nd - a.ndim) + a.shape), b.reshape((1,) * (nd - b.ndim) + b.shape)


def _prefactor_over_expm1(prefactor: Array, log_prefactor: Array, x: Array) -> Array:
    """`prefactor / expm1(x)` for x > 0, without overflow and with finite gradients.

    `log_prefactor` must equal `log(prefactor)`; it is used where `exp(x)` could overflow. The
    result has the broadcast shape of the three arguments.
    """
    dtype = jnp.result_type(prefactor, x)
    switch = _X_SWITCH_F64 if dtype == jnp.float64 else _X_SWITCH_F32
    small = x <= switch
    # The direct branch never sees a large x, the Wien one never a small x. (`where`, not
    # `minimum`/`maximum`: those pass half the gradient each way at a tie.)
    direct = prefactor / jnp.expm1(jnp.where(small, x, switch))
    # A e^-x / (1 - e^-x) with 1 - e^-x = 1 to the last bit past the switch; the exponent is
    # formed in log space so that a huge A times a tiny e^-x does not underflow early.
    wien = jnp.exp(log_prefactor - jnp.where(small, switch, x))
    return jnp.where(small, direct, wien)


@eqx.filter_jit  # compiled once per shape/dtype for eager callers; inlined under an outer jit
def _planck_nm(wavelength_nm: Array, temperature: Array) -> Array:
    wavelength_nm = check_positive(wavelength_nm, "wavelength_nm", "nm")
    temperature = check_positive(temperature, "temperature", "K")
    wavelength_nm, temperature = _same_rank(wavelength_nm, temperature)
    # Per wavelength, before broadcasting against the temperatures (see the module notes).
    prefactor = _C1L_NM * wavelength_nm**-5
    log_prefactor = _LOG_C1L_NM - 5.0 * jnp.log(wavelength_nm)
    # Second radiation constant term x = h c / (lambda k T) = c_2 / (lambda T)
    x = _C2_NM / (wavelength_nm * temperature)
    return _prefactor_over_expm1(prefactor, log_prefactor, x)


@eqx.filter_jit
def _planck_hz(frequency_hz: Array, temperature: Array) -> Array:
    frequency_hz = check_positive(frequency_hz, "frequency_hz", "Hz")
    temperature = check_positive(temperature, "temperature", "K")
    frequency_hz, temperature = _same_rank(frequency_hz, temperature)
    nu_thz = frequency_hz / _HZ_PER_THZ  # per frequency, before broadcasting
    prefactor = _C1L_THZ * nu_thz**3
    log_prefactor = _LOG_C1L_THZ + 3.0 * jnp.log(nu_thz)
    x = _H_OVER_K * frequency_hz / temperature  # x = h nu / (k T)
    return _prefactor_over_expm1(prefactor, log_prefactor, x)


def planck(wavelength_nm: FloatLike, temperature: FloatLike) -> Float[Array, "..."]:
    r"""Spectral radiance of a blackbody per unit wavelength (Planck's law).

    $$L_{bb,\lambda}(\lambda, T) = \frac{2 h c^2}{\lambda^5\left(e^{hc/(\lambda k T)} - 1\right)}$$

    with the exact SI-2019 constants of `radiometria.constants` (the thesis prints older CODATA
    values; see there). The result is a density per nanometre, so integrating it over a
    nanometre grid (`integrate_spectrum`) gives a radiance in W sr^-1 m^-2.

    **Arguments:**

    - `wavelength_nm`: wavelength in vacuum, > 0. [nm]
    - `temperature`: thermodynamic temperature, > 0. [K]

    The two arguments broadcast together. Python floats are accepted; integer arrays raise
    `TypeError` (convert them explicitly).

    **Returns:**

    Spectral radiance, >= 0, with the broadcast shape of the inputs. [W sr^-1 m^-2 nm^-1]

    Non-positive wavelengths or temperatures raise `equinox.EquinoxRuntimeError`, also under
    `equinox.filter_jit` (under a bare `jax.jit`, JAX reports the same message as a
    `jax.errors.JaxRuntimeError`). NaN inputs are not errors: they propagate to NaN outputs.

    Accuracy and range: for wavelengths from 1 nm to 1 mm and temperatures from 1 K to 1e6 K the
    result is finite, non-negative and never NaN in float32 and float64, and so are its
    gradients with respect to both arguments. Where the true radiance lies below the smallest
    representable number (deep in the Wien tail, e.g. 1 nm at 1 K), the result is exactly 0
    with gradient 0. The relative error is a few ulp times max(1, x), x = c_2 / (lambda T), which
    is the conditioning of the formula itself (measured against 50-digit decimal arithmetic on
    4000 log-uniform points of the domain: <= 4.2 eps max(1, x) in float32, <= 6 eps max(1, x)
    in float64).

    !!! note "Thesis"
        Thesis eq. (1.24), section 1.5.

    ??? cite "References"
        `Planck1901`; `CIE2018` (CIE 015:2018, section 3.1); `Pharr2023` section 4.4.1.
    """
    wavelength_nm = as_float_array(wavelength_nm, "wavelength_nm")
    temperature = as_float_array(temperature, "temperature")
    return _planck_nm(wavelength_nm, temperature)


def planck_frequency(frequency_hz: FloatLike, temperature: FloatLike) -> Float[Array, "..."]:
    r"""Spectral radiance of a blackbody per unit frequency (Planck's law in frequency).

    $$L_{bb,\nu}(\nu, T) = \frac{2 h \nu^3}{c^2\left(e^{h\nu/(k T)} - 1\right)}$$

    It is the same radiation as `planck`, as a density per hertz:
    $L_\nu = L_\lambda\, \lambda^2 / c$ at $\nu = c / \lambda$ (see
    `spectral_density_per_nm_to_per_hz`).

    **Arguments:**

    - `frequency_hz`: frequency, > 0. [Hz]
    - `temperature`: thermodynamic temperature, > 0. [K]

    **Returns:**

    Spectral radiance, >= 0, with the broadcast shape of the inputs. [W sr^-1 m^-2 Hz^-1]

    Errors, NaN handling and stability as for `planck`, over the frequencies of 1 nm to 1 mm
    (3e11 Hz to 3e17 Hz) and temperatures from 1 K to 1e6 K.

    !!! note "Thesis"
        Thesis section 1.5 (eq. (1.24) written per frequency, see its footnote 5 in section 1.4).

    ??? cite "References"
        `Planck1901`; `McCluney2014` section 2.
    """
    frequency_hz = as_float_array(frequency_hz, "frequency_hz")
    temperature = as_float_array(temperature, "temperature")
    return _planck_hz(frequency_hz, temperature)


def planck_exitance(wavelength_nm: FloatLike, temperature: FloatLike) -> Float[Array, "..."]:
    r"""Spectral radiant exitance of a blackbody, $M_{bb,\lambda} = \pi L_{bb,\lambda}$.

    A blackbody is a Lambertian emitter, so its exitance is its radiance integrated over the
    cosine-weighted hemisphere (which measures pi sr).

    **Arguments:**

    - `wavelength_nm`: wavelength in vacuum, > 0. [nm]
    - `temperature`: thermodynamic temperature, > 0. [K]

    **Returns:**

    Spectral exitance, >= 0. [W m^-2 nm^-1] Integrated over all wavelengths it gives
    `stefan_boltzmann_exitance(temperature)`.

    !!! note "Thesis"
        Thesis eq. (1.23) and (1.24), section 1.5.

    ??? cite "References"
        `McCluney2014` section 2.
    """
    return math.pi * planck(wavelength_nm, temperature)


def stefan_boltzmann_exitance(temperature: FloatLike) -> Float[Array, "..."]:
    r"""Total radiant exitance of a blackbody (Stefan-Boltzmann law), $M_{bb} = \sigma T^4$.

    **Arguments:**

    - `temperature`: thermodynamic temperature, > 0. [K]

    **Returns:**

    Radiant exitance. [W m^-2] The total radiance is this divided by pi.

    !!! note "Thesis"
        Thesis eq. (1.22), section 1.5 (with the exact sigma of `constants.STEFAN_BOLTZMANN`).

    ??? cite "References"
        `BIPM2019`; `McCluney2014` section 2.
    """
    temperature = check_positive(as_float_array(temperature, "temperature"), "temperature", "K")
    return _c.STEFAN_BOLTZMANN * temperature**4


def planck_peak_wavelength(temperature: FloatLike) -> Float[Array, "..."]:
    r"""Wavelength at which `planck` peaks (Wien's displacement law), $\lambda_{max} = b / T$.

    `b = constants.WIEN_DISPLACEMENT` = 2.897771955e-3 m K exactly (SI 2019).

    **Arguments:**

    - `temperature`: thermodynamic temperature, > 0. [K]

    **Returns:**

    Peak wavelength of the spectral radiance per unit wavelength. [nm]

    !!! note "Thesis"
        Thesis section 1.5 (the maximum of eq. (1.24) in wavelength).

    ??? cite "References"
        `Wien1896`; `Tiesinga2021` (CODATA 2018).
    """
    temperature = check_positive(as_float_array(temperature, "temperature"), "temperature", "K")
    return _WIEN_DISPLACEMENT_NM / temperature


def planck_peak_frequency(temperature: FloatLike) -> Float[Array, "..."]:
    r"""Frequency at which `planck_frequency` peaks, $\nu_{max} = b' T$.

    $b' = x_3 k / h$ = 5.878925757e10 Hz K^-1, where $x_3 \approx 2.8214$ solves
    $x = 3 (1 - e^{-x})$. Note $c / \nu_{max} \approx 1.76\,\lambda_{max}$: the peaks of the
    densities per wavelength and per frequency are at different places.

    **Arguments:**

    - `temperature`: thermodynamic temperature, > 0. [K]

    **Returns:**

    Peak frequency of the spectral radiance per unit frequency. [Hz]

    !!! note "Thesis"
        Thesis section 1.5 (the maximum of eq. (1.24) written per frequency).

    ??? cite "References"
        `Tiesinga2021` (CODATA 2018, Wien frequency displacement law constant).
    """
    temperature = check_positive(as_float_array(temperature, "temperature"), "temperature", "K")
    return _WIEN_FREQUENCY_DISPLACEMENT * temperature
