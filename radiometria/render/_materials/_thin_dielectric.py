"""Mitsuba's `thindielectric` BSDF: a thin non-absorbing slab (window panes, soap films)."""

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array, Float, Int

from ...scattering import ThinDielectricBxDF
from ._dielectric import _AbstractSmoothDielectric


class ThinDielectric(_AbstractSmoothDielectric):
    """Thin dielectric slabs (Mitsuba's `thindielectric`): reflectance summed over the
    slab's internal reflections, $R' = R + T^2R/(1 - R^2)$, and straight-through transmission
    (`radiometria.scattering.ThinDielectricBxDF`).

    **Fields:**

    - `eta`: texture of `int_ior / ext_ior` (Mitsuba's defaults: BK7 in air). [1]
    - `specular_reflectance`, `specular_transmittance`: textures of factors on the two lobes
        (default 1). [1]
    - `two_sided`: `(m,)` bool (both sides always scatter).

    !!! note "Thesis"
        Section 3.1.1, eq. 3.13-3.18.

    ??? cite "References"
        `Jakob2022` (`thindielectric`).
    """

    NAME: ClassVar[str] = "thindielectric"
    ALWAYS_TWO_SIDED: ClassVar[bool] = True

    def bxdf(self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"], uv=None):
        return ThinDielectricBxDF(
            jnp.maximum(self.eta(row, wavelength_nm), 1e-3),
            self.specular_reflectance(row, wavelength_nm, uv),
            self.specular_transmittance(row, wavelength_nm, uv),
        )
