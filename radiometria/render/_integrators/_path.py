r"""Unidirectional path tracing: `path_radiance` and the `Path` integrator (thesis ch. 8).

`path_radiance` estimates the light transport equation

$$L_o(p, \omega_o) = L_e(p, \omega_o) + \int_{S^2} f(p, \omega_o, \omega_i)\, L_i(p, \omega_i)
  \,|\cos\theta_i|\, d\omega_i$$

for a batch of rays at once, at the four hero wavelengths of each path, by unidirectional
path tracing with next-event estimation (one light sample per vertex), multiple importance
sampling of light and BSDF samples with the power heuristic, and Russian roulette. Depths
follow Mitsuba 3's `path` integrator: `max_depth` is the largest number of path segments
counted from the camera, so `max_depth=1` sees only emitters visible from the camera and
`max_depth=2` is direct illumination (the `Direct` integrator); Russian roulette starts once
`rr_depth` segments have been traced (Mitsuba's default 5), with survival probability
`min(max_lambda beta, 0.95)`. The scene's plugins do the rest: its accelerator finds hits,
its light (`AbstractLight`) samples and weighs next-event estimation, and its materials
(`MaterialSet`) build the BxDF at each hit.

Everything is structure-of-arrays over the ray batch, and the loop over path segments is one
`lax.scan` of static length `max_depth` (one compiled copy of a segment: its hit, the emission
there, and, but for the last segment, next-event estimation, the BSDF sample and roulette).
Within a segment, the live paths are compacted (`_math.compact_indices`: `jnp.nonzero` with a static
size) and traced in chunks of static size by a `lax.fori_loop` whose trip count is the number of
live chunks: terminated paths (escaped, absorbed, killed by roulette, or never started) cost
nothing, and every shape stays static. Random numbers come in as one array `u` of shape `(rays,
sample_dimensions(max_depth))`, so independent and quasi-random samplers feed the same code.

**Derivatives.** Radiance estimates are differentiable in the scene's spectra (reflectance and
emission rows of the `SpectrumTable`s, hence in the RGB colours or temperatures they are
computed from): for fixed variates `u` (common random numbers) the estimate is a smooth
function of them, since the sampling decisions (cosine-weighted BSDF samples, the light
distribution of next-event estimation, fixed when the scene is compiled) do not depend on
them. Forward mode (`jax.jvp`, `jax.jacfwd`) works through the compacted loop. Reverse mode
(`jax.grad`, `jax.vjp`) cannot pass through a loop whose trip count is traced (the number of
live chunks), so `path_radiance(..., compact=False)` traces every path of the batch in each
segment (paths already terminated are traced too and their results discarded), a loop of
static length that reverse mode differentiates. Russian roulette's survival probability is a
sampling decision: its derivative is detached (`lax.stop_gradient`, as Mitsuba 3's
differentiable integrators `dr.detach` it), so the derivative of a surviving path is
$\partial(\beta/q) = \partial\beta / q$, whose expectation is the derivative of the
expectation. (The derivative of the estimate for fixed `u` would add $-\beta\,\partial q/q^2$
and miss the jump where the decision flips, a biased gradient.) Without roulette
(`rr_depth >= max_depth`) the derivative is exactly that of the estimate for fixed `u`, which
`tests/render/test_gradients.py` checks against central finite differences.

Per bounce the eight variates are used as `[light point u0, u1 | BSDF u0, u1 | light choice,
BSDF lobe | roulette, unused]`, so each 2D sample is one aligned pair of dimensions (what a
padded Sobol sampler stratifies).
"""

import functools
from collections.abc import Callable
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

from ..._math import compact_indices, dot
from ...montecarlo import power_heuristic
from ...scattering import coordinate_system
from .._materials import HitGeometry
from .._render_scene import RenderScene
from ._base import AbstractIntegrator, check_path_fields, scene_flag, scene_max_depth

__all__ = ["DIMENSIONS_PER_BOUNCE", "Path", "path_radiance", "sample_dimensions"]

DIMENSIONS_PER_BOUNCE = 8


def sample_dimensions(max_depth: int) -> int:
    """Number of uniform variates one path of the integrators consumes, camera excluded.

    **Arguments:**

    - `max_depth`: the largest number of path segments. [1]

    **Returns:**

    `8 (max_depth - 1)`: eight variates per scattering vertex (module docstring). [1]

    !!! note "Thesis"
        Chapters 5-6: the dimension of the path-space integrand seen by a sampler.
    """
    return DIMENSIONS_PER_BOUNCE * max(max_depth - 1, 0)


def _offset(p, n, w, scale):
    """Move `p` off its surface, to the side of the normal `n` that `w` points into."""
    side = jnp.where(dot(n, w) >= 0, 1.0, -1.0).astype(p.dtype)
    return p + (side * scale)[..., None] * n


def shadow_ray(p, n, wi, dist, scale):
    """`(origin, direction, tmax)` of the shadow ray from a surface point `p` (normal `n`) to
    the point `p + dist wi` (`dist` [scene units], infinite for a light at infinity).

    The origin moves off the surface by `scale` along `n` (`_offset`), and the ray is aimed
    from there at the target, ending a relative 1e-4 short of it (pbrt-v4's `SpawnRayTo`).
    Keeping the direction `wi` from the moved origin would shift the ray parallel to itself,
    and where the target's surface is oblique to it (points near a curved emitter's
    silhouette) the shifted ray meets that surface before `tmax`: the sample would be
    counted as occluded by its own emitter, darkening next-event estimation (by 9 % under a
    sphere light, measured against its closed-form irradiance in the tests). `scale` may be
    0 (a point in a medium: no surface to leave)."""
    origin = _offset(p, n, wi, scale)
    finite = jnp.isfinite(dist)
    target = p + wi * jnp.where(finite, dist, 0.0)[:, None]
    d = target - origin
    length = jnp.sqrt(jnp.maximum(dot(d, d), jnp.finfo(p.dtype).tiny))
    direction = jnp.where(finite[:, None], d / length[:, None], wi)
    return origin, direction, jnp.where(finite, length * (1.0 - 1e-4), jnp.inf)


class _Vertex(eqx.Module):
    """A surface hit of a batch of rays (arrays of shape (n,) / (n, 3))."""

    valid: Array  # hit something
    p: Array  # position
    n: Array  # geometric normal of the face (winding order), unit
    face: Array  # int32, clipped to a valid index when not `valid`
    t: Array  # ray parameter of the hit
    cos_o: Array  # cos between n and -ray direction (> 0: the ray hit the front face)
    uv: Array  # (n, c) surface coordinates for textures (RenderScene.surface_width)
    ns: Array  # shading normal: interpolated vertex normals (RenderScene.shading_normal), or n


def _vertex(scene: RenderScene, origins, directions, tmax=None) -> _Vertex:
    """The closest hit of each ray (unbounded, or within `tmax`: 0 skips a ray) with its
    point, normals, uv and the cosine with the ray."""
    n_rays = origins.shape[0]
    if tmax is None:
        tmax = jnp.full((n_rays,), jnp.inf, dtype=origins.dtype)
    hit = scene.accelerator.intersect_closest(origins, directions, tmax)
    t = hit.t
    valid = hit.prim >= 0
    face = jnp.where(valid, hit.prim, 0)
    b1 = hit.b1[:, None].astype(origins.dtype)
    b2 = hit.b2[:, None].astype(origins.dtype)
    p = scene.p0[face] + b1 * scene.e1[face] + b2 * scene.e2[face]
    n = scene.normal[face]
    uv = jnp.concatenate([b1, b2], axis=-1)  # Mitsuba's uv of a mesh without uvs
    if scene.face_uv is not None:
        c = scene.face_uv[face]
        uv = (1.0 - b1 - b2) * c[:, 0] + b1 * c[:, 1] + b2 * c[:, 2]
    if scene.face_attributes is not None:  # mesh_attribute textures: barycentrics, corners
        uv = jnp.concatenate([uv, b1, b2, scene.face_attributes[face].astype(uv.dtype)], -1)
    ns = n
    if scene.shading_normal is not None:  # Mitsuba's vertex normals, interpolated
        c = scene.shading_normal[face]
        ns = (1.0 - b1 - b2) * c[:, 0] + b1 * c[:, 1] + b2 * c[:, 2]
        length = jnp.sqrt(dot(ns, ns))[:, None]
        ns = jnp.where(length > 0, ns / jnp.where(length > 0, length, 1.0), n)
    if scene.spheres is not None:  # hits on analytic spheres: the true sphere's geometry
        s = scene.face_sphere[face]
        on_sphere = (valid & (s >= 0))[:, None]
        t_s = jnp.where(on_sphere[:, 0], t, 0.0).astype(origins.dtype)[:, None]
        p_s, n_s, uv_s = scene.spheres.surface(jnp.maximum(s, 0), origins + t_s * directions)
        p = jnp.where(on_sphere, p_s.astype(p.dtype), p)
        n = jnp.where(on_sphere, n_s.astype(n.dtype), n)
        ns = jnp.where(on_sphere, n_s.astype(ns.dtype), ns)
        uv_hit = jnp.where(on_sphere, uv_s.astype(uv.dtype), uv[:, :2])
        uv = uv_hit if uv.shape[1] == 2 else jnp.concatenate([uv_hit, uv[:, 2:]], axis=-1)
    return _Vertex(valid=valid, p=p, n=n, face=face, t=t, cos_o=-dot(n, directions), uv=uv, ns=ns)


def surface_tangents(scene: RenderScene, face, normal) -> tuple[Array, Array]:
    """dp/du and dp/dv of the hit triangles `(n, 3)` [scene units per uv unit], as Mitsuba's
    meshes: from the corners' uv (`RenderScene.face_uv`), or the edges when the mesh has no
    uv (uv = barycentrics); a triangle with degenerate uv gets a frame around `normal`. On an
    analytic sphere (`RenderScene.spheres`), the sphere's, where its geometric normal is
    `normal`."""
    dpdu, dpdv = _triangle_tangents(scene, face, normal)
    if scene.spheres is None:
        return dpdu, dpdv
    s = scene.face_sphere[face]
    du, dv = scene.spheres.tangents(jnp.maximum(s, 0), normal)
    on_sphere = (s >= 0)[:, None]
    return (
        jnp.where(on_sphere, du.astype(dpdu.dtype), dpdu),
        jnp.where(on_sphere, dv.astype(dpdv.dtype), dpdv),
    )


def _triangle_tangents(scene: RenderScene, face, normal) -> tuple[Array, Array]:
    """dp/du and dp/dv of triangles (`surface_tangents`)."""
    e1, e2 = scene.e1[face], scene.e2[face]
    if scene.face_uv is None:
        return e1, e2
    c = scene.face_uv[face].astype(e1.dtype)
    d0, d1 = c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]
    det = d0[:, 0] * d1[:, 1] - d0[:, 1] * d1[:, 0]
    ok = (jnp.abs(det) > 1e-12)[:, None]
    inv = 1.0 / jnp.where(ok[:, 0], det, 1.0)[:, None]
    dpdu = (d1[:, 1:2] * e1 - d0[:, 1:2] * e2) * inv
    dpdv = (-d1[:, 0:1] * e1 + d0[:, 0:1] * e2) * inv
    s, t = coordinate_system(normal)
    return jnp.where(ok, dpdu, s), jnp.where(ok, dpdv, t)


def path_radiance(
    scene: RenderScene,
    origins: Float[Array, "n 3"],
    directions: Float[Array, "n 3"],
    wavelength_nm: Float[Array, "n k"],
    u: Float[Array, "n d"] | Callable[[Array, Array], Float[Array, "m 8"]],
    *,
    max_depth: int,
    rr_depth: int = 5,
    chunk: int | None = None,
    active: Bool[Array, " n"] | None = None,
    compact: bool = True,
    hide_emitters: bool = False,
) -> Float[Array, "n k"]:
    r"""Spectral radiance arriving along each ray, by path tracing with NEE, MIS and roulette.

    **Arguments:**

    - `scene`: the compiled scene (`RenderScene`).
    - `origins`, `directions`: camera rays, `(n, 3)`; directions unit length. [scene units]
    - `wavelength_nm`: the wavelengths of each path, `(n, k)` (k = 4 hero wavelengths). [nm]
    - `u`: uniform variates in [0, 1): an array `(n, sample_dimensions(max_depth))`, whose
        columns `8 b .. 8 b + 7` serve bounce `b`; or a function `u(b, paths)` returning those
        eight variates `(m, 8)` for the paths with indices `paths` (int32 `(m,)`; indices
        `>= n` are padding), so that a sampler can generate them for live paths only. [1]
    - `max_depth`: largest number of path segments (Mitsuba's meaning), a static int >= 1.
    - `rr_depth`: number of segments after which Russian roulette starts (static int >= 1);
        a value >= `max_depth` turns roulette off.
    - `chunk`: paths traced together within a bounce (static; default 2048 on CPUs, a quarter
        of the batch on accelerators). Each bounce traces only the live paths, gathered into
        chunks of this size, so the cost follows the live paths; the result does not depend
        on it.
    - `active`: optional `(n,)` booleans; paths where it is False are not traced at all
        (they cost nothing and return 0).
    - `compact`: trace only the live paths of each segment (default). `False` traces every
        path in every segment and discards the results of terminated ones: the same estimate
        (up to float rounding), slower once paths terminate, but differentiable in reverse
        mode (`jax.grad`); forward mode (`jax.jacfwd`) works either way (module docstring).
    - `hide_emitters`: emitters seen directly along the given rays (segment 0: area lights
        hit and lights at infinity seen by escaping rays) contribute nothing (Mitsuba's
        `hide_emitters`); their light still reaches the scene. Static bool, default False.

    **Returns:**

    Radiance estimates `(n, k)` at `wavelength_nm` [W m^-2 sr^-1 nm^-1, or the unit of the
    scene's emission spectra].

    !!! note "Thesis"
        Chapter 8 (light transport; title only in the text): the path integral form of the
        rendering equation, estimated with the methods of chapters 6-7.

    ??? cite "References"
        `Veach1997` ch. 9-10 (MIS, power heuristic); `Arvo1990` (Russian roulette);
        `Pharr2023` §13.4 (`PathIntegrator`); `Wilkie2014` (hero wavelengths);
        `Jakob2022` (Mitsuba 3's `path` integrator: depth and roulette conventions).
    """
    if isinstance(max_depth, bool) or not isinstance(max_depth, int) or max_depth < 1:
        raise ValueError(f"`max_depth` must be an int >= 1, got {max_depth!r}.")
    if isinstance(rr_depth, bool) or not isinstance(rr_depth, int) or rr_depth < 1:
        raise ValueError(f"`rr_depth` must be an int >= 1, got {rr_depth!r}.")
    if not isinstance(compact, bool):
        raise TypeError(f"`compact` must be a bool, got {compact!r}.")
    if not isinstance(hide_emitters, bool):
        raise TypeError(f"`hide_emitters` must be a bool, got {hide_emitters!r}.")
    n_rays = origins.shape[0]
    if callable(u):
        sample = u
    else:
        dims = sample_dimensions(max_depth)
        if u.shape != (n_rays, dims):
            raise ValueError(
                f"`u` must have shape (rays, {dims}) = {(n_rays, dims)} for "
                f"max_depth={max_depth}, got {u.shape}."
            )

        def sample(b, paths):
            cols = jax.lax.dynamic_slice_in_dim(
                u, b * DIMENSIONS_PER_BOUNCE, DIMENSIONS_PER_BOUNCE, 1
            )
            return jnp.take(cols, paths, axis=0, mode="clip")

    dtype = origins.dtype
    k = wavelength_nm.shape[-1]
    alive = jnp.ones((n_rays,), bool) if active is None else jnp.asarray(active, bool)
    state = _PathState(
        o=origins,
        d=directions,
        beta=jnp.ones((n_rays, k), dtype),
        radiance=jnp.zeros((n_rays, k), dtype),
        alive=alive,
        pdf=jnp.zeros((n_rays,), dtype),
        specular=jnp.ones((n_rays,), bool),  # camera rays: emission seen with MIS weight 1
        eta_scale=jnp.ones((n_rays,), dtype),
        hero_only=jnp.zeros((n_rays,), bool),
        escaped=jnp.zeros((n_rays,), bool),
    )
    chunk = _default_chunk(n_rays) if chunk is None else min(int(chunk), n_rays)
    n_pad = -(-n_rays // chunk) * chunk

    def one_segment_all(state: _PathState, b):
        # Every path, live or not: a loop of static length, which reverse mode differentiates.
        # Terminated paths get a harmless ray and zero throughput, so that their (discarded)
        # computation stays finite and passes no NaN into the cotangents.
        alive = state.alive
        traced = eqx.tree_at(
            lambda s: (s.o, s.d, s.beta),
            state,
            (
                jnp.where(alive[:, None], state.o, 0.0),
                jnp.where(alive[:, None], state.d, jnp.asarray([0.0, 0.0, 1.0], dtype)),
                jnp.where(alive[:, None], state.beta, 0.0),
            ),
        )
        paths = jnp.arange(n_rays, dtype=jnp.int32)
        new = _segment(
            scene,
            traced,
            wavelength_nm,
            functools.partial(sample, b, paths),
            b,
            max_depth=max_depth,
            rr_depth=rr_depth,
            hide_emitters=hide_emitters,
        )

        def keep(x, old):
            return jnp.where(alive.reshape(alive.shape + (1,) * (x.ndim - 1)), x, old)

        return jax.tree.map(keep, new, state), None

    def one_segment(state: _PathState, b):
        # Stream compaction: only live paths are traced, in chunks of static size, so the
        # work per segment follows the number of live paths, not the batch.
        live = compact_indices(state.alive, n_pad, n_rays)
        n_chunks = (jnp.sum(state.alive, dtype=jnp.int32) + chunk - 1) // chunk

        def one_chunk(i, state):
            sel = jax.lax.dynamic_slice_in_dim(live, i * chunk, chunk)
            take = functools.partial(jnp.take, indices=sel, axis=0, mode="clip")
            new = _segment(
                scene,
                jax.tree.map(take, state),
                take(wavelength_nm),
                functools.partial(sample, b, sel),
                b,
                max_depth=max_depth,
                rr_depth=rr_depth,
                hide_emitters=hide_emitters,
                prune=True,
            )
            return jax.tree.map(lambda a, x: a.at[sel].set(x, mode="drop"), state, new)

        return jax.lax.fori_loop(0, n_chunks, one_chunk, state), None

    segments = jnp.arange(max_depth, dtype=jnp.int32)
    state, _ = jax.lax.scan(one_segment if compact else one_segment_all, state, segments)
    return final_radiance(scene, state, wavelength_nm)


def final_radiance(scene: RenderScene, state, wavelength_nm) -> Float[Array, "n k"]:
    """The estimate of each path after its last segment: the radiance it gathered, plus
    what the lights at infinity give the paths that escaped (`escaped_radiance`), with the
    secondary wavelengths of paths through a dispersive interface dropped.

    The escape's lookup runs only when some path escaped, and inside a `lax.cond`: a
    branch's result is stored, so the lookup runs once per path instead of being fused into
    (and recomputed by) each consumer, such as the film's reduction of the k wavelengths to
    X, Y and Z (measured on the envmap benchmark: 12 ms per step of 65536 paths fused there).
    A path that kept only its hero wavelength is the hero's estimate alone, weighted as one
    wavelength out of k (pbrt's `TerminateSecondary`). Shared by `path` and `volpath`."""
    radiance = state.radiance + jax.lax.cond(
        jnp.any(state.escaped),
        lambda: escaped_radiance(scene, state, wavelength_nm),
        lambda: jnp.zeros_like(state.radiance),
    )
    k = radiance.shape[-1]
    hero = jnp.zeros((1, k), radiance.dtype).at[0, 0].set(k)
    return jnp.where(state.hero_only[:, None], radiance[:, :1] * hero, radiance)


def record_escape(new, escaped, d, beta, pdf, specular):
    """`new` (the state after a segment) with the paths flagged `escaped` keeping the
    direction `d`, throughput `beta`, BSDF density `pdf` and delta flag `specular` of the
    segment they escaped along, and flagged `escaped` (for `escaped_radiance`)."""

    def at_escape(x, old):
        return jnp.where(escaped.reshape(escaped.shape + (1,) * (x.ndim - 1)), old, x)

    return eqx.tree_at(
        lambda s: (s.d, s.beta, s.pdf, s.specular, s.escaped),
        new,
        (
            at_escape(new.d, d),
            at_escape(new.beta, beta),
            at_escape(new.pdf, pdf),
            at_escape(new.specular, specular),
            new.escaped | escaped,
        ),
    )


def escaped_radiance(scene: RenderScene, state, wavelength_nm) -> Float[Array, "n k"]:
    """What the lights at infinity (`constant`, `envmap`) add to paths that left the scene:
    `beta L_e(d) w` for the paths flagged `state.escaped`, where `d`, `beta`, `pdf` and
    `specular` are those of the escaping segment and `w` weighs the escape against
    next-event estimation of the same direction (power heuristic; 1 after a delta lobe or
    from the camera).

    A path escapes at most once (it ends there), so the segments only record the escape and
    this looks the light up once per path, after the segment loop, instead of once per
    traced path in every segment (where most lanes hit a surface and the lookup, an image
    map's four texels and its distribution's density, would be thrown away)."""
    esc = state.escaped
    le = scene.light.emitted_escaped(state.d, esc, wavelength_nm)
    pdf_light = scene.light.pdf_escaped(state.d)
    w = jnp.where(state.specular, 1.0, power_heuristic(1, state.pdf, 1, pdf_light))
    return jnp.where(esc[:, None], state.beta * le * w[:, None], 0.0)


def _default_chunk(n_rays: int) -> int:
    """Paths per compacted chunk: 2048 on CPUs (the chunk's (paths, triangles) temporaries of
    brute-force intersection stay in cache: measured twice as fast as 8192), a quarter of the
    batch (at least 65536) on accelerators. Grid media need no smaller chunks: their tracking
    loops compact the walks still going into fewer lanes as others end
    (`radiometria.media._grid._staged_loop`); before that, chunks of 256 paths were used
    there, each waiting for its longest walk."""
    if jax.default_backend() == "cpu":
        return min(n_rays, 2048)
    return min(n_rays, max(65536, -(-n_rays // 4)))


class _PathState(eqx.Module):
    """The state of a batch of paths between segments (arrays with a leading path axis)."""

    o: Array  # origin of the next segment (n, 3)
    d: Array  # its unit direction (n, 3)
    beta: Array  # path throughput (n, k)
    radiance: Array  # radiance gathered so far (n, k)
    alive: Array  # bool (n,)
    pdf: Array  # solid-angle density of the BSDF sample that chose `d` (n,)
    specular: Array  # bool (n,): `d` came from the camera or a delta lobe (no MIS)
    eta_scale: Array  # (n,): product of eta^2 over refractions, for roulette (Mitsuba, pbrt)
    hero_only: Array  # bool (n,): secondary wavelengths terminated by dispersion
    # bool (n,): the path left the scene; `d`, `beta`, `pdf` and `specular` stay those of the
    # escaping segment, for `escaped_radiance` after the loop.
    escaped: Array


def _segment(
    scene: RenderScene,
    state: _PathState,
    wavelength_nm,
    sample,
    b,
    *,
    max_depth,
    rr_depth,
    hide_emitters=False,
    prune=False,
) -> _PathState:
    """Trace segment `b` of every path: its hit and the emission found there (MIS-weighted
    against next-event estimation), then, unless it is the last segment, the vertex's light
    sample (NEE), its BSDF sample (the next segment) and Russian roulette."""
    v = _vertex(scene, state.o, state.d)
    le = scene.light.emitted(v.face, v.cos_o, v.valid, wavelength_nm, v.uv)
    pdf_light = scene.light.pdf_li(v.face, v.t, v.cos_o, state.o)
    w = jnp.where(state.specular, 1.0, power_heuristic(1, state.pdf, 1, pdf_light))
    if hide_emitters:  # emitters seen directly from the camera are black (Mitsuba)
        w = jnp.where(b == 0, 0.0, w)
    radiance = state.radiance + jnp.where(v.valid[:, None], state.beta * le * w[:, None], 0.0)
    # A ray that leaves the scene sees the lights at infinity (constant, envmap), weighted
    # against next-event estimation of the same direction like a hit on an emitter: recorded
    # here and looked up once per path after the loop (`escaped_radiance`).
    escaped = state.alive & ~v.valid
    if hide_emitters:
        escaped = escaped & (b > 0)
    pre = state
    state = eqx.tree_at(lambda s: (s.radiance, s.alive), state, (radiance, state.alive & v.valid))
    if max_depth == 1:
        new = eqx.tree_at(lambda s: s.alive, state, jnp.zeros_like(state.alive))
    else:
        new = jax.lax.cond(
            b < max_depth - 1,
            lambda: _scatter(
                scene, state, v, wavelength_nm, sample(), roulette=b >= rr_depth - 1, prune=prune
            ),
            lambda: eqx.tree_at(lambda s: s.alive, state, jnp.zeros_like(state.alive)),
        )
    return record_escape(new, escaped, pre.d, pre.beta, pre.pdf, pre.specular)


class ShadingFrame(eqx.Module):
    """The local frame at a batch of hits: the material, the shading normal `n` and tangents
    `s`, `t` (rows `(n, 3)`), whether the side hit scatters, and the local dp/du, dp/dv and
    geometric normal for normal and bump maps (`None` when no material needs them)."""

    material: Array
    s: Array
    t: Array
    n: Array
    scatters: Array  # bool (n,)
    geometry: HitGeometry | None

    def to_local(self, w):
        return jnp.stack([dot(w, self.s), dot(w, self.t), dot(w, self.n)], axis=-1)

    def to_world(self, w):
        return w[:, 0:1] * self.s + w[:, 1:2] * self.t + w[:, 2:3] * self.n


def shading_frame(scene: RenderScene, v: _Vertex) -> ShadingFrame:
    """The shading frame at the hits `v`, as Mitsuba builds it.

    The shading normal (interpolated vertex normals, else the face normal) is flipped towards
    the arriving ray for two-sided reflectors. A ray arriving at the back of a one-sided
    reflector ends there (Mitsuba's one-sided BSDFs: `scatters` is False); dielectrics keep the
    normal, and wo below it means the ray is inside. Which side was hit, and where rays leave
    from, follow the geometric normal (no light leaks through a surface; Mitsuba and pbrt
    alike). With normal or bump maps, and with anisotropic BSDFs
    (`MaterialSet.tangent_frame`), the tangent `s` follows dp/du (Mitsuba's frame); else any
    frame around the normal serves.
    """
    material = scene.face_material[v.face]
    two_sided = scene.materials.two_sided[material]
    transmissive = scene.materials.transmissive[material]
    front = v.cos_o > 0
    flip = (two_sided & ~front & ~transmissive)[:, None]
    n = jnp.where(flip, -v.ns, v.ns)
    scatters = front | two_sided | transmissive
    if not (scene.materials.needs_geometry or scene.materials.tangent_frame):
        s, t = coordinate_system(n)
        return ShadingFrame(material, s, t, n, scatters, None)
    dpdu, dpdv = surface_tangents(scene, v.face, v.n)
    s = dpdu - n * dot(n, dpdu)[:, None]
    s_len = jnp.sqrt(dot(s, s))[:, None]
    s = jnp.where(s_len > 1e-12, s / jnp.where(s_len > 1e-12, s_len, 1.0), coordinate_system(n)[0])
    t = jnp.cross(n, s)
    if not scene.materials.needs_geometry:
        return ShadingFrame(material, s, t, n, scatters, None)
    local = ShadingFrame(material, s, t, n, scatters, None).to_local
    ng = jnp.where(flip, -v.n, v.n)
    geometry = HitGeometry(local(dpdu), local(dpdv), local(ng))
    return ShadingFrame(material, s, t, n, scatters, geometry)


def _scatter(
    scene: RenderScene, state: _PathState, v: _Vertex, wavelength_nm, u_b, roulette, prune=False
):
    """At the hit `v`: next-event estimation, BSDF sampling of the next segment, roulette.
    With `prune`, a path whose throughput is zero at every wavelength (a black BSDF) ends
    here, as in Mitsuba: it would add nothing (`compact` loops only; the static loop of
    reverse mode keeps it, so that derivatives through a zero reflectance survive)."""
    beta, radiance = state.beta, state.radiance
    wo = -state.d
    frame = shading_frame(scene, v)
    alive = state.alive & frame.scatters
    to_local, to_world = frame.to_local, frame.to_world
    wo_l = to_local(wo)
    bsdf = scene.materials.bxdf(frame.material, wavelength_nm, v.uv, frame.geometry)
    offset = scene.ray_epsilon * (1.0 + jnp.max(jnp.abs(v.p), axis=-1))

    # Next-event estimation: a point on a light (e.g. an emissive triangle chosen by power x
    # area, then a uniform point on it) or a direction to a light at infinity (unbounded
    # shadow ray), weighted against BSDF sampling by MIS (delta lights: weight 1).
    # The BSDF's three queries at once (one pass per material kind in a mixed scene).
    ls = scene.light.sample_li(v.p, u_b[:, 4], u_b[:, 0:2], wavelength_nm)
    wi_l = to_local(ls.wi)
    f_light, pdf_bsdf, bs = bsdf.f_pdf_sample(wo_l, wi_l, u_b[:, 5], u_b[:, 2:4])
    f_light = f_light * jnp.abs(wi_l[:, 2:3])
    w_light = power_heuristic(1, ls.pdf, 1, pdf_bsdf)
    if ls.delta is not None:  # a delta light (point, spot, directional): no BSDF sample finds it
        w_light = jnp.where(ls.delta, 1.0, w_light)
    use = alive & (ls.pdf > 0)
    origin, direction, shadow_tmax = shadow_ray(v.p, v.n, ls.wi, ls.dist, offset)
    shadow_tmax = jnp.where(use, shadow_tmax, 0.0)
    use = use & ~scene.accelerator.intersect_any(origin, direction, shadow_tmax)
    nee = beta * f_light * ls.radiance * (w_light / jnp.where(use, ls.pdf, 1.0))[:, None]
    radiance = radiance + jnp.where(use[:, None], nee, 0.0)

    # BSDF sampling (`bs`): the next path segment.
    alive = alive & (bs.pdf > 0)
    weight = bs.f * (jnp.abs(bs.wi[:, 2]) / jnp.where(alive, bs.pdf, 1.0))[:, None]
    beta = jnp.where(alive[:, None], beta * weight, 0.0)
    wi = to_world(bs.wi)
    wi = wi / jnp.sqrt(dot(wi, wi))[:, None]

    # Russian roulette: survive with probability q = min(max_lambda beta eta^2, 0.95);
    # survivors are reweighted by 1/q (Mitsuba's rule).
    eta_scale = state.eta_scale * jnp.where(bs.is_transmission, bs.eta * bs.eta, 1.0)
    # q is a sampling decision: its derivative is detached (module docstring, "Derivatives").
    q = jax.lax.stop_gradient(jnp.minimum(jnp.max(beta, axis=-1) * eta_scale, 0.95))
    alive = alive & (~roulette | (u_b[:, 6] < q))
    beta = jnp.where(alive[:, None], beta / jnp.where(alive & roulette, q, 1.0)[:, None], 0.0)
    if prune:
        alive = alive & jnp.any(beta != 0, axis=-1)
    return _PathState(
        o=_offset(v.p, v.n, wi, offset),
        d=wi,
        beta=beta,
        radiance=radiance,
        alive=alive,
        pdf=bs.pdf,
        specular=bs.is_delta,
        eta_scale=eta_scale,
        hero_only=state.hero_only | (alive & bs.terminate_secondary),
        escaped=state.escaped,
    )


class Path(AbstractIntegrator):
    """Unidirectional path tracing with next-event estimation, MIS and Russian roulette
    (Mitsuba 3's `path` integrator; `path_radiance`).

    **Arguments:**

    - `max_depth`: largest number of path segments (Mitsuba's meaning: 1 = emitters seen
        directly, 2 = direct illumination), a static int >= 1 (default 8).
    - `rr_depth`: number of segments after which Russian roulette starts (Mitsuba's
        `rr_depth`, default 5); a value >= `max_depth` turns roulette off.
    - `hide_emitters`: emitters seen directly from the camera are black (Mitsuba's
        `hide_emitters`, default False); static bool.

    !!! note "Thesis"
        Chapter 8 (light transport; title only in the text), estimated with the methods of
        chapters 6-7.

    ??? cite "References"
        `Veach1997` ch. 9-10; `Pharr2023` §13.4; `Jakob2022` (`path`).
    """

    NAME: ClassVar[str] = "path"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"max_depth", "rr_depth", "hide_emitters"})
    max_depth: int = eqx.field(static=True, default=8)
    rr_depth: int = eqx.field(static=True, default=5)
    hide_emitters: bool = eqx.field(static=True, default=False)

    def __check_init__(self):
        check_path_fields(self)

    @classmethod
    def from_properties(cls, params: dict, *, where: str = "scene") -> "Path":
        """From a scene file's `max_depth` (default 8; -1 = unbounded, taken as
        `DEFAULT_UNBOUNDED_DEPTH`), `rr_depth` (default 5) and `hide_emitters` (default
        false)."""
        hide = scene_flag(params, "hide_emitters", False, where)
        return cls(
            max_depth=scene_max_depth(params),
            rr_depth=params.get("rr_depth", 5),
            hide_emitters=hide,
        )

    def sample_dimensions(self) -> int:
        return sample_dimensions(self.max_depth)

    def radiance(self, scene, origins, directions, wavelength_nm, variates, active):
        def u(b, paths):
            first = DIMENSIONS_PER_BOUNCE * b
            return variates(first, DIMENSIONS_PER_BOUNCE, paths)

        return path_radiance(
            scene,
            origins,
            directions,
            wavelength_nm,
            u,
            max_depth=self.max_depth,
            rr_depth=self.rr_depth,
            active=active,
            hide_emitters=self.hide_emitters,
        )
