"""Diffuse area lights on triangles (Mitsuba's `area` emitter), sampled by power and area."""

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from ..._math import dot
from ...montecarlo import sample_cosine_hemisphere, sample_uniform_triangle
from ...scattering import coordinate_system
from ...upsampling import RGBIlluminantSpectrum
from .._spectral import SpectrumTable
from .._textures import AbstractTexture, ConstantTexture
from ._base import AbstractLight, EmissionSample, LightSample


class AreaLight(AbstractLight):
    r"""Diffuse emitters on triangles of the scene: constant radiance per emitter, emitted on
    the front side (the side of the winding normal) or on both.

    Next-event estimation picks an emissive triangle with probability proportional to its
    area times its mean emitted radiance over the 1 nm grid, then a point uniformly on it;
    the density per unit solid angle is $p_A\,d^2/|\cos\theta_l|$.

    Build it with `AreaLight.from_triangles` (NumPy work, once, outside `jit`).

    **Fields:**

    - `radiance`: texture of the emitted radiance, one row per emitter. [W m^-2 sr^-1 nm^-1]
    - `two_sided`: `(e,)` bool, emitters that emit on both sides.
    - `face_emitter`: `(f,)` int32 emitter of each scene triangle, -1 when not emissive.
    - `light_pdf_area`: `(f,)` density of next-event estimation per unit area on each
        triangle. [1/area]
    - `light_face`: `(l,)` the emissive triangles; `light_cdf`: `(l,)` their cumulative
        selection probabilities (last = 1).
    - `p0`, `e1`, `e2`, `normal`: `(l, 3)` first corner, edges and unit normal of each
        emissive triangle. [scene units]
    - `phi`: emitted power, $\pi \sum_i A_i \bar L_i$ (twice that for two-sided emitters),
        with $\bar L_i$ the radiance averaged over the 1 nm grid (static, for `LightSet`).
        [W nm^-1]

    !!! note "Thesis"
        Chapter 8 (emitters); eq. 1.13-1.14 (radiance and solid angle).

    ??? cite "References"
        `Pharr2023` §12.2 (sampling area lights by power and area), §12.5 (light sampling);
        `Jakob2022` (Mitsuba's `area` emitter).
    """

    NAME: ClassVar[str] = "area"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"radiance"})
    radiance: AbstractTexture
    two_sided: Bool[Array, " e"]
    face_emitter: Int[Array, " f"]
    light_pdf_area: Float[Array, " f"]
    light_face: Int[Array, " l"]
    light_cdf: Float[Array, " l"]
    p0: Float[Array, "l 3"]
    e1: Float[Array, "l 3"]
    e2: Float[Array, "l 3"]
    normal: Float[Array, "l 3"]
    phi: float = eqx.field(static=True, default=0.0)

    @classmethod
    def from_triangles(
        cls,
        p0,
        e1,
        e2,
        normal,
        area: np.ndarray,
        face_emitter: np.ndarray,
        radiance: "SpectrumTable | AbstractTexture",
        emitter_two_sided=None,
        *,
        dtype=jnp.float32,
    ) -> "AreaLight":
        """Area lights on the triangles of a scene.

        **Arguments:**

        - `p0`, `e1`, `e2`, `normal`: `(f, 3)` the scene's triangles (first corner, edges,
            unit normal) as device arrays. [scene units]
        - `area`: `(f,)` float64 triangle areas. [scene units^2]
        - `face_emitter`: `(f,)` emitter row of each triangle, or -1.
        - `radiance`: emitted radiance, one row per emitter (a `SpectrumTable` or a
            texture). [W m^-2 sr^-1 nm^-1]
        - `emitter_two_sided`: `(e,)` bool (default: front side only).
        - `dtype`: float dtype of the arrays.
        """
        if isinstance(radiance, SpectrumTable):
            radiance = ConstantTexture(SpectrumTable(jnp.asarray(radiance.values, dtype)))
        face_emitter = np.asarray(face_emitter, np.int64)
        n_faces = face_emitter.shape[0]
        n_em = radiance.n_rows
        two_sided = (
            np.zeros(n_em, bool) if emitter_two_sided is None else np.asarray(emitter_two_sided)
        ).reshape(n_em)
        if n_em == 0:  # no light: one black row keeps the (clamped) emitter lookups in range
            values = radiance.table.values
            radiance = ConstantTexture(SpectrumTable(jnp.zeros((1,) + values.shape[1:], dtype)))
            two_sided = np.zeros(1, bool)
        # Next-event estimation picks an emissive triangle with probability proportional to
        # area x (mean emitted radiance over the grid), then a point uniformly on it.
        emissive = np.flatnonzero((face_emitter >= 0) & (area > 0))
        phi = 0.0
        if emissive.size:
            mean_le = np.asarray(radiance.table.values, np.float64).mean(axis=1)
            power = area[emissive] * mean_le[face_emitter[emissive]]
            keep = power > 0
            emissive, power = emissive[keep], power[keep]
            sides = np.where(two_sided[face_emitter[emissive]], 2.0, 1.0)
            phi = float(np.pi * np.sum(power * sides))
        pdf_area = np.zeros(n_faces)
        if emissive.size == 0:
            # No light to sample: a dummy entry whose density is 0, so NEE contributes nothing.
            light_face, light_cdf = np.zeros(1, np.int64), np.ones(1)
        else:
            prob = power / power.sum()
            light_face = emissive
            light_cdf = np.cumsum(prob)
            light_cdf[-1] = 1.0
            pdf_area[emissive] = prob / area[emissive]
        lf = jnp.asarray(light_face, jnp.int32)
        return cls(
            radiance=radiance,
            two_sided=jnp.asarray(two_sided, bool),
            face_emitter=jnp.asarray(face_emitter, jnp.int32),
            light_pdf_area=jnp.asarray(pdf_area, dtype),
            light_face=lf,
            light_cdf=jnp.asarray(light_cdf, dtype),
            p0=p0[lf],
            e1=e1[lf],
            e2=e2[lf],
            normal=normal[lf],
            phi=phi,
        )

    @staticmethod
    def radiance_texture(values: list, dtype=jnp.float32) -> ConstantTexture:
        """Emitted radiance of scene values, one row each: RGB triples become
        `RGBIlluminantSpectrum`s (thesis 2.2.3; white (1, 1, 1) emits D65 with Y = 1)."""
        return ConstantTexture.from_values(values, RGBIlluminantSpectrum, dtype)

    def _emitter_two_sided(self, face):
        return self.two_sided[jnp.maximum(self.face_emitter[face], 0)]

    def pdf_li(self, face, dist, cos_light):
        two_sided = self._emitter_two_sided(face)
        cos_light = jnp.where(two_sided, jnp.abs(cos_light), cos_light)
        pdf_area = self.light_pdf_area[face]
        ok = (cos_light > 0) & (pdf_area > 0)
        return jnp.where(ok, pdf_area * dist * dist / jnp.where(ok, cos_light, 1.0), 0.0)

    def emitted(self, face, cos_o, valid, wavelength_nm):
        emitter = self.face_emitter[face]
        two_sided = self.two_sided[jnp.maximum(emitter, 0)]
        on = valid & (emitter >= 0) & ((cos_o > 0) | (two_sided & (cos_o != 0)))
        le = self.radiance(jnp.maximum(emitter, 0), wavelength_nm)
        return jnp.where(on[:, None], le, 0.0)

    def emitted_escaped(self, directions, escaped, wavelength_nm):
        return jnp.zeros(wavelength_nm.shape, directions.dtype)

    def pdf_escaped(self, directions):
        return jnp.zeros(directions.shape[:-1], directions.dtype)

    def power(self, scene_radius: float) -> float:
        return self.phi

    def sample_li(self, p, u_select, u2, wavelength_nm) -> LightSample:
        dtype = p.dtype
        # (a comparison against every entry is cheaper than a binary-search loop for a few)
        method = "compare_all" if self.light_cdf.shape[0] <= 64 else "scan_unrolled"
        j = jnp.searchsorted(self.light_cdf, u_select, side="right", method=method)
        j = jnp.clip(j, 0, self.light_face.shape[0] - 1)
        lf = self.light_face[j]
        bary = sample_uniform_triangle(u2, check=False).astype(dtype)
        y = self.p0[j] + bary[:, 1:2] * self.e1[j] + bary[:, 2:3] * self.e2[j]
        to_light = y - p
        dist = jnp.sqrt(jnp.sum(to_light * to_light, axis=-1))
        wi = to_light / jnp.where(dist > 0, dist, 1.0)[:, None]
        cos_light = -jnp.sum(self.normal[j] * wi, axis=-1)
        pdf = self.pdf_li(lf, dist, cos_light)
        le = self.radiance(jnp.maximum(self.face_emitter[lf], 0), wavelength_nm)
        return LightSample(wi=wi, dist=dist, radiance=le, pdf=pdf)

    def sample_le(self, u_select, u_pos, u_dir, u_side, observer, wavelength_nm):
        """An emitted ray: a triangle by power x area, a uniform point on it and a
        cosine-weighted direction on its front side (a two-sided emitter: either side, each
        with probability 1/2, chosen by `u_side`), so the throughput is
        $L_e \\pi / p_A$ (twice that for two-sided emitters)."""
        dtype = observer.dtype
        method = "compare_all" if self.light_cdf.shape[0] <= 64 else "scan_unrolled"
        j = jnp.searchsorted(self.light_cdf, u_select, side="right", method=method)
        j = jnp.clip(j, 0, self.light_face.shape[0] - 1)
        lf = self.light_face[j]
        bary = sample_uniform_triangle(u_pos, check=False).astype(dtype)
        p = self.p0[j] + bary[:, 1:2] * self.e1[j] + bary[:, 2:3] * self.e2[j]
        emitter = jnp.maximum(self.face_emitter[lf], 0)
        two_sided = self.two_sided[emitter]
        flip = two_sided & (u_side >= 0.5)
        n = jnp.where(flip[:, None], -self.normal[j], self.normal[j])
        s, t = coordinate_system(n)
        local = sample_cosine_hemisphere(u_dir, check=False).astype(dtype)
        d = local[:, 0:1] * s + local[:, 1:2] * t + local[:, 2:3] * n
        d = d / jnp.sqrt(dot(d, d))[:, None]
        pdf_dir = local[:, 2] / jnp.pi * jnp.where(two_sided, 0.5, 1.0)
        le = self.radiance(emitter, wavelength_nm)
        to_obs = observer - p
        cos_obs = jnp.sum(self.normal[j] * to_obs, axis=-1)
        facing = (cos_obs > 0) | (two_sided & (cos_obs != 0))
        return EmissionSample(
            p=p,
            n=n,
            d=d,
            le=le,
            pdf_pos=self.light_pdf_area[lf],
            pdf_dir=pdf_dir,
            le_observer=jnp.where(facing[:, None], le, 0.0),
            delta_pos=jnp.zeros(pdf_dir.shape, bool),
            pdf_dir_observer=jnp.where(
                facing,
                jnp.abs(cos_obs)
                / (jnp.pi * jnp.sqrt(jnp.maximum(dot(to_obs, to_obs), jnp.finfo(dtype).tiny)))
                * jnp.where(two_sided, 0.5, 1.0),
                0.0,
            ),
        )

    def pdf_le(self, face, cos_o):
        """Position density `light_pdf_area` of `face` and the cosine-weighted direction
        density $|\\cos| / \\pi$ (halved for two-sided emitters; 0 on the dark side)."""
        emitter = self.face_emitter[face]
        two_sided = self.two_sided[jnp.maximum(emitter, 0)]
        on = (emitter >= 0) & ((cos_o > 0) | (two_sided & (cos_o != 0)))
        pdf_dir = jnp.abs(cos_o) / jnp.pi * jnp.where(two_sided, 0.5, 1.0)
        return jnp.where(on, self.light_pdf_area[face], 0.0), jnp.where(on, pdf_dir, 0.0)
