r"""A thin dielectric slab (Mitsuba 3's `thindielectric`): glass panes, soap films, windows.

The slab's two parallel interfaces reflect light back and forth; summing the geometric series
of the internal reflections (no absorption, incoherent) gives the slab's reflectance and
transmittance from the single-interface Fresnel reflectance $R$ (thesis eq. 3.18):

$$R' = R + \frac{T^2 R}{1 - R^2},\qquad T' = 1 - R',\qquad T = 1 - R.$$

Transmitted light leaves parallel to its arrival (the two refractions cancel), so the slab
transmits straight through: $\omega_i = -\omega_o$.
"""

import jax.numpy as jnp
from jax import Array

from .._checks import as_float_array
from .._math import safe_div
from ._bxdfs import (
    BSDFSample,
    _AbstractDeltaBxDF,
    _broadcast,
    _check_mode,
    _dirs,
    _failed_or,
    _mirror_xy,
    _spectral,
    _u2,
)
from ._fresnel import _check_eta, _fr_dielectric_snell

__all__ = ["ThinDielectricBxDF", "thin_slab_reflectance"]


def thin_slab_reflectance(cos_theta, eta) -> Array:
    r"""Reflectance $R' = R + T^2R/(1 - R^2)$ of a thin non-absorbing slab (module notes).

    **Arguments:**

    - `cos_theta`: cosine of the incident angle, either side, `(...)`. [dimensionless]
    - `eta`: relative index of the slab over the outside, > 0, broadcast with `cos_theta`.
        [dimensionless]

    **Returns:**

    $R'$ in [0, 1] (1 where $R = 1$). [dimensionless]

    !!! note "Thesis"
        Eq. 3.18 (single interface), section 3.1.1; the slab sum of
        `slab_reflectance_transmittance`.

    ??? cite "References"
        `Jakob2022` (`thindielectric`); `Pharr2023` §14.3.
    """
    cos_theta, eta = jnp.broadcast_arrays(as_float_array(cos_theta, "cos_theta"), eta)
    r = _fr_dielectric_snell(jnp.abs(cos_theta), eta, 1.0 / eta)[0]
    t = 1.0 - r
    return jnp.where(r < 1.0, r + t * t * safe_div(r, 1.0 - r * r), 1.0)


class ThinDielectricBxDF(_AbstractDeltaBxDF):
    r"""Thin dielectric slab: delta reflection with probability $R'$ (mirror direction) and
    delta transmission straight through with probability $1 - R'$ (`thin_slab_reflectance`).

    `f` and `pdf` are 0 (delta lobes). A sample's weight is the factor
    `specular_reflectance` or `specular_transmittance`; the transmitted ray keeps its
    direction and crosses no index change (`eta = 1`), so radiance needs no $\eta^2$ factor.
    The hero wavelength chooses the lobe; every wavelength gets its own $R'$.

    **Fields:**

    - `eta`: relative index of the slab over the outside, > 0, `(..., n_lambda)`. [dimensionless]
    - `specular_reflectance`, `specular_transmittance`: factors on the two lobes,
        `(..., n_lambda)` (default 1). [dimensionless]

    !!! note "Thesis"
        Section 3.1.1, eq. 3.13-3.18.

    ??? cite "References"
        `Jakob2022` (`thindielectric`).
    """

    eta: Array
    specular_reflectance: Array
    specular_transmittance: Array

    def __init__(self, eta, specular_reflectance=1.0, specular_transmittance=1.0):
        self.eta = _check_eta(_spectral(eta, "eta"))
        self.specular_reflectance = _spectral(specular_reflectance, "specular_reflectance")
        self.specular_transmittance = _spectral(specular_transmittance, "specular_transmittance")

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        _check_mode(mode)
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        u2 = _u2(u2)
        _, (wo, u_lobe, _v, eta, s_r, s_t) = _broadcast(
            (wo, 1),
            (u_lobe, 0),
            (u2, 1),
            (self.eta, 1),
            (self.specular_reflectance, 1),
            (self.specular_transmittance, 1),
        )
        c = jnp.abs(wo[..., 2])
        r = thin_slab_reflectance(jnp.broadcast_to(c[..., None], eta.shape), eta)
        r_h = r[..., 0]
        reflect = u_lobe < r_h
        wi = jnp.where(reflect[..., None], _mirror_xy(wo), -wo)
        pdf = jnp.where(reflect, r_h, 1.0 - r_h)
        ok = (c > 0) & (pdf > 0)
        value = jnp.where(reflect[..., None], r * s_r, (1.0 - r) * s_t)
        f = value / jnp.where(ok, c, 1.0)[..., None]
        sample = BSDFSample(
            f=f,
            wi=wi,
            pdf=pdf,
            is_delta=jnp.ones(c.shape, bool),
            is_transmission=~reflect,
            eta=jnp.ones_like(c),
            terminate_secondary=jnp.zeros(c.shape, bool),
        )
        return _failed_or(ok, sample)
