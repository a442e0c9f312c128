r"""A homogeneous participating medium at a path's hero wavelengths (thesis 1.3, ch. 4).

Coefficients are constant in space and may vary with wavelength: arrays per wavelength, or
`radiometria.radiometry.AbstractSpectrum` objects evaluated at the path's wavelengths.
Transmittance is exact, $T_j = e^{-\sigma_{t,j} d}$ (thesis eq. 1.12), and free-flight
sampling is analytic.

Weight convention (`MediumInteraction.weight`, the one the interface documents, as in pbrt-v3's
`HomogeneousMedium::Sample` and `Novak2018` §4): a path carrying wavelengths $j = 1..k$ samples
one distance $t$ for all of them, from the *mixture* (single-sample MIS with the balance
heuristic over the wavelengths, `Wilkie2014`; pbrt-v4's spectral MIS in `VolPathIntegrator`)

$$p(t) = \frac1k\sum_j \sigma_{t,j}\,e^{-\sigma_{t,j}t},$$

drawn by picking $j$ uniformly and then $t \sim \sigma_{t,j}e^{-\sigma_{t,j}t}$. A sample
before the segment's end is a real interaction (`scattered = True`) with weight
$w_j = \sigma_{s,j}e^{-\sigma_{t,j}t}/p(t)$: absorption is not sampled as a path end but
folded into the weight through $\sigma_s$ (the albedo). Past the end (`scattered = False`,
`t = t_max`) the weight is $w_j = T_j(t_{max})/P$, $P = \frac1k\sum_j T_j(t_{max})$. Hence for
every wavelength $E[w_j\,1_{scattered}\,f(t)] = \int_0^{t_{max}}\sigma_{s,j}e^{-\sigma_{t,j}t}
f(t)\,\mathrm dt$ and $E[w_j\,1_{not\ scattered}] = T_j(t_{max})$: the two terms of the
volume rendering equation, unbiased at each wavelength. With one wavelength this is the
classical $w = \varrho$ at an event and $w = 1$ past the end.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from .._checks import as_float_array, check_in_range
from .._math import safe_div
from ..radiometry import AbstractSpectrum
from ._coefficients import optical_depth
from ._medium import AbstractMedium, MediumInteraction
from ._phase import AbstractPhaseFunction
from ._validation import check_coefficient


def _spectral(value, wavelength_nm: Array, name: str, upper: float) -> Array:
    """A coefficient at the wavelengths `(n, k)`: a spectrum evaluated, or an array broadcast."""
    if isinstance(value, AbstractSpectrum):
        v = jnp.asarray(value(wavelength_nm))
        v = eqx.error_if(
            v,
            ~jnp.isfinite(v) | (v < 0) | (v > upper),
            f"`{name}` evaluated at the wavelengths must be finite and lie in [0, {upper}].",
        )
    else:
        v = value
    v = jnp.asarray(v)
    try:
        shape = np.broadcast_shapes(v.shape, wavelength_nm.shape)
    except ValueError:
        shape = None
    if shape != wavelength_nm.shape:
        raise ValueError(
            f"`{name}` of shape {v.shape} does not broadcast to the wavelengths' shape "
            f"{wavelength_nm.shape} (give a scalar, one value per wavelength (k,), or (n, k))."
        )
    v = v.reshape((1,) * (wavelength_nm.ndim - v.ndim) + v.shape)
    return jnp.broadcast_to(v, shape)


class HomogeneousMedium(AbstractMedium):
    r"""A medium with constant extinction $\sigma_t$, albedo $\varrho$ and a phase function.

    **Arguments:**

    - `sigma_t`: extinction coefficient per wavelength: an array (scalar, `(k,)` for the
        path's `k` wavelengths, or `(n, k)`) or an `AbstractSpectrum`; finite and >= 0.
        [scene units^-1; m^-1 for physical scenes]
    - `albedo`: single-scattering albedo $\sigma_s/\sigma_t$, an array or spectrum in
        [0, 1]. [dimensionless]
    - `phase`: the phase function, an `AbstractPhaseFunction`.

    Arrays are checked here (a concrete bad value raises `ValueError` naming `sigma_t` or
    `albedo`); spectra are checked when evaluated (`equinox.EquinoxRuntimeError`).

    ```python
    fog = HomogeneousMedium(sigma_t=jnp.array([0.5, 0.6, 0.7, 0.8]), albedo=0.9,
                            phase=HenyeyGreenstein(0.3))
    T = fog.transmittance(o, w, t_max, wavelength_nm)        # exact, (n, 4)
    mi = fog.sample_free_flight(o, w, t_max, wavelength_nm, u)
    ```

    !!! note "Thesis"
        Section 1.3 (eq. 1.11-1.12) and chapter 4 (energy transport in a medium; title only).

    ??? cite "References"
        `Pharr2023` §11.4 (`HomogeneousMedium`); `Novak2018` §3-4; `Wilkie2014`.
    """

    sigma_t: Float[Array, "..."] | AbstractSpectrum
    albedo: Float[Array, "..."] | AbstractSpectrum
    phase: AbstractPhaseFunction

    def __init__(self, sigma_t, albedo, phase: AbstractPhaseFunction):
        if not isinstance(phase, AbstractPhaseFunction):
            raise TypeError(
                f"`phase` must be an AbstractPhaseFunction, got {type(phase).__name__}."
            )
        if not isinstance(sigma_t, AbstractSpectrum):
            sigma_t = check_coefficient(sigma_t, "sigma_t", unit="scene units^-1")
        if not isinstance(albedo, AbstractSpectrum):
            albedo = check_coefficient(albedo, "albedo", upper=1.0)
        self.sigma_t = sigma_t
        self.albedo = albedo
        self.phase = phase

    def coefficients(
        self, wavelength_nm: Float[Array, "n k"]
    ) -> tuple[Float[Array, "n k"], Float[Array, "n k"]]:
        """`(sigma_t, sigma_s)` at the wavelengths `(n, k)` [nm]. [scene units^-1]"""
        lam = as_float_array(wavelength_nm, "wavelength_nm")
        st = _spectral(self.sigma_t, lam, "sigma_t", np.inf)
        rho = _spectral(self.albedo, lam, "albedo", 1.0)
        return st, rho * st

    def transmittance(
        self,
        origins: Float[Array, "n 3"],
        directions: Float[Array, "n 3"],
        t_max: Float[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        u: Float[Array, "n d"] | None = None,
    ) -> Float[Array, "n k"]:
        """Exact transmittance $e^{-\\sigma_{t,j} t_{max}}$ `(n, k)` (1 in a vacuum, also
        for an infinite `t_max` [scene units]); `origins`, `directions` and `u` are unused.
        [dimensionless]"""
        st, _ = self.coefficients(wavelength_nm)
        d = check_in_range(as_float_array(t_max, "t_max"), "t_max", 0.0, np.inf)
        return jnp.exp(-optical_depth(st, d[:, None]))

    def sample_free_flight(
        self,
        origins: Float[Array, "n 3"],
        directions: Float[Array, "n 3"],
        t_max: Float[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        u: Float[Array, "n d"],
        channel: Int[Array, " n"] | None = None,
    ) -> MediumInteraction:
        """Sample the distance to the next interaction on `(0, t_max)` from `u[:, 0]` in
        [0, 1) (the mixture over wavelengths of the class docstring; the variate is remapped
        to choose the wavelength and then the distance). Returns a `MediumInteraction` with
        the weights of the module docstring and the per-wavelength densities `pdf`.

        With `channel` `(n,)` (indices into the `k` wavelengths) the distance is sampled at
        that wavelength alone, `u[:, 0]` unchanged, and the weight is $f_j / p_c$ (the
        path-level spectral MIS of `volpathmis` combines it with `pdf`, `Miller2019`)."""
        st, ss = self.coefficients(wavelength_nm)
        n, k = st.shape
        d = check_in_range(as_float_array(t_max, "t_max"), "t_max", 0.0, np.inf)
        u = as_float_array(u, "u")
        if u.ndim != 2 or u.shape[0] != n or u.shape[1] < 1 or d.shape != (n,):
            raise ValueError(
                f"`u` must be (n, d) with d >= 1 and `t_max` (n,), for n = {n} rays; got "
                f"{u.shape} and {d.shape}."
            )
        u0 = check_in_range(u[:, 0], "u", 0.0, 1.0, closed_upper=False)
        # Choose wavelength j = floor(k u), and reuse the remainder as the distance variate.
        ku = u0 * k
        j = jnp.clip(jnp.floor(ku), 0, k - 1).astype(jnp.int32)
        u1 = jnp.clip(ku - j.astype(ku.dtype), 0.0, 1.0 - jnp.finfo(ku.dtype).eps)
        if channel is not None:
            j = jnp.clip(jnp.asarray(channel, jnp.int32), 0, k - 1)
            u1 = u0
        st_j = jnp.take_along_axis(st, j[:, None], axis=1)[:, 0]
        pos = st_j > 0
        t = jnp.where(pos, -jnp.log1p(-u1) / jnp.where(pos, st_j, 1.0), jnp.inf)
        scattered = t < d
        t_end = jnp.where(scattered, t, d)
        tr = jnp.exp(-optical_depth(st, t_end[:, None]))  # T_j(t) or T_j(t_max), (n, k)
        pdf = jnp.where(scattered[:, None], st * tr, tr)  # per wavelength, (n, k)
        if channel is None:
            p_used = jnp.mean(pdf, axis=1)  # the mixture's density (or P(no event))
        else:
            p_used = jnp.take_along_axis(pdf, j[:, None], axis=1)[:, 0]
        f = jnp.where(scattered[:, None], ss * tr, tr)
        weight = safe_div(f, p_used[:, None])
        return MediumInteraction(t=t_end, scattered=scattered, weight=weight, pdf=pdf)
