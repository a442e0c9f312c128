r"""Monochromatic waves in vacuum and in a medium (thesis section 1.1, eq. 1.1-1.6).

A monochromatic wave of frequency $\nu$ has period $T = 1/\nu$ (eq. 1.1), angular frequency
$\omega = 2\pi\nu$ (eq. 1.2), vacuum wavelength $\lambda_0 = cT = c/\nu$ (eq. 1.3) and, in a
medium where its phase velocity is $v$, wavelength $\lambda = vT = v/\nu$ (eq. 1.4). The angular
wavenumbers are $k_0 = 2\pi/\lambda_0 = \omega/c$ (eq. 1.5) and $k = 2\pi/\lambda = \omega/v$
(eq. 1.6). The refractive index relates the two media,

$$\eta = \sqrt{\mu_r\epsilon_r} = \frac{c}{v} = \frac{k}{k_0} = \frac{\lambda_0}{\lambda},$$

with $\epsilon_0 = 1/(\mu_0 c^2)$ (`constants.VACUUM_PERMITTIVITY`). The frequency does not
change across media; wavelength, wavenumber and phase velocity do.

Here $\eta$ is real and positive (a lossless, isotropic medium); absorbing media with a complex
index are handled by `scattering.fresnel_conductor`. Wavelengths are in nm at the boundary
(style.md section 4), every other quantity is SI: wavenumbers in rad m^-1, velocities in m s^-1.
The conversion from vacuum wavelength to frequency is `wavelength_to_frequency` (eq. 1.3).
"""

import math

from jaxtyping import Array, Float

from .. import constants as _c
from .._checks import as_float_array, check_positive
from .._math import safe_sqrt
from .._types import FloatLike


def _positive(x, name: str, unit: str = "") -> Array:
    return check_positive(as_float_array(x, name), name, unit)


# --- Time: period and angular frequency (eq. 1.1-1.2) -------------------------------------------


def period(frequency_hz: FloatLike) -> Float[Array, "..."]:
    r"""Period of a monochromatic wave, $T = 1/\nu$.

    **Arguments:**

    - `frequency_hz`: frequency $\nu$, > 0. [Hz]

    **Returns:**

    Period $T$. [s] (About 1.8e-15 s for green light, 545 THz.) The inverse is
    `frequency_from_period`.

    !!! note "Thesis"
        Thesis eq. (1.1), section 1.1.

    ??? cite "References"
        `Born1999` §1.3.
    """
    return 1.0 / _positive(frequency_hz, "frequency_hz", "Hz")


def frequency_from_period(period_s: FloatLike) -> Float[Array, "..."]:
    r"""Frequency of a monochromatic wave of period $T$, $\nu = 1/T$.

    **Arguments:**

    - `period_s`: period $T$, > 0. [s]

    **Returns:**

    Frequency $\nu$. [Hz] The inverse is `period`.

    !!! note "Thesis"
        Thesis eq. (1.1), section 1.1.

    ??? cite "References"
        `Born1999` §1.3.
    """
    return 1.0 / _positive(period_s, "period_s", "s")


def angular_frequency(frequency_hz: FloatLike) -> Float[Array, "..."]:
    r"""Angular frequency of a monochromatic wave, $\omega = 2\pi\nu = 2\pi/T$.

    **Arguments:**

    - `frequency_hz`: frequency $\nu$, > 0. [Hz]

    **Returns:**

    Angular frequency $\omega$. [rad s^-1] The inverse is `frequency_from_angular_frequency`.

    !!! note "Thesis"
        Thesis eq. (1.2), section 1.1.

    ??? cite "References"
        `Born1999` §1.3.
    """
    return 2.0 * math.pi * _positive(frequency_hz, "frequency_hz", "Hz")


def frequency_from_angular_frequency(omega: FloatLike) -> Float[Array, "..."]:
    r"""Frequency from the angular frequency, $\nu = \omega / (2\pi)$.

    **Arguments:**

    - `omega`: angular frequency $\omega$, > 0. [rad s^-1]

    **Returns:**

    Frequency $\nu$. [Hz] The inverse is `angular_frequency`.

    !!! note "Thesis"
        Thesis eq. (1.2), section 1.1.

    ??? cite "References"
        `Born1999` §1.3.
    """
    return _positive(omega, "omega", "rad s^-1") / (2.0 * math.pi)


# --- The medium: refractive index and phase velocity ---------------------------------------------


def refractive_index_from_permittivity(
    eps_r: FloatLike, mu_r: FloatLike = 1.0
) -> Float[Array, "..."]:
    r"""Refractive index of a lossless medium, $\eta = \sqrt{\mu_r\epsilon_r}$.

    $\epsilon_r = \epsilon/\epsilon_0$ and $\mu_r = \mu/\mu_0$ are the relative permittivity and
    permeability; since $\epsilon_0\mu_0 = 1/c^2$ and $\epsilon\mu = 1/v^2$, this equals
    $c/v$. Optical media are non-magnetic to a good approximation ($\mu_r = 1$, the default),
    so $\eta = \sqrt{\epsilon_r}$ (Maxwell's relation), with $\epsilon_r$ taken at the optical
    frequency (for water about 1.78, not the static 80).

    **Arguments:**

    - `eps_r`: relative permittivity $\epsilon_r$ at the wave's frequency, > 0. [dimensionless]
    - `mu_r`: relative permeability $\mu_r$, > 0; default 1. [dimensionless]

    **Returns:**

    Refractive index $\eta$, > 0. [dimensionless] Negative or complex permittivities (metals,
    absorbing media) are outside this real-valued relation and raise.

    !!! note "Thesis"
        Thesis section 1.1 (the refractive index after eq. 1.6).

    ??? cite "References"
        `Born1999` §1.2 (Maxwell's relation $n = \sqrt{\epsilon\mu}$); `Hecht2002` §3.5.
    """
    eps_r = _positive(eps_r, "eps_r")
    mu_r = _positive(mu_r, "mu_r")
    # eta = sqrt(mu_r eps_r); the double-where sqrt keeps gradients finite at the error edge
    return safe_sqrt(mu_r * eps_r, propagate_nan=True)


def phase_velocity(eta: FloatLike) -> Float[Array, "..."]:
    r"""Phase velocity of light in a medium of refractive index $\eta$, $v = c/\eta$.

    **Arguments:**

    - `eta`: refractive index $\eta$, > 0. [dimensionless]

    **Returns:**

    Phase velocity $v$. [m s^-1] The inverse is `refractive_index_from_phase_velocity`.

    !!! note "Thesis"
        Thesis section 1.1 ($\eta = c/v$, after eq. 1.6).

    ??? cite "References"
        `Born1999` §1.2; `Hecht2002` §3.5.
    """
    return _c.SPEED_OF_LIGHT / _positive(eta, "eta")


def refractive_index_from_phase_velocity(velocity: FloatLike) -> Float[Array, "..."]:
    r"""Refractive index of a medium in which light has phase velocity $v$, $\eta = c/v$.

    **Arguments:**

    - `velocity`: phase velocity $v$, > 0. [m s^-1]

    **Returns:**

    Refractive index $\eta$. [dimensionless] The inverse is `phase_velocity`.

    !!! note "Thesis"
        Thesis section 1.1 ($\eta = c/v$, after eq. 1.6).

    ??? cite "References"
        `Born1999` §1.2.
    """
    return _c.SPEED_OF_LIGHT / _positive(velocity, "velocity", "m s^-1")


# --- Space: wavelength and wavenumber in vacuum and in a medium (eq. 1.3-1.6) -------------------


def wavelength_in_medium_nm(wavelength_nm: FloatLike, eta: FloatLike) -> Float[Array, "..."]:
    r"""Wavelength in a medium of refractive index $\eta$, $\lambda = vT = \lambda_0/\eta$.

    **Arguments:**

    - `wavelength_nm`: wavelength in vacuum $\lambda_0$, > 0. [nm]
    - `eta`: refractive index $\eta$ of the medium, > 0. [dimensionless]

    **Returns:**

    Wavelength $\lambda$ in the medium. [nm] The inverse is `wavelength_in_vacuum_nm`.

    !!! note "Thesis"
        Thesis eq. (1.3)-(1.4), section 1.1.

    ??? cite "References"
        `Born1999` §1.3.3; `Hecht2002` §3.5.
    """
    wavelength_nm = _positive(wavelength_nm, "wavelength_nm", "nm")
    return wavelength_nm / _positive(eta, "eta")


def wavelength_in_vacuum_nm(wavelength_medium_nm: FloatLike, eta: FloatLike) -> Float[Array, "..."]:
    r"""Vacuum wavelength of light of wavelength $\lambda$ in a medium, $\lambda_0 = \eta\lambda$.

    **Arguments:**

    - `wavelength_medium_nm`: wavelength $\lambda$ in the medium, > 0. [nm]
    - `eta`: refractive index $\eta$ of the medium, > 0. [dimensionless]

    **Returns:**

    Wavelength in vacuum $\lambda_0$. [nm] The inverse of `wavelength_in_medium_nm`.

    !!! note "Thesis"
        Thesis eq. (1.3)-(1.4), section 1.1.

    ??? cite "References"
        `Born1999` §1.3.3.
    """
    wavelength_medium_nm = _positive(wavelength_medium_nm, "wavelength_medium_nm", "nm")
    return _positive(eta, "eta") * wavelength_medium_nm


def wavenumber_vacuum(wavelength_nm: FloatLike) -> Float[Array, "..."]:
    r"""Angular wavenumber in vacuum, $k_0 = 2\pi/\lambda_0 = 2\pi\nu/c = \omega/c$.

    **Arguments:**

    - `wavelength_nm`: wavelength in vacuum $\lambda_0$, > 0. [nm]

    **Returns:**

    Angular wavenumber $k_0$. [rad m^-1] (About 1.14e7 rad m^-1 at 550 nm.) The inverse is
    `wavelength_from_wavenumber`.

    !!! note "Thesis"
        Thesis eq. (1.5), section 1.1.

    ??? cite "References"
        `Born1999` §1.3.3.
    """
    wavelength_nm = _positive(wavelength_nm, "wavelength_nm", "nm")
    # k_0 = 2 pi / lambda_0 with lambda_0 in m = lambda_nm * 1e-9
    return (2.0 * math.pi * _c.NM_PER_M) / wavelength_nm


def wavelength_from_wavenumber(k0: FloatLike) -> Float[Array, "..."]:
    r"""Vacuum wavelength from the angular wavenumber in vacuum, $\lambda_0 = 2\pi/k_0$.

    With a wavenumber $k$ measured in a medium this gives the wavelength $\lambda = 2\pi/k$ in
    that medium instead.

    **Arguments:**

    - `k0`: angular wavenumber $k_0$, > 0. [rad m^-1]

    **Returns:**

    Wavelength $\lambda_0$. [nm] The inverse of `wavenumber_vacuum`.

    !!! note "Thesis"
        Thesis eq. (1.5)-(1.6), section 1.1.

    ??? cite "References"
        `Born1999` §1.3.3.
    """
    k0 = _positive(k0, "k0", "rad m^-1")
    # lambda_0 = 2 pi / k_0 in m, times 1e9 for nm
    return (2.0 * math.pi * _c.NM_PER_M) / k0


def wavenumber_in_medium(wavelength_nm: FloatLike, eta: FloatLike) -> Float[Array, "..."]:
    r"""Angular wavenumber in a medium, $k = 2\pi/\lambda = \omega/v = \eta k_0$.

    **Arguments:**

    - `wavelength_nm`: wavelength in vacuum $\lambda_0$ (the same light's wavelength outside
        the medium), > 0. [nm]
    - `eta`: refractive index $\eta$ of the medium, > 0. [dimensionless]

    **Returns:**

    Angular wavenumber $k$ in the medium. [rad m^-1] Together with the direction of
    propagation $\hat k$ it makes the wave vector $\vec k = k\hat k$.

    !!! note "Thesis"
        Thesis eq. (1.6), section 1.1 (and $\eta = k/k_0$).

    ??? cite "References"
        `Born1999` §1.3.3.
    """
    k0 = wavenumber_vacuum(wavelength_nm)
    return _positive(eta, "eta") * k0
