"""Directional lights (Mitsuba's `directional` emitter): parallel light from infinity."""

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..._checks import device_array
from .._spectral import SpectrumTable
from ._base import LightSample, emission_at_infinity
from ._common import (
    AbstractDeltaLight,
    illuminant_table,
    pick_row,
    row_cdf,
    spectral_param,
    vector_or_to_world_param,
)


class DirectionalLight(AbstractDeltaLight):
    r"""Directional lights: every `directional` emitter of a scene, one row each.

    A directional light of irradiance $E$ (on a surface facing it) travelling along $d$ gives
    a shading point the irradiance $E \cos\theta$ from $-d$, unless something lies in between
    (its shadow ray is unbounded). Next-event estimation picks one by its power over a disk of
    the scene's radius, $\pi r^2 \bar E$; rays never hit it.

    **Fields:**

    - `direction`: `(m, 3)` unit directions in which the light travels.
    - `irradiance`: `SpectrumTable`, one row per light. [W m^-2 nm^-1]
    - `cdf`: `(m,)` cumulative probabilities; `mean_irradiance`: summed mean irradiance
        (static). [W m^-2 nm^-1]
    - `bound_center`, `bound_radius`: the scene's bounding sphere (`with_bounds`), where
        emitted rays start (`sample_le`); `None` / 0 until set. [scene units]

    !!! note "Thesis"
        Chapter 8 (light sources); eq. 1.6-1.9 (irradiance).

    ??? cite "References"
        `Pharr2023` §12.4 (distant lights); `Jakob2022` (Mitsuba's `directional` emitter).
    """

    NAME: ClassVar[str] = "directional"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"irradiance", "direction", "to_world"})
    direction: Float[Array, "m 3"]
    irradiance: SpectrumTable
    cdf: Float[Array, " m"]
    mean_irradiance: float = eqx.field(static=True)
    bound_center: Float[Array, " 3"] | None = None
    bound_radius: float = eqx.field(static=True, default=0.0)

    def with_bounds(self, center, radius: float) -> "DirectionalLight":
        """The same lights knowing the scene's bounding sphere (`center` `(3,)`, `radius`)
        [scene units], so they can start light paths."""
        return dataclasses.replace(
            self, bound_center=device_array(center, self.direction.dtype), bound_radius=radius
        )

    @classmethod
    def from_properties(
        cls, params: list[dict], *, where: list[str], dtype=jnp.float32
    ) -> "DirectionalLight":
        """Directional lights from scene parameters (Mitsuba's names): `irradiance` (default
        1) [W m^-2 nm^-1], and `direction` or `to_world` (its +z axis), not both. Bad values
        raise `ValueError` naming `where`."""
        dirs, rows = [], []
        for p, w in zip(params, where, strict=True):
            d = vector_or_to_world_param(p, "direction", w, 2)
            norm = np.linalg.norm(d)
            if not norm > 0:
                raise ValueError(f"{w}: the light's direction is zero.")
            dirs.append(d / norm)
            rows.append(spectral_param(p, "irradiance", w))
        mean = np.array([r.mean() for r in rows])
        return cls(
            direction=device_array(np.stack(dirs), dtype),
            irradiance=illuminant_table(rows, dtype),
            cdf=device_array(row_cdf(mean), dtype),
            mean_irradiance=float(mean.sum()),
        )

    def sample_li(self, p, u_select, u2, wavelength_nm) -> LightSample:
        j, prob, _ = pick_row(self.cdf, u_select)
        n = p.shape[0]
        return LightSample(
            wi=-self.direction[j],
            dist=jnp.full((n,), jnp.inf, p.dtype),
            radiance=self.irradiance(j, wavelength_nm),
            pdf=prob,
            delta=jnp.ones((n,), bool),
        )

    def sample_le(self, u_select, u_pos, u_dir, u_side, observer, wavelength_nm):
        """An emitted ray: a light by irradiance (`u_select`), its direction (a delta,
        `pdf_dir = 1`) and an origin uniform on the disk of the scene's radius across it
        (`u_pos`), so the throughput is $\\pi r^2 E$."""
        if self.bound_center is None:
            raise ValueError("a directional light needs the scene's bounds (`with_bounds`).")
        j, prob, _ = pick_row(self.cdf, u_select)
        d = self.direction[j].astype(observer.dtype)
        le = self.irradiance(j, wavelength_nm)
        one = jnp.ones(prob.shape, observer.dtype)
        return emission_at_infinity(
            d, u_pos, self.bound_center, self.bound_radius, le, one, prob, delta_dir=True
        )

    def power(self, scene_radius: float) -> float:
        return float(np.pi * scene_radius**2 * self.mean_irradiance)
