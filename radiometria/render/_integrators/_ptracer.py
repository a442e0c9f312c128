r"""Light tracing (particle tracing): the `PTracer` integrator (thesis ch. 9).

Light tracing estimates the same pixel measurements as path tracing from the other end: a
path starts on a light (`AbstractLight.sample_le`: a point and an emitted direction, with
throughput $\beta_0 = L_e |\cos\theta_l| / (p_A\, p_\omega)$), and every vertex it reaches is
connected to the camera (`AbstractCamera.sample_wi`, a shadow ray) and *splatted* into the
film at the raster position the connection reaches, with the value

$$\beta\, f(\omega_\mathrm{light} \to \omega_\mathrm{cam})\,
  \frac{|\omega_\mathrm{light} \cdot n_s|\,|\omega_\mathrm{cam} \cdot n_g|}
       {|\omega_\mathrm{light} \cdot n_g|}\; \frac{W_e}{p_\mathrm{cam}}$$

(`Veach1997` §10.2 and §5.3.2: the BSDF in the adjoint (importance) mode, with the
non-symmetric correction for shading normals; $W_e$ the camera's importance and
$p_\mathrm{cam} = d^2/\cos\theta_\mathrm{cam}$ the pinhole's density per solid angle). The
light's own point is splatted the same way (depth 0, $L_e |\cos\theta_l| W_e / (p_A
p_\mathrm{cam})$) unless `hide_emitters`; delta lights (point, spot) are not, since a camera
ray can never hit them and the path tracer does not see them either.

**Lights at infinity** (`constant`, `envmap`) and **directional** lights start their paths
on a disk of the scene's bounding-sphere radius $r$ across the emitted direction, one radius
behind the sphere ($p_A = 1/\pi r^2$; the direction's density is the light's, 1 for a
directional light), so $\beta_0 = L_e / (p_A\,p_\omega)$ (pbrt-v4's `SampleLe`). Their
depth-0 splat is 0: light tracing does not estimate the environment seen directly by the
camera (render that with `path`). Continuing the path
samples the BSDF in importance mode, $\beta \mathrel{*}= f |\omega\cdot n_g|
|\omega_\mathrm{light}\cdot n_s| / (|\omega_\mathrm{light}\cdot n_g|\,p)$, with Russian
roulette after `rr_depth` segments on the throughput relative to the emitted one.

**Depths** are Mitsuba's (and the path tracer's): `max_depth` counts the segments of the whole
path, the camera connection included, so `max_depth = 1` is the emitters seen directly and
`max_depth = 2` direct illumination.

**Normalisation** (the driver's splat path, `radiometria.render.render`). One light path is
traced per (pixel, sample) slot of the driver, so a render of $P$ pixels at `spp` traces
$N = P \cdot \mathrm{spp}$ light paths. $W_e$ integrates to 1 over the whole film, so a splat
estimates the film-wide measurement; the pixel $j$ with reconstruction filter $f_j$ is

$$I_j = \frac{1}{\mathrm{spp}\;F_j} \sum_{i=1}^{N} \sum_\text{vertices} C_i\,
  f(\mathbf{r}_i - \mathbf{c}_j), \qquad F_j = \int_\text{film} f(\mathbf{r} - \mathbf{c}_j)
  \,d\mathbf{r}$$

(raster units), i.e. pbrt-v4's $1/\mathrm{spp}$ splat scale (`Pharr2023` §5.4, `RGBFilm::
AddSplat` and `splatScale`), divided by the filter's integral over the film: the light
paths' $P/N = 1/\mathrm{spp}$ turns the film-wide importance into a per-pixel one, and $F_j$
makes the estimate the same filtered radiance $\int f L / \int f$ that the path tracer's
weighted average estimates, at the image border too. The driver adds exactly $F_j$ per
(pixel, sample) slot to the film's weight sums, so the film's usual division develops it.

Everything is structure-of-arrays over the light paths and the vertices are one `lax.scan` of
static length; all paths are traced in every segment (terminated ones discarded). The
variates of a path are `[point u0, u1 | direction u0, u1 | light choice, side, -, -]` for the
emission, then `[BSDF u0, u1 | lobe, roulette]` per scattering vertex.

!!! note "Thesis"
    Chapter 9 (bidirectional methods; title only in the text).

??? cite "References"
    `Veach1997` §5.3 (adjoint BSDFs, shading normals), §10.2 (light tracing); `Pharr2023`
    §5.4 (splats), §12.1 (`SampleLe`), §5.2.4 (camera importance); `Jakob2022` (Mitsuba 3's
    `ptracer`).
"""

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

from ..._math import dot
from ._base import AbstractIntegrator, check_path_fields, scene_max_depth
from ._path import _offset, _vertex, shading_frame, shadow_ray

__all__ = ["PTracer", "Splats", "ptracer_sample_dimensions"]

_EMISSION_DIMENSIONS = 8
_DIMENSIONS_PER_VERTEX = 4


def ptracer_sample_dimensions(max_depth: int) -> int:
    """Variates one light path consumes: 8 for the emission, 4 per scattering vertex
    (`max_depth - 2` of them). [1]"""
    return _EMISSION_DIMENSIONS + _DIMENSIONS_PER_VERTEX * max(max_depth - 2, 0)


class Splats(eqx.Module):
    """Film contributions of light-path vertices connected to the camera (arrays `(V, n, ...)`:
    `V` vertices of each of `n` paths).

    **Fields:**

    - `raster`: raster positions `(V, n, 2)`. [px]
    - `value`: the contribution at the path's wavelengths `(V, n, k)`, already divided by
        the densities of the path (the film divides by spp and the filter integral, module
        docstring). [W m^-2 sr^-1 nm^-1]
    - `valid`: `(V, n)` bool.
    """

    raster: Float[Array, "*v n 2"]
    value: Float[Array, "*v n k"]
    valid: Bool[Array, "*v n"]


class PTracer(AbstractIntegrator):
    """Light tracing with splats into the film (Mitsuba 3's `ptracer`; module docstring).

    **Arguments:**

    - `max_depth`: largest number of path segments, camera connection included (Mitsuba's
        meaning; 1 = emitters seen directly), a static int >= 1 (default 8).
    - `rr_depth`: segments after which Russian roulette starts (default 5).
    - `hide_emitters`: do not splat the emitters' own points (emitters seen directly).

    It needs a camera with `sample_wi` (the pinhole camera); every light kind starts light
    paths (area, point, spot, directional, constant, envmap; the environment seen directly
    is not estimated, module docstring); it is rendered through
    `radiometria.render.render`, which gives it the camera. `radiance` (per camera ray) is
    0: all of its estimate is in the splats.

    !!! note "Thesis"
        Chapter 9 (bidirectional methods; title only in the text).

    ??? cite "References"
        `Veach1997` §10.2; `Pharr2023` §5.4; `Jakob2022` (`ptracer`).
    """

    NAME: ClassVar[str] = "ptracer"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"max_depth", "rr_depth", "hide_emitters", "samples_per_pass"}
    )
    SPLATS_ONLY: ClassVar[bool] = True  # no per-camera-ray estimate: the driver skips it
    max_depth: int = eqx.field(static=True, default=8)
    rr_depth: int = eqx.field(static=True, default=5)
    hide_emitters: bool = eqx.field(static=True, default=False)

    def __check_init__(self):
        check_path_fields(self)

    @classmethod
    def from_properties(cls, params: dict, *, where: str = "scene") -> "PTracer":
        """From a scene file's `max_depth` (default 8; -1 = unbounded, taken as
        `DEFAULT_UNBOUNDED_DEPTH`), `rr_depth` (default 5) and `hide_emitters` (default
        false); errors name `where`."""
        unknown = set(params) - cls.PARAMETERS
        if unknown:
            raise ValueError(
                f"{where}: unknown ptracer parameter(s) {sorted(unknown)}; valid: "
                f"{sorted(cls.PARAMETERS)}."
            )
        depth = scene_max_depth(params)
        try:
            return cls(
                max_depth=depth,
                rr_depth=params.get("rr_depth", 5),
                hide_emitters=params.get("hide_emitters", False),
            )
        except (ValueError, TypeError) as e:
            raise type(e)(f"{where}: ptracer: {e}") from None

    def sample_dimensions(self) -> int:
        return ptracer_sample_dimensions(self.max_depth)

    def radiance(self, scene, origins, directions, wavelength_nm, variates, active):
        """0: light tracing estimates nothing per camera ray (see `splats`)."""
        return jnp.zeros(wavelength_nm.shape, origins.dtype)

    def splats(self, scene, camera, wavelength_nm, variates, active) -> Splats:
        """Trace one light path per row of `wavelength_nm` `(n, k)` [nm] (rows where
        `active` is False trace nothing) and connect each vertex to `camera`.

        **Returns:**

        `Splats` of shape `(max_depth, n, ...)`: row 0 the emitters' own points, row `i`
        the `i`-th surface vertex of each path (module docstring for the values).
        """
        dtype = wavelength_nm.dtype
        n, k = wavelength_nm.shape
        paths = jnp.arange(n, dtype=jnp.int32)
        u0 = variates(0, _EMISSION_DIMENSIONS, paths).astype(dtype)
        eye = jnp.broadcast_to(camera.to_world[:3, 3].astype(dtype), (n, 3))
        es = scene.light.sample_le(u0[:, 4], u0[:, 0:2], u0[:, 2:4], u0[:, 5], eye, wavelength_nm)
        ok = active & (es.pdf_pos > 0) & (es.pdf_dir > 0)
        pdf_pos = jnp.where(ok, es.pdf_pos, 1.0)
        has_n = ~es.delta_pos

        def scale_of(p):
            return scene.ray_epsilon * (1.0 + jnp.max(jnp.abs(p), axis=-1))

        def visible(p, normal, cs, surface):
            offset = jnp.where(surface, scale_of(p), 0.0)  # a delta light's point: no surface
            origin, direction, tmax = shadow_ray(p, normal, cs.wi, cs.dist, offset)
            tmax = jnp.where(cs.valid, tmax, 0.0)
            return cs.valid & ~scene.accelerator.intersect_any(origin, direction, tmax)

        # Depth 0: the emitter's own point seen by the camera (not for delta lights).
        cs = camera.sample_wi(es.p)
        cos_l = jnp.abs(dot(es.n, cs.wi))
        v0 = es.le_observer * (cos_l * cs.importance / jnp.where(cs.valid, cs.pdf, 1.0))[:, None]
        v0 = v0 / pdf_pos[:, None]
        ok0 = ok & has_n & visible(es.p, es.n, cs, has_n) & (not self.hide_emitters)
        first = Splats(raster=cs.raster, value=jnp.where(ok0[:, None], v0, 0.0), valid=ok0)

        cos_d = jnp.where(has_n, jnp.abs(dot(es.n, es.d)), 1.0)
        beta = es.le * (cos_d / (pdf_pos * jnp.where(ok, es.pdf_dir, 1.0)))[:, None]
        beta = jnp.where(ok[:, None], beta, 0.0)
        beta_max0 = jnp.maximum(jnp.max(beta, axis=-1), jnp.finfo(dtype).tiny)
        offset = scale_of(es.p)
        o = jnp.where(has_n[:, None], _offset(es.p, es.n, es.d, offset), es.p)
        state = (
            jnp.where(ok[:, None], o, 0.0),
            jnp.where(
                ok[:, None], es.d, jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0], dtype), es.d.shape)
            ),
            beta,
            ok,
            jnp.zeros((n,), bool),  # hero wavelength only (dispersion)
        )

        def vertex(state, i):
            o, d, beta, alive, hero_only = state
            v = _vertex(scene, o, d)
            alive = alive & v.valid
            frame = shading_frame(scene, v)
            alive = alive & frame.scatters
            to_local = frame.to_local
            wo = -d  # towards the light
            wo_l = to_local(wo)
            bsdf = scene.materials.bxdf(frame.material, wavelength_nm, v.uv, frame.geometry)
            wo_ng = jnp.abs(dot(wo, v.n))
            wo_ng = jnp.where(wo_ng > 0, wo_ng, 1.0)

            # Connection to the camera (adjoint BSDF, shading-normal correction).
            cs = camera.sample_wi(v.p)
            f = bsdf.f(wo_l, to_local(cs.wi), mode="importance")
            g = jnp.abs(wo_l[:, 2]) * jnp.abs(dot(cs.wi, v.n)) / wo_ng
            g = g * cs.importance / jnp.where(cs.valid, cs.pdf, 1.0)
            value = beta * f * g[:, None]
            hero = jnp.zeros((1, k), dtype).at[0, 0].set(k)
            value = jnp.where(hero_only[:, None], value[:, :1] * hero, value)
            seen = alive & visible(v.p, v.n, cs, True)
            splat = Splats(cs.raster, jnp.where(seen[:, None], value, 0.0), seen)

            # The next segment: BSDF sample in importance mode, then roulette.
            u = variates(_EMISSION_DIMENSIONS + _DIMENSIONS_PER_VERTEX * (i - 1), 4, paths)
            u = u.astype(dtype)
            bs = bsdf.sample_f(wo_l, u[:, 2], u[:, 0:2], mode="importance")
            wi = frame.to_world(bs.wi)
            wi = wi / jnp.sqrt(jnp.maximum(dot(wi, wi), jnp.finfo(dtype).tiny))[:, None]
            alive = alive & (bs.pdf > 0) & (i < self.max_depth - 1)
            corr = jnp.abs(wo_l[:, 2]) * jnp.abs(dot(wi, v.n)) / wo_ng
            pdf = jnp.where(alive, bs.pdf, 1.0)
            beta = jnp.where(alive[:, None], beta * bs.f * (corr / pdf)[:, None], 0.0)
            q = jnp.minimum(jnp.max(beta, axis=-1) / beta_max0, 0.95)
            roulette = i >= self.rr_depth
            alive = alive & (~roulette | (u[:, 3] < q))
            beta = jnp.where(alive[:, None], beta / jnp.where(roulette, q, 1.0)[:, None], 0.0)
            hero_only = hero_only | (alive & bs.terminate_secondary)
            o = _offset(v.p, v.n, wi, scale_of(v.p))
            o = jnp.where(alive[:, None], o, 0.0)
            wi = jnp.where(
                alive[:, None], wi, jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0], dtype), wi.shape)
            )
            return (o, wi, beta, alive, hero_only), splat

        if self.max_depth == 1:
            return jax.tree.map(lambda x: x[None], first)
        depths = jnp.arange(1, self.max_depth, dtype=jnp.int32)
        _, rest = jax.lax.scan(vertex, state, depths)
        return jax.tree.map(lambda a, b: jnp.concatenate([a[None], b], axis=0), first, rest)
