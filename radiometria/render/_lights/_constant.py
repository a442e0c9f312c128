"""A constant environment (Mitsuba's `constant` emitter): the same radiance from everywhere."""

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..._checks import device_array
from ...montecarlo import sample_uniform_sphere
from .._spectral import SpectrumTable
from ._base import LightSample, emission_at_infinity
from ._common import AbstractSurfacelessLight, illuminant_table, spectral_param


class ConstantLight(AbstractSurfacelessLight):
    r"""A light at infinity of the same radiance $L$ in every direction.

    Rays that leave the scene see $L$. Next-event estimation samples a direction uniformly on
    the sphere (density $1/4\pi$, as Mitsuba's `constant` does), weighted against BSDF
    sampling by MIS; its power for picking among lights is $4\pi^2 r^2 \bar L$ (pbrt's, for a
    scene of radius $r$).

    **Fields:**

    - `radiance`: `SpectrumTable` with one row. [W m^-2 sr^-1 nm^-1]
    - `mean_radiance`: its mean over the 1 nm grid (static). [W m^-2 sr^-1 nm^-1]
    - `bound_center`, `bound_radius`: the scene's bounding sphere (`with_bounds`), where
        emitted rays start (`sample_le`); `None` / 0 until set. [scene units]

    !!! note "Thesis"
        Chapter 8 (light sources); eq. 1.13 (radiance).

    ??? cite "References"
        `Pharr2023` §12.5.1 (uniform infinite lights); `Jakob2022` (Mitsuba's `constant`).
    """

    NAME: ClassVar[str] = "constant"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"radiance"})
    radiance: SpectrumTable
    mean_radiance: float = eqx.field(static=True)
    bound_center: Float[Array, " 3"] | None = None
    bound_radius: float = eqx.field(static=True, default=0.0)

    def with_bounds(self, center, radius: float) -> "ConstantLight":
        """The same light knowing the scene's bounding sphere (`center` `(3,)`, `radius`)
        [scene units], so it can start light paths."""
        return dataclasses.replace(
            self, bound_center=device_array(center, jnp.float32), bound_radius=radius
        )

    @classmethod
    def from_properties(
        cls, params: list[dict], *, where: list[str], dtype=jnp.float32
    ) -> "ConstantLight":
        """A constant environment from its `radiance` (RGB, spectrum or number; default 1)
        [W m^-2 sr^-1 nm^-1]. A scene has at most one light at infinity (as in Mitsuba)."""
        if len(params) != 1:
            raise ValueError(f"{where[1]}: a scene takes one environment emitter, got a second.")
        row = spectral_param(params[0], "radiance", where[0])
        return cls(radiance=illuminant_table([row], dtype), mean_radiance=float(row.mean()))

    def _le(self, n, wavelength_nm):
        return self.radiance(jnp.zeros((n,), jnp.int32), wavelength_nm)

    def sample_li(self, p, u_select, u2, wavelength_nm) -> LightSample:
        n = p.shape[0]
        wi = sample_uniform_sphere(u2, check=False).astype(p.dtype)
        return LightSample(
            wi=wi,
            dist=jnp.full((n,), jnp.inf, p.dtype),
            radiance=self._le(n, wavelength_nm),
            pdf=jnp.full((n,), 1.0 / (4.0 * np.pi), p.dtype),
            delta=jnp.zeros((n,), bool),
        )

    def emitted_escaped(self, directions, escaped, wavelength_nm):
        le = self._le(directions.shape[0], wavelength_nm)
        return jnp.where(escaped[:, None], le, 0.0)

    def pdf_escaped(self, directions):
        return jnp.full(directions.shape[:-1], 1.0 / (4.0 * np.pi), directions.dtype)

    def sample_le(self, u_select, u_pos, u_dir, u_side, observer, wavelength_nm):
        """An emitted ray: a direction uniform on the sphere (`u_dir`, `pdf_dir` $1/4\\pi$)
        travelling inwards, from a point uniform on the disk of the scene's radius across it
        (`u_pos`), so the throughput is $4\\pi \\cdot \\pi r^2 L$."""
        if self.bound_center is None:
            raise ValueError("a constant environment needs the scene's bounds (`with_bounds`).")
        dtype = observer.dtype
        n = observer.shape[0]
        d = -sample_uniform_sphere(u_dir, check=False).astype(dtype)
        pdf_dir = jnp.full((n,), 1.0 / (4.0 * np.pi), dtype)
        return emission_at_infinity(
            d,
            u_pos,
            self.bound_center.astype(dtype),
            self.bound_radius,
            self._le(n, wavelength_nm),
            pdf_dir,
            jnp.ones((n,), dtype),
        )

    def power(self, scene_radius: float) -> float:
        return float(4.0 * np.pi**2 * scene_radius**2 * self.mean_radiance)
