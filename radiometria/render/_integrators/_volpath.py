r"""Volumetric path tracing: `volpath_radiance` and the `VolPath` integrator (thesis ch. 9).

`volpath_radiance` estimates the volume rendering equation (the light transport equation with
participating media between surfaces),

$$L(\mathbf x, \omega) = \int_0^{d} T(t)\,\sigma_s(\mathbf x_t)\int_{S^2} p(\omega', \omega)
  L(\mathbf x_t, \omega')\,d\omega'\,dt + T(d)\,L_o(\mathbf x_d, \omega),
  \qquad T(t) = e^{-\int_0^t \sigma_t},$$

for a batch of rays at the four hero wavelengths of each path, by unidirectional path tracing
with next-event estimation at surface and medium vertices, multiple importance sampling of
light samples against BSDF and phase-function samples (power heuristic, on solid-angle
densities: the transmittance factors are common to both strategies), and Russian roulette,
with Mitsuba 3's `volpath` conventions (`max_depth` counts scattering vertices, surface or
medium, plus one; `rr_depth`; `hide_emitters`).

**Media along a segment.** A segment starts at a vertex in the path's current medium and
walks along its ray: each intersection with a `null` surface (an index-matched boundary) is
crossed without counting a bounce, switching the medium by the surface's `interior` /
`exterior` indices (the interior lies against the triangle's normal), for at most
`max_null` crossings (a static bound; a path still walking after them is ended). On each piece
in a medium the distance to the next interaction is sampled by the medium
(`radiometria.media.AbstractMedium.sample_free_flight`): for homogeneous media in closed form
from the single-sample mixture over the path's wavelengths (spectral MIS with the balance
heuristic, `Wilkie2014`; pbrt-v4's `VolPathIntegrator`), whose weights keep every wavelength
unbiased, so chromatic media need no hero-only fallback; grids use weighted delta tracking.
A sampled interaction becomes a medium vertex (the albedo is carried in the weight, absorption
is not sampled as a path end); otherwise the ray reaches the next surface, where emission is
gathered, or escapes, and the lights at infinity are looked up once per path after the last
segment with that segment's throughput and densities (`_path.final_radiance`). Shadow rays
of next-event estimation pass through `null` surfaces in the same way, multiplying the
transmittance of each piece (exact for homogeneous media, ratio tracking for grids); any other
surface blocks them. A surface with `interior`/`exterior` indices and a real BSDF (a
dielectric) changes the medium when a sampled direction crosses it.

**Spectral MIS.** A path carries `k` wavelengths but samples one distance per free flight;
how the `k` per-wavelength densities $p_j$ of that sample are combined is `spectral_mis`
(homogeneous media; grids always use weighted delta tracking). `"segment"` (`volpath`): each
free flight draws its wavelength afresh and is weighted by the one-sample balance heuristic
of that flight alone, $f_j / \frac1k\sum_i p_i$. `"path"` (`volpathmis`, `Miller2019`, Mitsuba
3's `volpathmis`): the wavelength $c$ is drawn once per path and every contribution is
weighted by the balance heuristic over whole paths, $F_j / \frac1k\sum_i P_i$ with
$P_i = \prod p_i$ over the path's free flights, kept as normalised ratios
$r_i = P_i / \frac1k\sum P$ (`_VolState.mis`), so a flight's weight is
$f_j / \frac1k\sum_i r_i p_i$ (bounded by `k` over the whole path, where per-segment weights
are bounded by `k` per segment). `"none"` (`volpathmis` with `use_spectral_mis=false`, and
Mitsuba's `volpath` in spectral variants): wavelength $c$ once per path, weight $f_j / p_c$.
All three are unbiased at every wavelength and differ only in variance.

**Variates.** Per scattering vertex the eight variates of `path_radiance` (`[light point u0,
u1 | BSDF or phase u0, u1 | light choice, BSDF lobe | roulette, unused]`, at the same
dimensions as `Path`, so that on a scene without media `volpath` consumes exactly the
variates of `path` and renders the same image), then four per segment after all those:
`[free flight, seed of the further free flights and tracking steps, the path's free-flight
wavelength (first segment, "path"/"none"), unused]`.
Variates beyond the first free flight of a segment come from hashing the seed with the step
(`pcg4d`, `Jarzynski2020`).

**Derivatives.** As in `path_radiance`: with `compact=False` reverse mode passes through
every loop (they have static trip counts then). Free-flight distances are sampling decisions:
they are drawn with detached coefficients and the weight is reattached as
$w\,f/\mathrm{sg}(f)$, $f = \sigma_s e^{-\sigma_t t}$ at an interaction or $e^{-\sigma_t d}$
past the segment, so the derivative of the estimate w.r.t. `sigma_t` and `albedo` is unbiased
(Mitsuba 3's detached sampling in its differentiable volumetric integrators,
`Nimier-David2022`); shadow-ray transmittances are differentiated directly.
"""

import functools
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

from ..._bits import pcg4d, uint32_to_unit_float
from ..._math import dot
from ...media import HomogeneousMedium
from ...montecarlo import power_heuristic
from .._materials._null import has_null, is_null
from .._media import KEEP_MEDIUM, MediumSet
from .._render_scene import RenderScene
from ._base import AbstractIntegrator, check_path_fields, scene_flag, scene_max_depth
from ._path import (
    DIMENSIONS_PER_BOUNCE,
    _default_chunk,
    _offset,
    _Vertex,
    _vertex,
    final_radiance,
    record_escape,
    shading_frame,
    shadow_ray,
)
from ._segments import run_segments

__all__ = [
    "MEDIUM_DIMENSIONS",
    "SPECTRAL_MIS",
    "VolPath",
    "volpath_radiance",
    "volpath_sample_dimensions",
]

MEDIUM_DIMENSIONS = 4  # variates per segment for the media (module docstring)
SPECTRAL_MIS = ("segment", "path", "none")  # `volpath_radiance(spectral_mis=...)`
_MAX_NULL = 8  # null-surface crossings per segment and per shadow ray


def volpath_sample_dimensions(max_depth: int) -> int:
    """Number of uniform variates one path of `volpath` consumes, camera excluded.

    **Arguments:**

    - `max_depth`: the largest number of path segments. [1]

    **Returns:**

    `8 (max_depth - 1) + 4 max_depth`: the eight per scattering vertex of `path`, then four
    per segment for the media (module docstring). [1]

    !!! note "Thesis"
        Chapters 5-6: the dimension of the path-space integrand seen by a sampler.
    """
    return DIMENSIONS_PER_BOUNCE * max(max_depth - 1, 0) + MEDIUM_DIMENSIONS * max_depth


def _hash_uniform(seed_u: Array, step, n: int) -> Array:
    """`(m, n)` further uniforms from a seed variate `(m,)` and a step number (pcg4d)."""
    bits = (seed_u.astype(jnp.float32) * 4294967296.0).astype(jnp.uint32)
    step = jnp.asarray(step).astype(jnp.uint32)
    blocks = jnp.arange(-(-n // 4), dtype=jnp.uint32)
    words = pcg4d(
        bits[:, None],
        jnp.broadcast_to(step, bits.shape)[:, None] + jnp.uint32(0x9E3779B9),
        blocks[None, :],
        jnp.full((1, 1), 0x85EBCA6B, jnp.uint32),
    )
    return uint32_to_unit_float(words.reshape(bits.shape[0], -1)[:, :n], seed_u.dtype)


def _crossed(scene: RenderScene, face, n, w, medium):
    """The medium a ray of direction `w` is in after crossing (or leaving) triangle `face`,
    whose geometric normal is `n` there: its interior against the normal, its exterior along
    it; unchanged for a triangle that is no medium boundary."""
    interior = scene.face_interior[face]
    exterior = scene.face_exterior[face]
    into = jnp.where(dot(n, w) < 0, interior, exterior)
    return jnp.where(interior == KEEP_MEDIUM, medium, into)


def _path_mis(weight, pdf, mis, channel):
    """Path-level spectral MIS (module docstring, "Spectral MIS"): the weight `f_j / p_c`
    of a free flight sampled at wavelength `c` becomes `f_j / mean_i(r_i p_i)`, and the ratios
    become `r_j p_j / mean_i(r_i p_i)` (detached: sampling densities)."""
    pdf = jax.lax.stop_gradient(pdf)
    p_c = jnp.take_along_axis(pdf, channel[:, None], axis=1)
    rp = mis * pdf
    m = jnp.mean(rp, axis=1, keepdims=True)
    ok = m > 0
    m = jnp.where(ok, m, 1.0)
    return jnp.where(ok, weight * p_c / m, 0.0), jnp.where(ok, rp / m, mis)


def _attached_weight(media: MediumSet, medium, mi, t_max, wavelength_nm):
    """Free-flight weights with detached sampling and attached coefficients (module
    docstring, "Derivatives"): the value is unchanged, the derivative is the weight's."""
    if media is None:
        return mi.weight
    weight = jax.lax.stop_gradient(mi.weight)
    m = jnp.clip(medium, 0, media.n_media - 1)
    for i, plugin in enumerate(media.plugins):
        mask = (medium >= 0) & (media.plugin_of[m] == i)
        med = plugin.medium(media.row_of[m], wavelength_nm)
        if not isinstance(med, HomogeneousMedium):
            continue
        st, ss = med.coefficients(wavelength_nm)
        t = jax.lax.stop_gradient(jnp.where(mi.scattered, mi.t, jnp.where(mask, t_max, 0.0)))
        f = jnp.where(mi.scattered[:, None], ss, 1.0) * jnp.exp(-st * t[:, None])
        f_det = jax.lax.stop_gradient(f)
        ratio = f / jnp.where(f_det > 0, f_det, 1.0)
        weight = jnp.where(mask[:, None], weight * ratio, weight)
    return weight


class _VolState(eqx.Module):
    """The state of a batch of paths between segments (arrays with a leading path axis)."""

    o: Array  # origin of the next segment (n, 3)
    d: Array  # its unit direction (n, 3)
    beta: Array  # path throughput (n, k)
    radiance: Array  # radiance gathered so far (n, k)
    alive: Array  # bool (n,)
    pdf: Array  # solid-angle density of the sample that chose `d` (n,)
    specular: Array  # bool (n,): `d` came from the camera or a delta lobe (no MIS)
    eta_scale: Array  # (n,): product of eta^2 over refractions, for roulette
    hero_only: Array  # bool (n,): secondary wavelengths terminated by dispersion
    medium: Array  # int32 (n,): the medium `d` travels in (-1: vacuum)
    mis: Array  # (n, k): path-level spectral MIS ratios P_j / mean_i P_i (module docstring)
    channel: Array  # int32 (n,): the wavelength index free flights are sampled at ("path")
    # bool (n,): the path left the scene; `d`, `beta`, `pdf` and `specular` stay those of the
    # escaping segment (`beta` with the walk's free-flight weights), for `escaped_radiance`.
    escaped: Array


class _Walk(eqx.Module):
    """Where a segment's walk through null surfaces stands."""

    o: Array
    beta: Array
    radiance: Array
    medium: Array
    pending: Array  # still walking
    dist: Array  # distance walked from the segment's vertex
    event: Array  # a medium interaction was sampled
    p: Array  # the next vertex: the interaction or the surface hit
    face: Array
    surface: Array  # the walk ended on a non-null surface
    cos_o: Array
    mis: Array  # (n, k) spectral MIS ratios after the walk's free flights
    uv: Array  # (n, 2) surface coordinates of the surface hit (textures)
    ns: Array  # (n, 3) shading normal of the surface hit (`_vertex`), for the BSDF frame
    n: Array  # (n, 3) geometric normal of the surface hit (`_vertex`)


def _bounded_loop(body, init, n: int, differentiable: bool, pending):
    """`n` iterations of `body(i, carry)`; stops early (`while_loop`) once `pending(carry)`
    is False everywhere, unless a static trip count is needed for reverse mode."""
    if n == 1:
        return body(0, init)
    if differentiable:
        return jax.lax.fori_loop(0, n, body, init)

    def cond(c):
        i, carry = c
        return (i < n) & jnp.any(pending(carry))

    def step(c):
        i, carry = c
        return i + 1, body(i, carry)

    return jax.lax.while_loop(cond, step, (jnp.int32(0), init))[1]


def _walk(scene, state, wavelength_nm, u_med, b, *, max_null, differentiable, hide_emitters,
          spectral_mis):  # fmt: skip
    """Trace segment `b` from each path's vertex through null surfaces to the next real
    vertex (a medium interaction or a surface), gathering the emission of surfaces on the
    way. A walk that leaves the scene ends with none of `pending`, `event` and `surface`
    set; its lights at infinity are looked up once per path after the last segment
    (`_path.final_radiance`), not here for every walking lane."""
    n = state.o.shape[0]
    dtype = state.o.dtype
    media = scene.media
    null_mat = is_null(scene.materials)
    show = jnp.logical_not(hide_emitters) | (b > 0)
    walk = _Walk(
        o=state.o,
        beta=state.beta,
        radiance=state.radiance,
        medium=state.medium,
        pending=state.alive,
        dist=jnp.zeros((n,), dtype),
        event=jnp.zeros((n,), bool),
        p=state.o,
        face=jnp.zeros((n,), jnp.int32),
        surface=jnp.zeros((n,), bool),
        cos_o=jnp.zeros((n,), dtype),
        mis=state.mis,
        uv=jnp.zeros((n, scene.surface_width), dtype),
        ns=jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0], dtype), (n, 3)),
        n=jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0], dtype), (n, 3)),
    )
    d = state.d

    def body(i, w: _Walk) -> _Walk:
        # Walks that ended trace nothing (an empty interval, skipped by the traversal).
        v = _vertex(scene, w.o, d, jnp.where(w.pending, jnp.inf, 0.0).astype(dtype))
        beta = w.beta
        event = jnp.zeros((n,), bool)
        t_event = v.t
        if media is not None:
            u_ff = jnp.where(i == 0, u_med[:, 0], _hash_uniform(u_med[:, 1], i, 1)[:, 0])
            t_max = jnp.where(v.valid, v.t, jnp.inf)
            inside = w.pending & (w.medium >= 0)
            t_max = jnp.where(inside, t_max, 0.0)
            channel = None if spectral_mis == "segment" else state.channel
            mi = media.sample_free_flight(
                w.medium, w.o, d, t_max, wavelength_nm, u_ff[:, None], channel
            )
            weight = _attached_weight(media, w.medium, mi, t_max, wavelength_nm)
            if spectral_mis == "path":
                weight, ratios = _path_mis(weight, mi.pdf, w.mis, state.channel)
                ratios = jnp.where(inside[:, None], ratios, w.mis)
            beta = jnp.where(inside[:, None], beta * weight, beta)
            event = inside & mi.scattered
            t_event = mi.t
        through = w.pending & ~event
        hit = through & v.valid
        null_hit = hit & null_mat[scene.face_material[v.face]]
        # Emission where the walk meets a surface, weighted by MIS against next-event
        # estimation from the segment's vertex (distance dist + t from it).
        le = scene.light.emitted(v.face, v.cos_o, hit, wavelength_nm, v.uv)
        pdf_light = scene.light.pdf_li(v.face, w.dist + v.t, v.cos_o, state.o)
        mis = jnp.where(state.specular, 1.0, power_heuristic(1, state.pdf, 1, pdf_light))
        gathered = jnp.where((hit & show)[:, None], beta * le * mis[:, None], 0.0)
        medium = w.medium
        if scene.media is not None:
            medium = jnp.where(null_hit, _crossed(scene, v.face, v.n, d, w.medium), w.medium)
        if scene.media is None or spectral_mis != "path":
            ratios = w.mis
        offset = scene.ray_epsilon * (1.0 + jnp.max(jnp.abs(v.p), axis=-1))
        o = jnp.where(null_hit[:, None], _offset(v.p, v.n, d, offset), w.o)
        ended = w.pending & ~null_hit
        p_event = w.o + t_event[:, None] * d
        return _Walk(
            o=o,
            beta=beta,
            radiance=w.radiance + gathered,
            medium=medium,
            pending=null_hit,
            dist=w.dist + jnp.where(null_hit, v.t, 0.0),
            event=jnp.where(ended, event, w.event),
            p=jnp.where((ended & event)[:, None], p_event, jnp.where(ended[:, None], v.p, w.p)),
            face=jnp.where(ended, v.face, w.face),
            surface=jnp.where(ended, hit & ~null_hit, w.surface),
            cos_o=jnp.where(ended, v.cos_o, w.cos_o),
            mis=ratios,
            uv=jnp.where(ended[:, None], v.uv, w.uv),
            ns=jnp.where(ended[:, None], v.ns, w.ns),
            n=jnp.where(ended[:, None], v.n, w.n),
        )

    return _bounded_loop(body, walk, max_null, differentiable, lambda w: w.pending)


def _shadow_transmittance(
    scene, origin, w, t_max, medium, wavelength_nm, seed_u, *, max_null, differentiable
):
    """Transmittance `(n, k)` of shadow-ray segments, through null surfaces and media; 0
    where a non-null surface blocks the segment."""
    n, k = wavelength_nm.shape
    null_mat = is_null(scene.materials)

    def body(i, c):
        o, remaining, med, tr, pending = c
        hit = scene.accelerator.intersect_closest(o, w, jnp.where(pending, remaining, 0.0))
        valid = pending & (hit.prim >= 0)
        face = jnp.where(valid, hit.prim, 0)
        t_hit = jnp.where(valid, hit.t.astype(o.dtype), remaining)
        if scene.media is not None:
            seg = jnp.where(pending & (med >= 0), t_hit, 0.0)
            u = _hash_uniform(seed_u, 1000 + i, 4)
            tr = tr * scene.media.transmittance(med, o, w, seg, wavelength_nm, u)
        null_hit = valid & null_mat[scene.face_material[face]]
        tr = jnp.where((valid & ~null_hit)[:, None], 0.0, tr)
        p = o + t_hit[:, None] * w
        offset = scene.ray_epsilon * (1.0 + jnp.max(jnp.abs(p), axis=-1))
        ng = scene.geometric_normal(face, p)
        o = jnp.where(null_hit[:, None], _offset(p, ng, w, offset), o)
        if scene.media is not None:
            med = jnp.where(null_hit, _crossed(scene, face, ng, w, med), med)
        remaining = jnp.where(null_hit, remaining - t_hit - offset, remaining)
        return o, remaining, med, tr, null_hit & (remaining > 0)

    init = (origin, t_max, medium, jnp.ones((n, k), origin.dtype), t_max > 0)
    out = _bounded_loop(body, init, max_null, differentiable, lambda c: c[4])
    return jnp.where(out[4][:, None], 0.0, out[3])  # still walking after max_null: blocked


def _scatter(scene, state, walk: _Walk, wavelength_nm, u_b, seed_u, roulette, *, max_null,
             differentiable):  # fmt: skip
    """At each path's vertex (a surface hit or a medium interaction): next-event estimation,
    the BSDF or phase-function sample of the next segment, and Russian roulette."""
    beta, radiance = walk.beta, walk.radiance
    d = state.d
    wo = -d
    in_medium = walk.event
    face = walk.face
    ng = walk.n
    material = scene.face_material[face]
    # The BSDF frame is the shading normal (as in `path_radiance`: Mitsuba's smoothed vertex
    # normals, also for meshes whose file has none); which side was hit, offsets and medium
    # changes follow the geometric normal `ng`.
    # Medium vertices take any frame (the phase function ignores it); surfaces get `path`'s
    # shading frame, with the differential geometry normal and bump maps need.
    ns = jnp.where(walk.event[:, None], ng, walk.ns)
    hit = _Vertex(valid=walk.surface, p=walk.p, n=ng, face=face, t=jnp.zeros_like(walk.cos_o),
                  cos_o=walk.cos_o, uv=walk.uv, ns=ns)  # fmt: skip
    frame = shading_frame(scene, hit)
    alive = state.alive & (walk.event | (walk.surface & frame.scatters))
    to_local, to_world = frame.to_local, frame.to_world

    p = walk.p
    wo_l = to_local(wo)
    bsdf = scene.materials.bxdf(material, wavelength_nm, walk.uv, frame.geometry)
    offset = scene.ray_epsilon * (1.0 + jnp.max(jnp.abs(p), axis=-1))
    media = scene.media

    # Next-event estimation, weighted against BSDF / phase sampling by MIS.
    ls = scene.light.sample_li(p, u_b[:, 4], u_b[:, 0:2], wavelength_nm)
    wi_l = to_local(ls.wi)
    # The BSDF's three queries at once (one pass per material kind in a mixed scene).
    f_light, pdf_dir, bs = bsdf.f_pdf_sample(wo_l, wi_l, u_b[:, 5], u_b[:, 2:4])
    f_light = f_light * jnp.abs(wi_l[:, 2:3])
    if media is not None:
        ph = media.phase(walk.medium, wo, ls.wi, wavelength_nm)
        f_light = jnp.where(in_medium[:, None], ph[:, None], f_light)
        pdf_dir = jnp.where(in_medium, ph, pdf_dir)
    w_light = power_heuristic(1, ls.pdf, 1, pdf_dir)
    if ls.delta is not None:
        w_light = jnp.where(ls.delta, 1.0, w_light)
    use = alive & (ls.pdf > 0)
    if media is None and max_null == 1:
        origin, direction, shadow_tmax = shadow_ray(p, ng, ls.wi, ls.dist, offset)
        shadow_tmax = jnp.where(use, shadow_tmax, 0.0)
        use = use & ~scene.accelerator.intersect_any(origin, direction, shadow_tmax)
        tr = jnp.ones_like(beta)
    else:
        origin, direction, shadow_tmax = shadow_ray(
            p, ng, ls.wi, ls.dist, jnp.where(in_medium, 0.0, offset)
        )
        # a light at infinity: an unbounded segment, as a finite length for the walk
        shadow_tmax = jnp.where(use, jnp.minimum(shadow_tmax, 1e30), 0.0)
        start = walk.medium
        if media is not None:
            start = jnp.where(in_medium, start, _crossed(scene, face, ng, ls.wi, start))
        tr = _shadow_transmittance(
            scene, origin, direction, shadow_tmax, start, wavelength_nm, seed_u,
            max_null=max_null, differentiable=differentiable,
        )  # fmt: skip
    nee = beta * f_light * ls.radiance * tr * (w_light / jnp.where(use, ls.pdf, 1.0))[:, None]
    radiance = radiance + jnp.where(use[:, None], nee, 0.0)

    # The next segment: a BSDF sample at a surface, a phase-function sample in a medium.
    wi = to_world(bs.wi)
    wi = wi / jnp.sqrt(dot(wi, wi))[:, None]
    ok = bs.pdf > 0
    weight = bs.f * (jnp.abs(bs.wi[:, 2]) / jnp.where(ok, bs.pdf, 1.0))[:, None]
    pdf = bs.pdf
    specular = bs.is_delta
    transmission = bs.is_transmission
    medium = walk.medium
    if media is not None:
        ps = media.sample_phase(walk.medium, wo, u_b[:, 2:4], wavelength_nm)
        ok = jnp.where(in_medium, ps.pdf > 0, ok)
        wi = jnp.where(in_medium[:, None], ps.wi, wi)
        ratio = ps.value / jnp.where(ps.pdf > 0, ps.pdf, 1.0)
        weight = jnp.where(in_medium[:, None], ratio[:, None], weight)
        pdf = jnp.where(in_medium, ps.pdf, pdf)
        specular = specular & ~in_medium
        transmission = transmission & ~in_medium
        medium = jnp.where(in_medium, medium, _crossed(scene, face, ng, wi, medium))
    alive = alive & ok
    beta = jnp.where(alive[:, None], beta * weight, 0.0)

    # Russian roulette (Path's rule); the survival probability is a detached decision.
    eta = jnp.where(transmission, bs.eta * bs.eta, 1.0)
    eta_scale = state.eta_scale * jnp.where(in_medium, 1.0, eta)
    q = jax.lax.stop_gradient(jnp.minimum(jnp.max(beta, axis=-1) * eta_scale, 0.95))
    alive = alive & (~roulette | (u_b[:, 6] < q))
    beta = jnp.where(alive[:, None], beta / jnp.where(alive & roulette, q, 1.0)[:, None], 0.0)
    if not differentiable:  # zero throughput adds nothing more (`path`'s `prune`)
        alive = alive & jnp.any(beta != 0, axis=-1)
    o = jnp.where(in_medium[:, None], p, _offset(p, ng, wi, offset))
    terminate = alive & bs.terminate_secondary & ~in_medium
    return _VolState(
        o=o,
        d=wi,
        beta=beta,
        radiance=radiance,
        alive=alive,
        pdf=pdf,
        specular=specular,
        eta_scale=eta_scale,
        hero_only=state.hero_only | terminate,
        medium=medium,
        mis=walk.mis,
        channel=state.channel,
        escaped=state.escaped,
    )


def _segment(scene, state, wavelength_nm, sample, b, *, max_depth, rr_depth, hide_emitters,
             max_null, differentiable, spectral_mis):  # fmt: skip
    """Segment `b` of every path: the walk to the next vertex, then (but for the last
    segment) its scattering."""
    dtype = state.o.dtype
    alive = state.alive
    # Terminated paths get a harmless ray and zero throughput (finite, unused results).
    state = eqx.tree_at(
        lambda s: (s.o, s.d, s.beta),
        state,
        (
            jnp.where(alive[:, None], state.o, 0.0),
            jnp.where(alive[:, None], state.d, jnp.asarray([0.0, 0.0, 1.0], dtype)),
            jnp.where(alive[:, None], state.beta, 0.0),
        ),
    )
    u_surface, u_med = sample()
    if spectral_mis != "segment":  # the path's free-flight wavelength, chosen once
        k = wavelength_nm.shape[-1]
        first = jnp.clip(jnp.floor(u_med[:, 2] * k), 0, k - 1).astype(jnp.int32)
        state = eqx.tree_at(lambda s: s.channel, state, jnp.where(b == 0, first, state.channel))
    walk = _walk(
        scene, state, wavelength_nm, u_med, b, max_null=max_null,
        differentiable=differentiable, hide_emitters=hide_emitters, spectral_mis=spectral_mis,
    )  # fmt: skip
    # A walk that left the scene (ended on neither a surface nor a medium interaction, and
    # not cut short by `max_null`) keeps this segment's direction, density and throughput.
    escaped = alive & ~walk.pending & ~walk.event & ~walk.surface
    if hide_emitters:
        escaped = escaped & (b > 0)
    ended = eqx.tree_at(
        lambda s: (s.radiance, s.alive, s.beta, s.medium, s.mis),
        state,
        (walk.radiance, jnp.zeros_like(alive), walk.beta, walk.medium, walk.mis),
    )
    if max_depth == 1:
        new = ended
    else:
        state = eqx.tree_at(lambda s: s.alive, state, alive & (walk.event | walk.surface))
        new = jax.lax.cond(
            b < max_depth - 1,
            lambda: _scatter(
                scene, state, walk, wavelength_nm, u_surface, u_med[:, 1],
                roulette=b >= rr_depth - 1, max_null=max_null, differentiable=differentiable,
            ),
            lambda: ended,
        )  # fmt: skip
    return record_escape(new, escaped, state.d, walk.beta, state.pdf, state.specular)


def volpath_radiance(
    scene: RenderScene,
    origins: Float[Array, "n 3"],
    directions: Float[Array, "n 3"],
    wavelength_nm: Float[Array, "n k"],
    u: Float[Array, "n d"] | None,
    *,
    max_depth: int,
    rr_depth: int = 5,
    hide_emitters: bool = False,
    chunk: int | None = None,
    active: Bool[Array, " n"] | None = None,
    compact: bool = True,
    max_null: int = _MAX_NULL,
    variates=None,
    spectral_mis: str = "segment",
) -> Float[Array, "n k"]:
    r"""Spectral radiance along each ray, by volumetric path tracing (module docstring).

    **Arguments:**

    - `scene`: the compiled scene (`RenderScene`), with or without `media`.
    - `origins`, `directions`: camera rays, `(n, 3)`; directions unit length; they start in
        the scene's `camera_medium`. [scene units]
    - `wavelength_nm`: the wavelengths of each path, `(n, k)`. [nm]
    - `u`: uniform variates in [0, 1), `(n, volpath_sample_dimensions(max_depth))` (module
        docstring, "Variates"); ignored when `variates` is given. [1]
    - `max_depth`: largest number of path segments (Mitsuba's meaning), a static int >= 1.
    - `rr_depth`: segments after which Russian roulette starts (static int >= 1).
    - `hide_emitters`: emitters seen directly from the camera (also through null surfaces)
        are black (Mitsuba's `hide_emitters`).
    - `chunk`, `active`, `compact`: as in `path_radiance` (`compact=False` for `jax.grad`).
    - `max_null`: static bound on the null surfaces crossed per segment and per shadow ray.
    - `variates`: instead of `u`, a function `variates(first, n_dims, paths)` (the
        integrators' `VariateFn`).
    - `spectral_mis`: how free flights in homogeneous media combine the path's wavelengths
        (module docstring, "Spectral MIS"): `"segment"` (`volpath`), `"path"` (`volpathmis`)
        or `"none"` (`volpathmis` with `use_spectral_mis=false`). Same expectation.

    **Returns:**

    Radiance estimates `(n, k)` at `wavelength_nm` [W m^-2 sr^-1 nm^-1, or the unit of the
    scene's emission spectra].

    !!! note "Thesis"
        Chapter 9 (volume rendering; title only in the text), chapter 4 (the medium), with
        the estimators of chapters 6-7.

    ??? cite "References"
        `Pharr2023` §14.1 (`VolPathIntegrator`); `Novak2018` (free-flight sampling,
        tracking); `Wilkie2014` (hero wavelengths); `Veach1997` (MIS); `Jakob2022`
        (Mitsuba 3's `volpath`).
    """
    for name, value in (("max_depth", max_depth), ("rr_depth", rr_depth), ("max_null", max_null)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"`{name}` must be an int >= 1, got {value!r}.")
    if spectral_mis not in SPECTRAL_MIS:
        raise ValueError(f"`spectral_mis` must be one of {SPECTRAL_MIS}, got {spectral_mis!r}.")
    n_rays = origins.shape[0]
    surface_dims = DIMENSIONS_PER_BOUNCE * max(max_depth - 1, 0)
    if variates is None:
        dims = volpath_sample_dimensions(max_depth)
        if u.shape != (n_rays, dims):
            raise ValueError(
                f"`u` must have shape (rays, {dims}) = {(n_rays, dims)} for "
                f"max_depth={max_depth}, got {u.shape}."
            )

        def variates(first, n_dims, paths):
            cols = jax.lax.dynamic_slice_in_dim(u, first, n_dims, 1)
            return jnp.take(cols, paths, axis=0, mode="clip")

    if not has_null(scene.materials):
        max_null = 1  # nothing to cross: one intersection per segment and per shadow ray

    def sample(b, paths):
        if max_depth == 1:  # no scattering vertex: no surface variates
            u_surface = jnp.zeros((paths.shape[0], DIMENSIONS_PER_BOUNCE), dtype)
        else:
            first = DIMENSIONS_PER_BOUNCE * jnp.minimum(b, max_depth - 2)
            u_surface = variates(first, DIMENSIONS_PER_BOUNCE, paths)
        u_med = variates(surface_dims + MEDIUM_DIMENSIONS * b, MEDIUM_DIMENSIONS, paths)
        return u_surface, u_med

    dtype = origins.dtype
    k = wavelength_nm.shape[-1]
    alive = jnp.ones((n_rays,), bool) if active is None else jnp.asarray(active, bool)
    state = _VolState(
        o=origins,
        d=directions,
        beta=jnp.ones((n_rays, k), dtype),
        radiance=jnp.zeros((n_rays, k), dtype),
        alive=alive,
        pdf=jnp.zeros((n_rays,), dtype),
        specular=jnp.ones((n_rays,), bool),
        eta_scale=jnp.ones((n_rays,), dtype),
        hero_only=jnp.zeros((n_rays,), bool),
        medium=jnp.full((n_rays,), scene.camera_medium, jnp.int32),
        mis=jnp.ones((n_rays, k), dtype),
        channel=jnp.zeros((n_rays,), jnp.int32),
        escaped=jnp.zeros((n_rays,), bool),
    )

    def segment(state, wavelength_nm, paths, b):
        return _segment(
            scene, state, wavelength_nm, functools.partial(sample, b, paths), b,
            max_depth=max_depth, rr_depth=rr_depth, hide_emitters=hide_emitters,
            max_null=max_null, differentiable=not compact, spectral_mis=spectral_mis,
        )  # fmt: skip

    chunk = _default_chunk(n_rays) if chunk is None else min(int(chunk), n_rays)
    state = run_segments(
        state, segment, wavelength_nm, n_segments=max_depth, chunk=chunk, compact=compact
    )
    return final_radiance(scene, state, wavelength_nm)


class VolPath(AbstractIntegrator):
    """Volumetric path tracing with next-event estimation through media, MIS and Russian
    roulette (Mitsuba 3's `volpath`; `volpath_radiance`).

    **Arguments:**

    - `max_depth`: largest number of path segments (1 = emitters seen directly, 2 = direct
        illumination; medium interactions count like surface bounces; null surfaces do not),
        a static int >= 1 (default 8).
    - `rr_depth`: segments after which Russian roulette starts (default 5).
    - `hide_emitters`: directly visible emitters are black (default False).

    On a scene without media it renders what `Path` renders, from the same variates.

    !!! note "Thesis"
        Chapter 9 (volume rendering; title only in the text).

    ??? cite "References"
        `Pharr2023` §14.1; `Jakob2022` (`volpath`); `Novak2018`.
    """

    NAME: ClassVar[str] = "volpath"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"max_depth", "rr_depth", "hide_emitters"})
    max_depth: int = eqx.field(static=True, default=8)
    rr_depth: int = eqx.field(static=True, default=5)
    hide_emitters: bool = eqx.field(static=True, default=False)

    def __check_init__(self):
        check_path_fields(self)

    @classmethod
    def from_properties(cls, params: dict, *, where: str = "scene") -> "VolPath":
        """From a scene file's `max_depth` (default 8; -1 = unbounded, taken as
        `DEFAULT_UNBOUNDED_DEPTH`), `rr_depth` (default 5) and `hide_emitters`."""
        return cls(
            max_depth=scene_max_depth(params),
            rr_depth=params.get("rr_depth", 5),
            hide_emitters=scene_flag(params, "hide_emitters", False, where),
        )

    def sample_dimensions(self) -> int:
        return volpath_sample_dimensions(self.max_depth)

    def radiance(self, scene, origins, directions, wavelength_nm, variates, active):
        return volpath_radiance(
            scene,
            origins,
            directions,
            wavelength_nm,
            None,
            max_depth=self.max_depth,
            rr_depth=self.rr_depth,
            hide_emitters=self.hide_emitters,
            active=active,
            variates=variates,
        )
