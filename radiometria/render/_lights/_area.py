"""Diffuse area lights on triangles (Mitsuba's `area` emitter), sampled by emitter (its
estimated contribution at the shading point), then by power and area."""

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ..._math import dot
from ...montecarlo import (
    sample_cosine_hemisphere,
    sample_uniform_cone,
    sample_uniform_sphere,
    sample_uniform_triangle,
)
from ...scattering import coordinate_system
from ...upsampling import RGBAlbedoSpectrum, RGBIlluminantSpectrum
from .._geometry._sphere import sphere_uv
from .._spectral import SpectrumTable, wavelength_grid_nm
from .._textures import (
    AbstractTexture,
    ConstantTexture,
    TextureSpec,
    concatenate_textures,
    texture_parameter,
)
from ._base import AbstractLight, EmissionSample, LightSample
from ._selection import MAX_SPATIAL_EMITTERS, EmitterBounds


def _mean_radiance(radiance: AbstractTexture, n_uv: int = 64) -> np.ndarray:
    """`(e,)` mean emitted radiance of each row over the 1 nm grid (and, for a texture, over
    an `n_uv` x `n_uv` grid of uv in [0, 1)^2), for selecting lights by power (NumPy, once).
    Any positive weight where the emission is positive keeps the estimate unbiased."""
    if isinstance(radiance, ConstantTexture):
        return np.asarray(radiance.table.values, np.float64).mean(axis=1)
    rows, wl = radiance.n_rows, wavelength_grid_nm()[::10]
    g = (np.arange(n_uv) + 0.5) / n_uv
    uv = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
    row = np.repeat(np.arange(rows), uv.shape[0])
    values = radiance(
        device_array(row, jnp.int32),
        jnp.broadcast_to(device_array(wl, jnp.float32), (row.size, wl.size)),
        device_array(np.tile(uv, (rows, 1)), jnp.float32),
    )
    return np.asarray(values, np.float64).reshape(rows, -1).mean(axis=1)


class AreaLight(AbstractLight):
    r"""Diffuse emitters on triangles of the scene: constant radiance per emitter, emitted on
    the front side (the side of the winding normal) or on both.

    Next-event estimation picks an emissive triangle with probability proportional to its
    area times its mean emitted radiance over the 1 nm grid (its power), then a point
    uniformly on it; the density per unit solid angle is $p_A\,d^2/|\cos\theta_l|$. With 2
    to `MAX_SPATIAL_EMITTERS` emitters (shapes), it first picks an emitter by its estimated
    contribution at the shading point (`selection`, an `EmitterBounds`: distance, the side
    it emits on, the solid angle it can subtend) and then one of its triangles by power, so
    the densities of a triangle are its power-based ones times $P_e(\mathbf p)/P_e$. On
    `bench_media.py`'s scenes (two emitters) that lowered the relative MSE at equal samples
    from 4.99e-2 to 4.07e-2. Emitted rays (`sample_le`, light tracing) are still picked by
    power.

    **Spheres.** An emitter whose triangles tessellate a `sphere` (`emitter_sphere`, with a
    constant radiance) is sampled, from a shading point outside it, by the cone of directions
    the true sphere subtends, as Mitsuba 3 samples its analytic sphere: the emitter is picked
    with the summed probability $P_e$ of its triangles, then a direction uniformly in the
    cone, whose half-angle has $\sin\theta_{max} = r/d_c$; the solid-angle density is
    $P_e / (2\pi(1 - \cos\theta_{max}))$ and the distance is the ray's to the true sphere.
    Its variance is that of the cone (a point sampled by area on the far half of the sphere
    adds nothing: measured 63x Mitsuba's per-sample variance under a sphere light). The mesh
    lies inside the true sphere (by `SPHERE_MAX_RADIAL_ERROR` of the radius at most), so a
    shadow ray to the true sphere never meets the light's own triangles; directions within
    that sliver of the silhouette that miss the mesh are counted by light samples only (a
    relative difference below 1e-3 of the sphere's rim, where Mitsuba's sphere is). From
    inside the sphere, and for textured radiance, triangles are sampled by area; when the
    scene intersects the sphere analytically (`emitter_true_sphere`), points are drawn
    uniformly on the true sphere instead (density $P_e / 4\pi r^2$), as are the origins of
    emitted rays (`sample_le`).

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
    - `uv0`, `duv1`, `duv2`: `(l, 2)` surface coordinates at the first corner of each
        emissive triangle and their changes along the two edges, where a texture gives the
        radiance (`None`: the points' barycentrics are their uv, as Mitsuba's meshes without
        uv). [1]
    - `sphere_center`, `sphere_radius`, `sphere_prob`: `(e, 3)`, `(e,)`, `(e,)` the true
        sphere of each emitter sampled by its cone (radius 0: none) and the summed selection
        probability $P_e$ of its triangles; `None` when no emitter is. [scene units]
    - `selection`: the emitters' `EmitterBounds`, or `None` (one emitter, or more than
        `MAX_SPATIAL_EMITTERS`: by power).
    - `phi`: emitted power, $\pi \sum_i A_i \bar L_i$ (twice that for two-sided emitters),
        with $\bar L_i$ the radiance averaged over the 1 nm grid (static, for `LightSet`).
        [W nm^-1]

    !!! note "Thesis"
        Chapter 8 (emitters); eq. 1.13-1.14 (radiance and solid angle).

    ??? cite "References"
        `Pharr2023` §12.2 (sampling area lights by power and area), §12.5 (light sampling),
        §12.6.3 (light bounds and their importance);
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
    uv0: Float[Array, "l 2"] | None = None
    duv1: Float[Array, "l 2"] | None = None
    duv2: Float[Array, "l 2"] | None = None
    sphere_center: Float[Array, "e 3"] | None = None
    sphere_radius: Float[Array, " e"] | None = None
    sphere_prob: Float[Array, " e"] | None = None
    analytic_center: Float[Array, "e 3"] | None = None
    analytic_radius: Float[Array, " e"] | None = None
    analytic_to_local: Float[Array, "e 3 3"] | None = None
    selection: EmitterBounds | None = None
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
        face_uv=None,
        emitter_sphere=None,
        emitter_true_sphere=None,
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
        - `face_uv`: `(f, 3, 2)` uv at the corners of each triangle, or `None` (barycentrics
            serve as uv); used when the radiance is a texture. [1]
        - `emitter_sphere`: per emitter, `(center (3,), radius)` of the sphere its triangles
            tessellate, or `None` (class docstring, "Spheres"). [scene units]
        - `emitter_true_sphere`: per emitter, `(center (3,), radius, rotation (3, 3))` of the
            sphere its triangles tessellate when the scene intersects that sphere
            analytically (`RenderScene.spheres`), else `None` (default: none). Such an
            emitter's points are drawn uniformly on the true sphere, density
            P_e / (4 pi r^2) on every one of its triangles. [scene units]
        - `dtype`: float dtype of the arrays.
        """
        if isinstance(radiance, SpectrumTable):
            radiance = ConstantTexture(SpectrumTable(device_array(radiance.values, dtype)))
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
        emissive = emissive[np.argsort(face_emitter[emissive], kind="stable")]  # by emitter
        phi = 0.0
        mean_le = None
        if emissive.size:
            mean_le = _mean_radiance(radiance)
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
        analytic = {}
        if emitter_true_sphere is not None and any(sp is not None for sp in emitter_true_sphere):
            if len(emitter_true_sphere) != n_em:
                raise ValueError(
                    f"`emitter_true_sphere` must have one entry per emitter ({n_em}), "
                    f"got {len(emitter_true_sphere)}."
                )
            center, radius = np.zeros((n_em, 3)), np.zeros(n_em)
            to_local = np.tile(np.eye(3), (n_em, 1, 1))
            for e, sp in enumerate(emitter_true_sphere):
                if sp is None:
                    continue
                center[e], radius[e] = np.asarray(sp[0], np.float64), float(sp[1])
                to_local[e] = np.asarray(sp[2], np.float64).T
                mine = face_emitter == e
                p_e = pdf_area[mine] @ area[mine]  # the emitter's selection probability
                pdf_area[mine] = p_e / (4.0 * np.pi * radius[e] ** 2)
            analytic = {
                "analytic_center": device_array(center, dtype),
                "analytic_radius": device_array(radius, dtype),
                "analytic_to_local": device_array(to_local, dtype),
            }
        lf = device_array(light_face, jnp.int32)
        selection = None
        if emissive.size and 2 <= np.unique(face_emitter[emissive]).size <= MAX_SPATIAL_EMITTERS:
            corners = np.asarray(p0, np.float64)[emissive][:, None] + np.stack(
                [np.zeros((emissive.size, 3)), np.asarray(e1, np.float64)[emissive],
                 np.asarray(e2, np.float64)[emissive]], axis=1)  # fmt: skip
            sph = None
            if emitter_true_sphere is not None or emitter_sphere is not None:
                sph = [
                    (t if t is not None else s)
                    for t, s in zip(
                        emitter_true_sphere or [None] * n_em,
                        emitter_sphere or [None] * n_em,
                        strict=True,
                    )
                ]
            selection = EmitterBounds.from_triangles(
                corners, np.asarray(normal, np.float64)[emissive], area[emissive],
                face_emitter[emissive], prob, mean_le, two_sided, sph, dtype=dtype,
            )  # fmt: skip
        uv = {}
        if face_uv is not None and not isinstance(radiance, ConstantTexture):
            c = np.asarray(face_uv, np.float64)[light_face]
            uv = {
                k: device_array(v, dtype)
                for k, v in (
                    ("uv0", c[:, 0]),
                    ("duv1", c[:, 1] - c[:, 0]),
                    ("duv2", c[:, 2] - c[:, 0]),
                )
            }
        spheres = {}
        if (
            emitter_sphere is not None
            and any(sp is not None for sp in emitter_sphere)
            and isinstance(radiance, ConstantTexture)
            and emissive.size
        ):
            if len(emitter_sphere) != n_em:
                raise ValueError(
                    f"`emitter_sphere` must have one entry per emitter ({n_em}), "
                    f"got {len(emitter_sphere)}."
                )
            center, radius = np.zeros((n_em, 3)), np.zeros(n_em)
            for e, sp in enumerate(emitter_sphere):
                if sp is not None:
                    center[e], radius[e] = np.asarray(sp[0], np.float64), float(sp[1])
            p_e = np.zeros(n_em)
            np.add.at(p_e, face_emitter[light_face], prob)
            spheres = {
                "sphere_center": device_array(center, dtype),
                "sphere_radius": device_array(radius, dtype),
                "sphere_prob": device_array(p_e, dtype),
            }
        return cls(
            radiance=radiance,
            two_sided=device_array(two_sided, bool),
            face_emitter=device_array(face_emitter, jnp.int32),
            light_pdf_area=device_array(pdf_area, dtype),
            light_face=lf,
            light_cdf=device_array(light_cdf, dtype),
            # rows gathered on the host: eager device gathers compile about six programs
            p0=device_array(np.asarray(p0)[light_face]),
            e1=device_array(np.asarray(e1)[light_face]),
            e2=device_array(np.asarray(e2)[light_face]),
            normal=device_array(np.asarray(normal)[light_face]),
            selection=selection,
            phi=phi,
            **uv,
            **spheres,
            **analytic,
        )

    @staticmethod
    def radiance_texture(values: list, dtype=jnp.float32, where: str = "scene") -> AbstractTexture:
        """Emitted radiance of scene values, one row each: RGB triples become
        `RGBIlluminantSpectrum`s (thesis 2.2.3; white (1, 1, 1) emits D65 with Y = 1).
        A texture (`TextureSpec`: `bitmap`, `checkerboard`) gives its texels' bounded (albedo)
        spectra, texels clipped to [0, 1] and no D65, as Mitsuba 3.9's textured `area` emitter
        evaluates them in its spectral variants (checked against Mitsuba in the tests)."""
        if not any(isinstance(v, TextureSpec) for v in values):
            return ConstantTexture.from_values(values, RGBIlluminantSpectrum, dtype)
        rows = [
            texture_parameter(v, RGBAlbedoSpectrum, "radiance", where)
            if isinstance(v, TextureSpec)
            else ConstantTexture.from_values([v], RGBIlluminantSpectrum, dtype)
            for v in values
        ]
        return concatenate_textures(rows)

    def _emitter_two_sided(self, face):
        return self.two_sided[jnp.maximum(self.face_emitter[face], 0)]

    def pdf_li(self, face, dist, cos_light, origin=None):
        two_sided = self._emitter_two_sided(face)
        cos_light = jnp.where(two_sided, jnp.abs(cos_light), cos_light)
        pdf_area = self.light_pdf_area[face]
        ok = (cos_light > 0) & (pdf_area > 0)
        pdf = jnp.where(ok, pdf_area * dist * dist / jnp.where(ok, cos_light, 1.0), 0.0)
        if origin is None:
            return pdf
        if self.sphere_radius is not None:
            e = jnp.maximum(self.face_emitter[face], 0)
            cone, pdf_cone, _ = self._cone(e, origin)
            pdf = jnp.where(cone & (self.face_emitter[face] >= 0), jnp.where(ok, pdf_cone, 0.0),
                            pdf)  # fmt: skip
        if self.selection is not None:
            pdf = pdf * self.selection.factor(self.face_emitter[face], origin)
        return pdf

    def _cone(self, e, p):
        r"""Whether emitter `e`'s light samples from `p` are drawn from its sphere's cone, the
        solid-angle density $P_e/(2\pi(1-\cos\theta_{max}))$, and `(axis, d_c, r, 1 -
        cos theta_max)` for sampling."""
        r = self.sphere_radius[e]
        to_c = self.sphere_center[e] - p
        dc2 = dot(to_c, to_c)
        cone = (r > 0) & (dc2 > r * r)
        dc2 = jnp.where(cone, dc2, 1.0)
        sin2 = jnp.where(cone, r * r / dc2, 0.5)
        omc = sin2 / (1.0 + jnp.sqrt(jnp.maximum(1.0 - sin2, 0.0)))  # 1 - cos, no cancellation
        pdf = self.sphere_prob[e] / (2.0 * jnp.pi * omc)
        dc = jnp.sqrt(dc2)
        return cone, pdf, (to_c / dc[:, None], dc, r, omc)

    def _point(self, j, e, u2, dtype):
        """A point of light triangle `j` (of emitter `e`) drawn uniformly from `u2`, or, for an
        emitter on an analytic sphere, uniformly on the true sphere: `(point, unit normal,
        uv or None)`."""
        bary = sample_uniform_triangle(u2, check=False).astype(dtype)
        y = self.p0[j] + bary[:, 1:2] * self.e1[j] + bary[:, 2:3] * self.e2[j]
        n_y = self.normal[j]
        uv = self._uv(j, bary, dtype)
        if self.analytic_radius is None:
            return y, n_y, uv
        r = self.analytic_radius[e]
        on = (r > 0)[:, None]
        w = sample_uniform_sphere(u2, check=False).astype(dtype)
        y = jnp.where(on, self.analytic_center[e] + r[:, None] * w, y)
        n_y = jnp.where(on, w, n_y)
        if uv is not None:
            uv = jnp.where(on, sphere_uv(self.analytic_to_local[e], w).astype(uv.dtype), uv)
        return y, n_y, uv

    def _uv(self, j, bary, dtype):
        """uv of sampled points (barycentrics `bary` on light triangle `j`), or `None` for an
        untextured radiance."""
        if isinstance(self.radiance, ConstantTexture):
            return None
        if self.uv0 is None:
            return bary[:, 1:3]
        return self.uv0[j] + bary[:, 1:2] * self.duv1[j] + bary[:, 2:3] * self.duv2[j]

    def emitted(self, face, cos_o, valid, wavelength_nm, uv=None):
        emitter = self.face_emitter[face]
        two_sided = self.two_sided[jnp.maximum(emitter, 0)]
        on = valid & (emitter >= 0) & ((cos_o > 0) | (two_sided & (cos_o != 0)))
        le = self.radiance(jnp.maximum(emitter, 0), wavelength_nm, uv)
        return jnp.where(on[:, None], le, 0.0)

    def emitted_escaped(self, directions, escaped, wavelength_nm):
        return jnp.zeros(wavelength_nm.shape, directions.dtype)

    def pdf_escaped(self, directions):
        return jnp.zeros(directions.shape[:-1], directions.dtype)

    def power(self, scene_radius: float) -> float:
        return self.phi

    def sample_li(self, p, u_select, u2, wavelength_nm) -> LightSample:
        dtype = p.dtype
        if self.selection is not None:  # an emitter by its estimate at p, then by power
            j, factor = self.selection.pick(p, u_select, self.light_cdf)
        else:
            # (a comparison against every entry is cheaper than a binary-search loop for a few)
            method = "compare_all" if self.light_cdf.shape[0] <= 64 else "scan_unrolled"
            j = jnp.searchsorted(self.light_cdf, u_select, side="right", method=method)
            j = jnp.clip(j, 0, self.light_face.shape[0] - 1)
            factor = None
        lf = self.light_face[j]
        e = jnp.maximum(self.face_emitter[lf], 0)
        y, n_y, uv = self._point(j, e, u2, dtype)
        to_light = y - p
        dist = jnp.sqrt(jnp.sum(to_light * to_light, axis=-1))
        wi = to_light / jnp.where(dist > 0, dist, 1.0)[:, None]
        cos_light = -jnp.sum(n_y * wi, axis=-1)
        pdf = self.pdf_li(lf, dist, cos_light)
        le = self.radiance(e, wavelength_nm, uv)
        if self.sphere_radius is not None:  # a direction in the cone of a sphere (docstring)
            cone, pdf_cone, (axis, dc, r, omc) = self._cone(e, p)
            local = sample_uniform_cone(u2, 1.0 - omc, check=False, one_minus_cos_theta_max=omc)
            sin2 = local[:, 0] ** 2 + local[:, 1] ** 2  # no cancellation in narrow cones
            s, t = coordinate_system(axis)
            w_c = local[:, 0:1] * s + local[:, 1:2] * t + local[:, 2:3] * axis
            w_c = w_c / jnp.sqrt(dot(w_c, w_c))[:, None]
            d_c = dc * local[:, 2] - jnp.sqrt(jnp.maximum(r * r - dc * dc * sin2, 0.0))
            wi = jnp.where(cone[:, None], w_c, wi)
            dist = jnp.where(cone, d_c, dist)
            pdf = jnp.where(cone, pdf_cone, pdf)
        if factor is not None:
            pdf = pdf * factor
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
        emitter = jnp.maximum(self.face_emitter[lf], 0)
        p, n_p, uv = self._point(j, emitter, u_pos, dtype)
        two_sided = self.two_sided[emitter]
        flip = two_sided & (u_side >= 0.5)
        n = jnp.where(flip[:, None], -n_p, n_p)
        s, t = coordinate_system(n)
        local = sample_cosine_hemisphere(u_dir, check=False).astype(dtype)
        d = local[:, 0:1] * s + local[:, 1:2] * t + local[:, 2:3] * n
        d = d / jnp.sqrt(dot(d, d))[:, None]
        pdf_dir = local[:, 2] / jnp.pi * jnp.where(two_sided, 0.5, 1.0)
        le = self.radiance(emitter, wavelength_nm, uv)
        to_obs = observer - p
        cos_obs = jnp.sum(n_p * to_obs, axis=-1)
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
