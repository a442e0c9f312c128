"""Point lights (Mitsuba's `point` emitter): isotropic delta lights."""

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..._checks import device_array
from ...montecarlo import sample_uniform_sphere
from .._spectral import SpectrumTable
from ._base import EmissionSample, LightSample
from ._common import (
    AbstractDeltaLight,
    direction_to_points,
    illuminant_table,
    pick_row,
    row_cdf,
    spectral_param,
    vector_or_to_world_param,
)


class PointLight(AbstractDeltaLight):
    r"""Isotropic point lights: every `point` emitter of a scene, one row each.

    A point of intensity $I$ at $x$ gives a shading point $p$ the irradiance
    $E = I \cos\theta / |x - p|^2$ from the direction $(x - p)/|x - p|$. Next-event estimation
    picks a light with probability proportional to its power $4\pi \bar I$ ($\bar I$ the
    intensity averaged over the 1 nm grid); rays never hit a point light.

    Build it with `PointLight.from_properties([params, ...], where=[...])`.

    **Fields:**

    - `position`: `(m, 3)` positions. [scene units]
    - `intensity`: `SpectrumTable`, one row per light. [W sr^-1 nm^-1]
    - `cdf`: `(m,)` cumulative probabilities of picking each light.
    - `phi`: total power (static). [W nm^-1]

    !!! note "Thesis"
        Chapter 8 (light sources); eq. 1.10-1.12 (intensity and irradiance, inverse-square
        law).

    ??? cite "References"
        `Pharr2023` §12.1.1 (point lights); `Jakob2022` (Mitsuba's `point` emitter).
    """

    NAME: ClassVar[str] = "point"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"intensity", "position", "to_world"})
    position: Float[Array, "m 3"]
    intensity: SpectrumTable
    cdf: Float[Array, " m"]
    phi: float = eqx.field(static=True)

    @classmethod
    def from_properties(
        cls, params: list[dict], *, where: list[str], dtype=jnp.float32
    ) -> "PointLight":
        """Point lights from scene parameters (Mitsuba's names): `intensity` (RGB, spectrum
        or number; default 1) [W sr^-1 nm^-1], and `position` [scene units] or `to_world`
        (its translation), not both. Bad values raise `ValueError` naming `where`."""
        pos, rows = [], []
        for p, w in zip(params, where, strict=True):
            pos.append(vector_or_to_world_param(p, "position", w, 3))
            rows.append(spectral_param(p, "intensity", w))
        mean = np.array([r.mean() for r in rows])
        return cls(
            position=device_array(np.stack(pos), dtype),
            intensity=illuminant_table(rows, dtype),
            cdf=device_array(row_cdf(mean), dtype),
            phi=float(4.0 * np.pi * mean.sum()),
        )

    def sample_li(self, p, u_select, u2, wavelength_nm) -> LightSample:
        j, prob, _ = pick_row(self.cdf, u_select)
        wi, dist, dist2, ok = direction_to_points(self.position[j], p)
        le = self.intensity(j, wavelength_nm) / jnp.where(ok, dist2, 1.0)[:, None]
        return LightSample(
            wi=wi,
            dist=dist,
            radiance=le,
            pdf=jnp.where(ok, prob, 0.0),
            delta=jnp.ones(dist.shape, bool),
        )

    def power(self, scene_radius: float) -> float:
        return self.phi

    def sample_le(self, u_select, u_pos, u_dir, u_side, observer, wavelength_nm):
        """An emitted ray: a light by power, a uniform direction on the sphere
        (density $1/4\\pi$); the throughput is $4\\pi I / P_j$."""
        j, prob, _ = pick_row(self.cdf, u_select)
        dtype = observer.dtype
        d = sample_uniform_sphere(u_dir, check=False).astype(dtype)
        le = self.intensity(j, wavelength_nm)
        return EmissionSample(
            p=self.position[j],
            n=jnp.zeros_like(d),
            d=d,
            le=le,
            pdf_pos=prob,
            pdf_dir=jnp.full(prob.shape, 1.0 / (4.0 * jnp.pi), dtype),
            le_observer=le,
            delta_pos=jnp.ones(prob.shape, bool),
            pdf_dir_observer=jnp.full(prob.shape, 1.0 / (4.0 * jnp.pi), dtype),
        )
