"""Relations between radiometric quantities that are closed formulas (thesis sections 1.1-1.4).

Radiance L [W sr^-1 m^-2], irradiance E and exitance M [W m^-2], intensity I [W sr^-1] and
flux Phi [W]; the same relations hold for their spectral densities per nm, and for the
photometric quantities (luminance, illuminance, luminous intensity, luminous flux) with the
photometric units. Angles are in radians; cosines are dimensionless.
"""

import math

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .. import constants as _c
from .._checks import (
    as_float_array,
    check_axis,
    check_broadcastable,
    check_in_range,
    check_positive,
)
from .._types import FloatLike

_HC = _c.PLANCK * _c.SPEED_OF_LIGHT  # J m
_C_NM = _c.SPEED_OF_LIGHT * _c.NM_PER_M  # nm s^-1 (nm Hz)


def _f(x, name: str) -> Array:
    return as_float_array(x, name)


def _cosine(cos_theta, name: str) -> Array:
    return check_in_range(_f(cos_theta, name), name, -1.0, 1.0)


# --- Waves and photons (sections 1.1-1.2) ------------------------------------------------------


def wavelength_to_frequency(wavelength_nm: FloatLike) -> Float[Array, "..."]:
    r"""Frequency of light of a given vacuum wavelength, $\nu = c / \lambda_0$.

    **Arguments:**

    - `wavelength_nm`: wavelength in vacuum, > 0. [nm]

    **Returns:**

    Frequency. [Hz] The inverse is `frequency_to_wavelength`.

    !!! note "Thesis"
        Thesis eq. (1.3), section 1.1.
    """
    wavelength_nm = check_positive(_f(wavelength_nm, "wavelength_nm"), "wavelength_nm", "nm")
    return _C_NM / wavelength_nm


def frequency_to_wavelength(frequency_hz: FloatLike) -> Float[Array, "..."]:
    r"""Vacuum wavelength of light of a given frequency, $\lambda_0 = c / \nu$.

    **Arguments:**

    - `frequency_hz`: frequency, > 0. [Hz]

    **Returns:**

    Wavelength in vacuum. [nm] The inverse is `wavelength_to_frequency`.

    !!! note "Thesis"
        Thesis eq. (1.3), section 1.1.
    """
    frequency_hz = check_positive(_f(frequency_hz, "frequency_hz"), "frequency_hz", "Hz")
    return _C_NM / frequency_hz


def photon_energy(wavelength_nm: FloatLike) -> Float[Array, "..."]:
    r"""Energy of one photon (Planck-Einstein relation), $Q = h\nu = hc/\lambda$.

    **Arguments:**

    - `wavelength_nm`: wavelength in vacuum, > 0. [nm]

    **Returns:**

    Photon energy. [J] (About 3.6e-19 J at 550 nm.)

    !!! note "Thesis"
        Thesis section 1.2 and section 1.4 (def. 1.4.1).
    """
    wavelength_nm = check_positive(_f(wavelength_nm, "wavelength_nm"), "wavelength_nm", "nm")
    return (_HC * _c.NM_PER_M) / wavelength_nm  # lambda in m = lambda_nm * 1e-9


def spectral_density_per_nm_to_per_hz(
    values_per_nm: FloatLike, wavelength_nm: FloatLike
) -> Float[Array, "..."]:
    r"""Convert a spectral density per wavelength into one per frequency.

    $$f_\nu = f_\lambda \left|\frac{\mathrm d\lambda}{\mathrm d\nu}\right|
            = f_\lambda\,\frac{\lambda^2}{c}$$

    so that `planck_frequency(wavelength_to_frequency(l), T)` equals
    `spectral_density_per_nm_to_per_hz(planck(l, T), l)`.

    **Arguments:**

    - `values_per_nm`: spectral density per nm at `wavelength_nm`. [quantity nm^-1]
    - `wavelength_nm`: vacuum wavelength at which the density is given, > 0. [nm]

    **Returns:**

    The density per Hz at the frequency $c / \lambda$. [quantity Hz^-1] The inverse is
    `spectral_density_per_hz_to_per_nm`.

    !!! note "Thesis"
        Thesis section 1.4, footnote 5 (spectral quantities per wavelength or per frequency).
    """
    values_per_nm = _f(values_per_nm, "values_per_nm")
    wavelength_nm = check_positive(_f(wavelength_nm, "wavelength_nm"), "wavelength_nm", "nm")
    # lambda^2 / c with lambda in nm and a density per nm: f_nm * lambda_nm * (lambda_nm / c_nm)
    return values_per_nm * wavelength_nm * (wavelength_nm / _C_NM)


def spectral_density_per_hz_to_per_nm(
    values_per_hz: FloatLike, frequency_hz: FloatLike
) -> Float[Array, "..."]:
    r"""Convert a spectral density per frequency into one per wavelength.

    $$f_\lambda = f_\nu \left|\frac{\mathrm d\nu}{\mathrm d\lambda}\right|
               = f_\nu\,\frac{\nu^2}{c}$$

    **Arguments:**

    - `values_per_hz`: spectral density per Hz at `frequency_hz`. [quantity Hz^-1]
    - `frequency_hz`: frequency at which the density is given, > 0. [Hz]

    **Returns:**

    The density per nm at the vacuum wavelength $c / \nu$. [quantity nm^-1] The inverse of
    `spectral_density_per_nm_to_per_hz`.

    !!! note "Thesis"
        Thesis section 1.4, footnote 5 (spectral quantities per wavelength or per frequency).
    """
    values_per_hz = _f(values_per_hz, "values_per_hz")
    frequency_hz = check_positive(_f(frequency_hz, "frequency_hz"), "frequency_hz", "Hz")
    # nu^2 / c with c in nm Hz: f_nu * nu * (nu / c_nm); no intermediate leaves float32 range
    return values_per_hz * frequency_hz * (frequency_hz / _C_NM)


def beer_lambert_transmittance(
    absorption_coefficient: FloatLike, distance: FloatLike
) -> Float[Array, "..."]:
    r"""Fraction of intensity left after a path through an absorbing medium, $e^{-\kappa_a z}$.

    **Arguments:**

    - `absorption_coefficient`: absorption coefficient $\kappa_a$, >= 0. [m^-1]
    - `distance`: path length $z$, >= 0. [m]

    **Returns:**

    Transmittance $I(z)/I_0$ in (0, 1]. [dimensionless] The penetration depth, where it is
    1/e, is $1/\kappa_a$.

    !!! note "Thesis"
        Thesis eq. (1.11)-(1.12), section 1.3.
    """
    kappa = _f(absorption_coefficient, "absorption_coefficient")
    kappa = check_in_range(kappa, "absorption_coefficient", 0.0, math.inf, unit="m^-1")
    distance = check_in_range(_f(distance, "distance"), "distance", 0.0, math.inf, unit="m")
    return jnp.exp(-kappa * distance)


# --- Energy and radiosity (section 1.4, table 1.2) ----------------------------------------------


def radiant_energy(
    flux: FloatLike,
    time_s: FloatLike | None = None,
    *,
    duration_s: FloatLike | None = None,
    axis: int = -1,
) -> Float[Array, "..."]:
    r"""Radiant energy delivered by a flux over time, $Q_e = \int \Phi_e(t)\,\mathrm dt$.

    The flux is the time derivative of the energy, $\Phi_e = \partial Q_e/\partial t$ (def.
    1.4.3), so the energy is its time integral. Give exactly one of:

    - `time_s`: the sample times of a flux sampled along `axis`; the integral is the trapezoid
        rule over them (nothing is assumed before the first or after the last sample);
    - `duration_s`: an exposure time $\Delta t$ for a constant flux, $Q_e = \Phi_e\,\Delta t$
        (elementwise, broadcasting with `flux`).

    **Arguments:**

    - `flux`: radiant flux $\Phi_e$. [W] (or its spectral density [W nm^-1], or luminous
        flux [lm])
    - `time_s`: strictly increasing sample times (n,), with n = `flux.shape[axis]` >= 2. [s]
    - `duration_s`: duration $\Delta t$ of a constant flux, >= 0. [s]
    - `axis`: the time axis of `flux` when `time_s` is given (static int).

    **Returns:**

    Radiant energy $Q_e$, with `axis` removed when integrating samples. [J] (or [J nm^-1], or
    luminous energy [lm s])

    Both or neither of `time_s` and `duration_s`, or a `time_s` that does not match `flux`,
    raise `ValueError`; decreasing times or a negative duration raise
    `equinox.EquinoxRuntimeError` (also under `jax.jit`).

    !!! note "Thesis"
        Thesis table 1.2 and def. 1.4.1, 1.4.3, section 1.4.

    ??? cite "References"
        `McCluney2014` (the radiometric quantities and their names).
    """
    flux = _f(flux, "flux")
    if (time_s is None) == (duration_s is None):
        raise ValueError("Give exactly one of `time_s` (sample times [s]) or `duration_s` [s].")
    if duration_s is not None:
        duration_s = _f(duration_s, "duration_s")
        duration_s = check_in_range(duration_s, "duration_s", 0.0, math.inf, unit="s")
        check_broadcastable(("flux", flux), ("duration_s", duration_s))
        flux, duration_s = jnp.broadcast_arrays(flux, duration_s)
        return flux * duration_s
    time_s = _f(time_s, "time_s")
    axis = check_axis(axis, flux.ndim, "axis") if flux.ndim else axis
    if flux.ndim == 0 or time_s.ndim != 1 or time_s.shape[0] != flux.shape[axis]:
        raise ValueError(
            f"`time_s` must be 1-D with one time per sample of `flux` along axis {axis} "
            f"[s]; got `time_s` {time_s.shape} and `flux` {flux.shape}."
        )
    if time_s.shape[0] < 2:
        raise ValueError(f"`time_s` needs >= 2 sample times [s], got {time_s.shape[0]}.")
    step = jnp.diff(time_s)
    step = eqx.error_if(step, step <= 0, "`time_s` must be strictly increasing [s].")
    flux = jnp.moveaxis(flux, axis, -1)
    # trapezoid rule: sum_i (t_{i+1} - t_i) (Phi_i + Phi_{i+1}) / 2
    step = jnp.broadcast_to(step, flux.shape[:-1] + step.shape)
    return 0.5 * jnp.sum(step * (flux[..., 1:] + flux[..., :-1]), axis=-1)


def radiosity(
    emitted_exitance: FloatLike,
    reflected_exitance: FloatLike = 0.0,
    transmitted_exitance: FloatLike = 0.0,
) -> Float[Array, "..."]:
    r"""Radiosity: all the flux per unit area leaving a surface, $J_e = M_e + M_r + M_t$.

        Radiosity counts what a surface emits (its radiant exitance $M_e$), what it reflects and
        what it transmits from the other side, per unit area; with nothing reflected or transmitted
        it is the exitance. For a Lambertian surface of reflectance $
    ho$ lit by irradiance $E$,
        $M_r =
    ho E$ (the radiosity method of `Goral1984`).

        **Arguments:**

        - `emitted_exitance`: radiant exitance $M_e$ of the surface's own emission, >= 0. [W m^-2]
        - `reflected_exitance`: reflected flux per unit area, >= 0; default 0. [W m^-2]
        - `transmitted_exitance`: flux transmitted through the surface per unit area, leaving it on
            the same side, >= 0; default 0. [W m^-2]

        The three broadcast together; the same holds for their spectral densities [W m^-2 nm^-1]
        and for the photometric analogue, luminous exitance [lm m^-2].

        **Returns:**

        Radiosity $J_e$. [W m^-2]

        !!! note "Thesis"
            Thesis table 1.2 and def. 1.4.4, section 1.4.

        ??? cite "References"
            `McCluney2014`; `Goral1984` (radiosity in rendering).
    """
    parts = []
    for name, x in (
        ("emitted_exitance", emitted_exitance),
        ("reflected_exitance", reflected_exitance),
        ("transmitted_exitance", transmitted_exitance),
    ):
        parts.append(check_in_range(_f(x, name), name, 0.0, math.inf, unit="W m^-2"))
    names = ("emitted_exitance", "reflected_exitance", "transmitted_exitance")
    check_broadcastable(*zip(names, parts, strict=True))
    emitted, reflected, transmitted = jnp.broadcast_arrays(*parts)
    return emitted + reflected + transmitted


# --- Radiance, irradiance, exitance, intensity (section 1.4) ------------------------------------


def irradiance_from_radiance(
    radiance: FloatLike, half_angle: FloatLike = math.pi / 2
) -> Float[Array, "..."]:
    r"""Irradiance from a uniform radiance arriving within a cone around the normal.

    Eq. (1.13) with constant $L$ over the cone $\theta \le \theta_0$:

    $$E = \int_0^{2\pi}\!\!\int_0^{\theta_0} L \cos\theta\sin\theta\,\mathrm d\theta\,
          \mathrm d\varphi = \pi L \sin^2\theta_0$$

    and over the whole hemisphere ($\theta_0 = \pi/2$, the default) $E = \pi L$.

    **Arguments:**

    - `radiance`: the uniform incident radiance. [W sr^-1 m^-2] (or its spectral density,
        [W sr^-1 m^-2 nm^-1], or luminance [cd m^-2])
    - `half_angle`: half-angle $\theta_0$ of the cone, in [0, pi/2]. [rad]

    **Returns:**

    Irradiance. [W m^-2] (or [W m^-2 nm^-1], or illuminance [lx])

    !!! note "Thesis"
        Thesis eq. (1.13), section 1.4.
    """
    radiance = _f(radiance, "radiance")
    half_angle = check_in_range(
        _f(half_angle, "half_angle"), "half_angle", 0.0, math.pi / 2, unit="rad"
    )
    return math.pi * radiance * jnp.sin(half_angle) ** 2


def radiance_from_irradiance(
    irradiance: FloatLike, half_angle: FloatLike = math.pi / 2
) -> Float[Array, "..."]:
    r"""Uniform radiance that gives an irradiance within a cone, $L = E / (\pi\sin^2\theta_0)$.

    The inverse of `irradiance_from_radiance`.

    **Arguments:**

    - `irradiance`: irradiance. [W m^-2]
    - `half_angle`: half-angle $\theta_0$ of the cone, in (0, pi/2]. [rad]

    **Returns:**

    Radiance. [W sr^-1 m^-2]

    !!! note "Thesis"
        Thesis eq. (1.13), section 1.4.
    """
    irradiance = _f(irradiance, "irradiance")
    half_angle = check_in_range(
        _f(half_angle, "half_angle"), "half_angle", 0.0, math.pi / 2, unit="rad", closed_lower=False
    )
    return irradiance / (math.pi * jnp.sin(half_angle) ** 2)


def exitance_from_radiance(radiance: FloatLike) -> Float[Array, "..."]:
    r"""Exitance of a Lambertian emitter of uniform radiance, $M = \pi L$.

    **Arguments:**

    - `radiance`: the emitted radiance, the same in every direction. [W sr^-1 m^-2] (or its
        spectral density [W sr^-1 m^-2 nm^-1])

    **Returns:**

    Radiant exitance. [W m^-2] (or [W m^-2 nm^-1]) The inverse is `radiance_from_exitance`.

    !!! note "Thesis"
        Thesis eq. (1.23), section 1.5 (and def. 1.4.7, section 1.4.1).
    """
    return math.pi * _f(radiance, "radiance")


def radiance_from_exitance(exitance: FloatLike) -> Float[Array, "..."]:
    r"""Radiance of a Lambertian emitter of given exitance, $L = M / \pi$.

    **Arguments:**

    - `exitance`: radiant exitance. [W m^-2]

    **Returns:**

    Radiance, the same in every direction. [W sr^-1 m^-2]

    !!! note "Thesis"
        Thesis eq. (1.23), section 1.5.
    """
    return _f(exitance, "exitance") / math.pi


def intensity_from_flux(flux: FloatLike) -> Float[Array, "..."]:
    r"""Intensity of an isotropic point source, $I = \Phi / (4\pi)$.

    **Arguments:**

    - `flux`: total radiant flux of the source. [W] (or luminous flux [lm])

    **Returns:**

    Radiant intensity, the same in every direction. [W sr^-1] (or [cd]) The inverse is
    `flux_from_intensity`.

    !!! note "Thesis"
        Thesis section 1.4 (def. 1.4.5).
    """
    return _f(flux, "flux") / (4.0 * math.pi)


def flux_from_intensity(intensity: FloatLike) -> Float[Array, "..."]:
    r"""Total flux of an isotropic point source, $\Phi = 4\pi I$.

    **Arguments:**

    - `intensity`: radiant intensity, the same in every direction. [W sr^-1]

    **Returns:**

    Radiant flux. [W]

    !!! note "Thesis"
        Thesis section 1.4 (def. 1.4.5).
    """
    return 4.0 * math.pi * _f(intensity, "intensity")


def irradiance_from_intensity(
    intensity: FloatLike, distance: FloatLike, cos_theta: FloatLike = 1.0
) -> Float[Array, "..."]:
    r"""Irradiance from a point source: inverse-square law with Lambert's cosine factor.

    $$E = \frac{I \max(\cos\theta, 0)}{d^2}$$

    **Arguments:**

    - `intensity`: radiant intensity of the source towards the receiver. [W sr^-1] (or [cd])
    - `distance`: distance from the source to the receiving point, > 0. [m]
    - `cos_theta`: cosine of the angle between the receiver's normal and the direction to the
        source, in [-1, 1]. A source behind the surface (cos < 0) gives 0. [dimensionless]

    **Returns:**

    Irradiance at the receiver. [W m^-2] (or illuminance [lx])

    !!! note "Thesis"
        Thesis section 1.4 (def. 1.4.5: falloff with the squared distance) and section 1.4.1
        (def. 1.4.7, footnote 8: $E = E_0\cos\theta$).
    """
    intensity = _f(intensity, "intensity")
    distance = check_positive(_f(distance, "distance"), "distance", "m")
    cos_theta = jnp.maximum(_cosine(cos_theta, "cos_theta"), 0.0)
    return intensity * cos_theta / distance**2


def lambert_intensity(intensity_normal: FloatLike, cos_theta: FloatLike) -> Float[Array, "..."]:
    r"""Lambert's cosine law for a flat Lambertian radiator, $I(\theta) = I_0 \max(\cos\theta, 0)$.

    For a small flat patch of area $A$ and radiance $L$, $I_0 = L A$.

    **Arguments:**

    - `intensity_normal`: intensity $I_0$ along the normal. [W sr^-1] (or [cd])
    - `cos_theta`: cosine of the angle between the normal and the direction of observation,
        in [-1, 1]. Directions behind the surface (cos < 0) receive nothing. [dimensionless]

    **Returns:**

    Intensity in that direction. [W sr^-1] (or [cd])

    !!! note "Thesis"
        Thesis section 1.4.1 (def. 1.4.7).
    """
    cos_theta = jnp.maximum(_cosine(cos_theta, "cos_theta"), 0.0)
    return _f(intensity_normal, "intensity_normal") * cos_theta


def etendue(
    area_source: FloatLike,
    cos_theta_source: FloatLike,
    area_receiver: FloatLike,
    cos_theta_receiver: FloatLike,
    distance: FloatLike,
    eta: FloatLike = 1.0,
) -> Float[Array, "..."]:
    r"""Etendue of the beam between two small patches.

    $$G = \frac{\eta^2\, A_s\cos\theta_s\, A_r\cos\theta_r}{d^2}$$

    Symmetric in source and receiver (etendue is conserved), and so is the throughput of
    radiance: the flux from source to receiver is $\Phi = (L / \eta^2)\, G$.

    **Arguments:**

    - `area_source`, `area_receiver`: areas of the two patches, >= 0. [m^2]
    - `cos_theta_source`, `cos_theta_receiver`: cosines between each patch's normal and the line
        joining them, in [-1, 1]; a patch facing away (cos < 0) gives 0. [dimensionless]
    - `distance`: distance between the patches, > 0. [m]
    - `eta`: refractive index of the (homogeneous, lossless) medium between them, > 0.
        [dimensionless]

    **Returns:**

    Etendue. [m^2 sr]

    !!! note "Thesis"
        Thesis section 1.4.1 (def. 1.4.8).
    """
    area_source = check_in_range(
        _f(area_source, "area_source"), "area_source", 0.0, math.inf, unit="m^2"
    )
    area_receiver = check_in_range(
        _f(area_receiver, "area_receiver"), "area_receiver", 0.0, math.inf, unit="m^2"
    )
    cos_s = jnp.maximum(_cosine(cos_theta_source, "cos_theta_source"), 0.0)
    cos_r = jnp.maximum(_cosine(cos_theta_receiver, "cos_theta_receiver"), 0.0)
    distance = check_positive(_f(distance, "distance"), "distance", "m")
    eta = check_positive(_f(eta, "eta"), "eta")
    return eta**2 * (area_source * cos_s) * (area_receiver * cos_r) / distance**2


def basic_radiance(radiance: FloatLike, eta: FloatLike) -> Float[Array, "..."]:
    r"""Basic radiance $L / \eta^2$, the quantity conserved along a ray across media.

    Across an interface (without reflection losses) $L_o/\eta_1^2 = L_i/\eta_2^2$, so the
    radiance in the second medium is `radiance_from_basic_radiance(basic_radiance(L, eta_1),
    eta_2)`.

    **Arguments:**

    - `radiance`: radiance in a medium of refractive index `eta`. [W sr^-1 m^-2]
    - `eta`: refractive index, > 0. [dimensionless]

    **Returns:**

    Basic radiance. [W sr^-1 m^-2] The inverse is `radiance_from_basic_radiance`.

    !!! note "Thesis"
        Thesis eq. (1.14)-(1.15), eq. (1.21), section 1.4.1 and section 1.4.2.
    """
    eta = check_positive(_f(eta, "eta"), "eta")
    return _f(radiance, "radiance") / eta**2


def radiance_from_basic_radiance(basic: FloatLike, eta: FloatLike) -> Float[Array, "..."]:
    r"""Radiance in a medium of refractive index $\eta$ from the basic radiance, $L = \eta^2 L_b$.

    **Arguments:**

    - `basic`: basic radiance $L/\eta^2$. [W sr^-1 m^-2]
    - `eta`: refractive index of the medium, > 0. [dimensionless]

    **Returns:**

    Radiance. [W sr^-1 m^-2]

    !!! note "Thesis"
        Thesis eq. (1.15), eq. (1.21), section 1.4.2.
    """
    eta = check_positive(_f(eta, "eta"), "eta")
    return _f(basic, "basic") * eta**2
