r"""Optical properties of surfaces and layers (thesis section 3.1, eq. 3.2, table 3.1, glossary).

The thesis follows the CIE vocabulary (`CIE2020`): properties ending in *-ance* (reflectance
$\rho$, transmittance $\tau$, absorptance $\alpha$) belong to an object under a given incident
spectrum, polarisation and geometry; those ending in *-ivity* belong to the material:

| function | quantity | thesis |
|---|---|---|
| `absorptance(reflectance, transmittance)` | $\alpha = 1 - \rho - \tau$ | eq. 3.2 |
| `flux_weighted_reflectance`, `_transmittance`, `_absorptance` | $\Phi^r/\Phi^i$ etc. | tab. 3.1 |
| `slab_reflectance_transmittance(r, tau_i)` | $\rho, \tau, \alpha$ of a layer | glossary |
| `reflectivity_kubelka1931(K, S)` | $\rho_\infty$, thick scattering layer | glossary |
| `transmissivity(kappa_a)`, `absorptivity(kappa_a)` | $\tau_u$, $\alpha_u$, unit path | glossary |

The internal transmittance of a path of length $z$ is Beer-Lambert's $e^{-\kappa_a z}$
(`radiometria.radiometry.beer_lambert_transmittance`, thesis eq. 1.12).
"""

import math

import equinox as eqx
import jax.numpy as jnp
from jax import Array

from .._checks import as_float_array, check_in_range
from .._math import align_ranks, safe_div
from ..radiometry import beer_lambert_transmittance, integrate_spectrum

__all__ = [
    "absorptance",
    "absorptivity",
    "flux_weighted_absorptance",
    "flux_weighted_reflectance",
    "flux_weighted_transmittance",
    "reflectivity_kubelka1931",
    "slab_reflectance_transmittance",
    "transmissivity",
]

# Rounding slack for rho + tau <= 1 (sums of values computed in float64 or float32).
_SUM_TOL = 1e-6


def _fraction(x, name: str) -> Array:
    return check_in_range(as_float_array(x, name), name, 0.0, 1.0, unit="dimensionless")


def absorptance(reflectance, transmittance) -> Array:
    r"""Absorptance from energy conservation, $\alpha = 1 - \rho - \tau$ (thesis eq. 3.2).

    $$\alpha + \rho + \tau = 1$$

    Spectral or total, for the same incident radiation and geometry (the -ance quantities of
    table 3.1).

    **Arguments:**

    - `reflectance`: $\rho$ in [0, 1]. [dimensionless]
    - `transmittance`: $\tau$ in [0, 1], broadcasting with `reflectance`; $\rho + \tau \le 1$
        (checked, with a rounding slack of 1e-6; the result is clipped at 0). [dimensionless]

    **Returns:**

    $\alpha$ in [0, 1]. [dimensionless]

    !!! note "Thesis"
        Eq. (3.2), section 3.1.

    ??? cite "References"
        `CIE2020` (absorptance, reflectance, transmittance).
    """
    rho = _fraction(reflectance, "reflectance")
    tau = _fraction(transmittance, "transmittance")
    rho, tau = align_ranks(rho, tau)
    total = rho + tau
    total = eqx.error_if(
        total,
        total > 1.0 + _SUM_TOL,
        "`reflectance` + `transmittance` must be <= 1 [dimensionless] (thesis eq. 3.2).",
    )
    return jnp.maximum(1.0 - total, 0.0)


def _flux_weighted(values, incident_spectrum, wavelengths_nm, name: str) -> Array:
    x = _fraction(values, name)
    phi = as_float_array(incident_spectrum, "incident_spectrum")
    phi = eqx.error_if(phi, phi < 0, "`incident_spectrum` must be >= 0 [W nm^-1]; got a value < 0.")
    x, phi = align_ranks(x, phi)
    try:
        shape = jnp.broadcast_shapes(x.shape, phi.shape)
    except ValueError:
        raise ValueError(
            f"`{name}` {x.shape} and `incident_spectrum` {phi.shape} do not broadcast."
        ) from None
    x, phi = jnp.broadcast_to(x, shape), jnp.broadcast_to(phi, shape)
    num = integrate_spectrum(x * phi, wavelengths_nm)
    den = integrate_spectrum(phi, wavelengths_nm)
    den = eqx.error_if(den, den <= 0, "`incident_spectrum` must have a positive integral.")
    return num / den


def flux_weighted_reflectance(reflectance, incident_spectrum, wavelengths_nm) -> Array:
    r"""Flux-weighted (total) reflectance for a given incident spectrum (thesis table 3.1).

    $$\rho = \frac{\Phi^r}{\Phi^i} =
      \frac{\int \rho_\lambda(\lambda)\,\Phi^i_\lambda(\lambda)\,d\lambda}
           {\int \Phi^i_\lambda(\lambda)\,d\lambda}
      \ne \int \rho_\lambda(\lambda)\,d\lambda$$

    The total reflectance depends on the incident spectrum, not only on the material: the same
    surface has different values under different illuminants. Both integrals use the trapezoid
    rule on the given grid (`radiometria.radiometry.integrate_spectrum`), so only the range of
    the grid counts.

    **Arguments:**

    - `reflectance`: spectral reflectance $\rho_\lambda$ in [0, 1], wavelengths on the last
        axis. [dimensionless]
    - `incident_spectrum`: spectral incident flux $\Phi^i_\lambda \ge 0$ (or any spectral
        density proportional to it, e.g. the irradiance for a fixed geometry), broadcasting with
        `reflectance`, with a positive integral. [W nm^-1, or any unit nm^-1]
    - `wavelengths_nm`: the grid, strictly increasing, `(n,)`. [nm]

    **Returns:**

    $\rho$ in [0, 1], with the wavelength axis removed. [dimensionless]

    !!! note "Thesis"
        Table 3.1 ("Reflectance"), section 3.1.

    ??? cite "References"
        `CIE2020` (reflectance).
    """
    return _flux_weighted(reflectance, incident_spectrum, wavelengths_nm, "reflectance")


def flux_weighted_transmittance(transmittance, incident_spectrum, wavelengths_nm) -> Array:
    r"""Flux-weighted (total) transmittance for a given incident spectrum (thesis table 3.1).

    $$\tau = \frac{\Phi^t}{\Phi^i} =
      \frac{\int \tau_\lambda(\lambda)\,\Phi^i_\lambda(\lambda)\,d\lambda}
           {\int \Phi^i_\lambda(\lambda)\,d\lambda}$$

    As `flux_weighted_reflectance`, for the transmitted flux.

    **Arguments:**

    - `transmittance`: spectral transmittance $\tau_\lambda$ in [0, 1], wavelengths on the
        last axis. [dimensionless]
    - `incident_spectrum`: spectral incident flux $\Phi^i_\lambda \ge 0$, broadcasting with
        `transmittance`. [W nm^-1, or any unit nm^-1]
    - `wavelengths_nm`: the grid, strictly increasing, `(n,)`. [nm]

    **Returns:**

    $\tau$ in [0, 1], with the wavelength axis removed. [dimensionless]

    !!! note "Thesis"
        Table 3.1 ("Transmittance"), section 3.1.

    ??? cite "References"
        `CIE2020` (transmittance).
    """
    return _flux_weighted(transmittance, incident_spectrum, wavelengths_nm, "transmittance")


def flux_weighted_absorptance(absorptance, incident_spectrum, wavelengths_nm) -> Array:
    r"""Flux-weighted (total) absorptance for a given incident spectrum (thesis table 3.1).

    $$\alpha = \frac{\Phi^a}{\Phi^i} =
      \frac{\int \alpha_\lambda(\lambda)\,\Phi^i_\lambda(\lambda)\,d\lambda}
           {\int \Phi^i_\lambda(\lambda)\,d\lambda}$$

    (the thesis's table prints $\rho_\lambda$ in the numerator, a misprint for
    $\alpha_\lambda$). Being linear in the spectral quantity, the three flux-weighted values
    obey eq. (3.2) whenever the spectral ones do: $\alpha + \rho + \tau = 1$.

    **Arguments:**

    - `absorptance`: spectral absorptance $\alpha_\lambda$ in [0, 1], e.g.
        `absorptance(reflectance, transmittance)`, wavelengths on the last axis.
        [dimensionless]
    - `incident_spectrum`: spectral incident flux $\Phi^i_\lambda \ge 0$, broadcasting with
        `absorptance`. [W nm^-1, or any unit nm^-1]
    - `wavelengths_nm`: the grid, strictly increasing, `(n,)`. [nm]

    **Returns:**

    $\alpha$ in [0, 1], with the wavelength axis removed. [dimensionless]

    !!! note "Thesis"
        Table 3.1 ("Absorptance"), eq. (3.2), section 3.1.

    ??? cite "References"
        `CIE2020` (absorptance).
    """
    return _flux_weighted(absorptance, incident_spectrum, wavelengths_nm, "absorptance")


def slab_reflectance_transmittance(
    interface_reflectance, internal_transmittance
) -> tuple[Array, Array, Array]:
    r"""Reflectance, transmittance and absorptance of an absorbing plane-parallel layer.

    Light enters through the first interface (reflectance $r$), crosses the layer (internal
    transmittance $\tau_i$) and bounces between the two faces; summing the incoherent multiple
    reflections (geometric series, `Stokes1862`):

    $$\rho = r + \frac{(1 - r)^2\,r\,\tau_i^2}{1 - r^2\tau_i^2},\qquad
      \tau = \frac{(1 - r)^2\,\tau_i}{1 - r^2\tau_i^2},\qquad
      \alpha = \frac{(1 - r)(1 - \tau_i)}{1 - r\,\tau_i}$$

    and $\alpha + \rho + \tau = 1$ (thesis eq. 3.2). Both faces have the same $r$ (the same
    medium on both sides, e.g. a glass plate in air; for unpolarised light use $r$ =
    `fresnel_dielectric` at the incident angle, the same at the inner face). As the layer gets
    thick ($\tau_i \to 0$) the reflectance stops changing and tends to $r$: a non-scattering
    material's reflectivity $\rho_\infty$ is its interface reflectance (thesis glossary, the
    $\bar\rho$ of section 3.1); with scattering inside see `reflectivity_kubelka1931`.

    **Arguments:**

    - `interface_reflectance`: $r$ in [0, 1]. [dimensionless]
    - `internal_transmittance`: $\tau_i$ in [0, 1] for one crossing, $e^{-\kappa_a d/\cos\theta_t}$
        for a layer of thickness $d$ (`radiometria.radiometry.beer_lambert_transmittance`).
        [dimensionless]

    **Returns:**

    `(reflectance, transmittance, absorptance)`, broadcast over the inputs. [dimensionless]
    $r = 1$ gives (1, 0, 0).

    !!! note "Thesis"
        Eq. (3.1)-(3.2), section 3.1 and the glossary (reflectivity, transmissivity).

    ??? cite "References"
        `Stokes1862`; `CIE2020`; `Born1999` section 1.6.
    """
    r = _fraction(interface_reflectance, "interface_reflectance")
    t = _fraction(internal_transmittance, "internal_transmittance")
    r, t = align_ranks(r, t)
    rt = r * t
    one_m_r = 1.0 - r
    # 1 - r^2 t^2 = (1 - r t)(1 + r t) vanishes only for r = t = 1 (lossless mirror faces).
    den = (1.0 - rt) * (1.0 + rt)
    tau = safe_div(one_m_r * one_m_r * t, den)
    rho = r + tau * rt
    alpha = safe_div(one_m_r * (1.0 - t), 1.0 - rt)
    return rho, tau, alpha


def reflectivity_kubelka1931(absorption_coefficient, scattering_coefficient) -> Array:
    r"""Reflectivity $\rho_\infty$ of an opaque (infinitely thick) scattering layer, Kubelka-Munk.

    $$\rho_\infty = 1 + \frac KS - \sqrt{\left(\frac KS\right)^2 + 2\frac KS}
      = \frac{S}{S + K + \sqrt{K^2 + 2KS}}$$

    The reflectance of a layer so thick that more thickness no longer changes it (thesis
    glossary, "reflectivity"), for diffuse light in the two-flux model of `Kubelka1931`, with
    the light scattered back from inside the material (subsurface scattering) included. It
    inverts the Kubelka-Munk remission function $K/S = (1 - \rho_\infty)^2/(2\rho_\infty)$.
    The second form is evaluated (no cancellation); $K = 0$ gives 1, $S = 0$ gives 0, and
    $K = S = 0$ gives 0. Interface reflection is not included (the Saunderson correction would
    add it).

    **Arguments:**

    - `absorption_coefficient`: Kubelka-Munk absorption coefficient $K \ge 0$. [m^-1]
    - `scattering_coefficient`: Kubelka-Munk scattering coefficient $S \ge 0$, same unit and
        broadcasting. [m^-1]

    **Returns:**

    $\rho_\infty$ in [0, 1]. [dimensionless]

    !!! note "Thesis"
        Section 3.1 and the glossary ("Reflectivity").

    ??? cite "References"
        `Kubelka1931`; `CIE2020` (reflectivity).
    """
    K = as_float_array(absorption_coefficient, "absorption_coefficient")
    S = as_float_array(scattering_coefficient, "scattering_coefficient")
    K = check_in_range(K, "absorption_coefficient", 0.0, math.inf, unit="m^-1")
    S = check_in_range(S, "scattering_coefficient", 0.0, math.inf, unit="m^-1")
    K, S = align_ranks(K, S)
    q = K * K + 2.0 * K * S
    pos = q > 0
    root = jnp.where(pos, jnp.sqrt(jnp.where(pos, q, 1.0)), 0.0)
    return safe_div(S, S + K + root)


def transmissivity(absorption_coefficient, unit_length=1.0) -> Array:
    r"""Transmissivity $\tau_u = e^{-\kappa_a\ell_u}$: internal transmittance of a unit path.

    The internal (not counting the interfaces) transmittance of a layer of an absorbing
    material in which the light travels a unit length (thesis glossary, "Transmissivity"),
    Beer-Lambert's law (thesis eq. 1.12) with $z = \ell_u$.

    **Arguments:**

    - `absorption_coefficient`: $\kappa_a \ge 0$. [m^-1]
    - `unit_length`: the unit path length $\ell_u > 0$; 1 m (SI) by default, 0.01 for a
        per-centimetre table. [m]

    **Returns:**

    $\tau_u$ in (0, 1]. [dimensionless]

    !!! note "Thesis"
        Glossary ("Transmissivity"), section 3.1; eq. (1.12).

    ??? cite "References"
        `CIE2020` (transmissivity).
    """
    kappa = as_float_array(absorption_coefficient, "absorption_coefficient")
    ell = as_float_array(unit_length, "unit_length")
    ell = eqx.error_if(ell, ell <= 0, "`unit_length` must be > 0 [m]; got a value <= 0.")
    return beer_lambert_transmittance(*align_ranks(kappa, ell))


def absorptivity(absorption_coefficient, unit_length=1.0) -> Array:
    r"""Absorptivity $\alpha_u = 1 - e^{-\kappa_a\ell_u}$: internal absorptance of a unit path.

    The complement of `transmissivity` (thesis eq. 3.2 inside the material, no interfaces and
    no scattering), computed as $-\mathrm{expm1}(-\kappa_a\ell_u)$ so it stays accurate for
    weak absorption.

    **Arguments:**

    - `absorption_coefficient`: $\kappa_a \ge 0$. [m^-1]
    - `unit_length`: the unit path length $\ell_u > 0$; 1 m by default. [m]

    **Returns:**

    $\alpha_u$ in [0, 1). [dimensionless]

    !!! note "Thesis"
        Glossary ("Absorptivity"), section 3.1; eq. (3.2).

    ??? cite "References"
        `CIE2020` (absorptivity).
    """
    kappa = as_float_array(absorption_coefficient, "absorption_coefficient")
    kappa = check_in_range(kappa, "absorption_coefficient", 0.0, math.inf, unit="m^-1")
    ell = as_float_array(unit_length, "unit_length")
    ell = eqx.error_if(ell, ell <= 0, "`unit_length` must be > 0 [m]; got a value <= 0.")
    kappa, ell = align_ranks(kappa, ell)
    return -jnp.expm1(-kappa * ell)
