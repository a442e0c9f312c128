r"""Bidirectional path tracing with multiple importance sampling: the `BDPT` integrator
(thesis ch. 9).

Each (pixel, sample) slot traces a *camera subpath* $z_0 z_1 \dots$ (the camera ray, then
BSDF samples in radiance mode) and a *light subpath* $y_0 y_1 \dots$ (an emitted ray,
`AbstractLight.sample_le`, then BSDF samples in importance mode), and combines every pair of
prefixes into a full path of $s$ light and $t$ camera vertices (`Veach1997` ch. 10):

- $s = 0$: the camera subpath hits an emitter ($L_e$ at $z_{t-1}$);
- $s = 1$: the light subpath's first vertex $y_0$ joined to $z_{t-1}$ by a shadow ray (next
  event estimation from the same emitted point);
- $t = 1$: $y_{s-1}$ joined to the camera (`AbstractCamera.sample_wi`) and *splatted* into
  the film at the raster position it reaches, as light tracing does (`PTracer`);
- $s, t \ge 2$: $y_{s-1}$ joined to $z_{t-1}$, the BSDFs of both ends evaluated (the light
  end in importance mode, with the shading-normal correction of `Veach1997` §5.3).

A full path of $s + t$ vertices has $s + t - 1$ segments; depths are Mitsuba's, so
`max_depth` bounds the segments ($s + t - 1 \le$ `max_depth`; 1 = emitters seen directly).

**MIS weights.** Strategy $(s, t)$ of a path $\bar x$ gets the balance ($\beta = 1$) or power
($\beta = 2$) heuristic weight $w_{s,t} = p_{s,t}^\beta / \sum_i p_i^\beta$ (`Veach1997`
eq. 10.9), computed as pbrt does from the ratios $p_i / p_{s,t}$: every vertex keeps the
area density with which its own subpath generated it (`pdf_fwd`) and the one with which the
other direction would have (`pdf_rev`); the connection changes `pdf_rev` of the two vertices
at each end of the connecting edge, which are recomputed per strategy, and

$$\frac{1}{w_{s,t}} = 1 + \sum_{i=1}^{t-1} \prod_{j=i}^{t-1}
  \Big(\frac{p^{\mathrm{rev}}_{z_j}}{p^{\mathrm{fwd}}_{z_j}}\Big)^\beta
  + \sum_{i=0}^{s-1} \prod_{j=i}^{s-1}
  \Big(\frac{p^{\mathrm{rev}}_{y_j}}{p^{\mathrm{fwd}}_{y_j}}\Big)^\beta$$

(`Pharr2016` §16.3.4; zero densities are taken as 1). A term is dropped when the strategy
it stands for would connect through a specular (delta) vertex or hit a delta light (a point
or a spot), which it cannot; specular vertices have both densities 0 (pbrt's convention).
Russian roulette is not part of the densities (pbrt's choice: the weights still sum to 1).

**Vectorised.** The two subpaths are `lax.scan`s of static length over the batch; the
strategies are two more `lax.scan`s over static lists of $(s, t)$ (one for $t \ge 2$, adding
to the camera ray's radiance, one for $t = 1$, giving `Splats`), each strategy gathering its
two end vertices by dynamic index, so one compiled copy serves every strategy. The MIS sums
are reversed cumulative products over the vertex axis with masks.

**Film.** The driver adds the camera-ray estimates and the splats of the same slots with one
normalisation (`radiometria.render.render`, the `ptracer` module's "Normalisation": the film
weight per slot is the filter's film integral $F_j$, pbrt-v4's $1/\mathrm{spp}$ splat scale).

**Lights at infinity** (`constant`, `envmap`) **and directional lights** follow pbrt-v4's
convention for vertices at infinity. A light subpath from such a light starts on a disk of the
scene's bounding-sphere radius $r$ across the emitted direction (`emission_at_infinity`); its
$y_0$ stands for the light itself, with the density of the *direction* (solid angle, the
light's pick probability included: pbrt's `InfiniteLightDensity`), and $y_1$ gets that of the
ray's origin on the disk, $|\cos\theta_{y_1}| / \pi r^2$. A camera ray that leaves the scene
ends the camera subpath on a vertex at infinity (strategy $s = 0$: the environment's
radiance), whose forward density stays per solid angle and whose reverse densities are the
light's direction density and, for the vertex before it, $|\cos| / \pi r^2$. Strategy
$s = 1$ samples the light's direction from the camera end (`sample_li`, next-event
estimation; the light is picked by the same variate as the light subpath's), since $y_0$ is
no point to connect to; for the same reason strategy $(1, 1)$ does not exist for these lights
and the MIS weights leave it out. A directional light is a delta light as well (no strategy
$s = 0$).

**Not handled:** participating media (a scene with media is refused: use `volpath`).

The variates of a slot are `[BSDF u0, u1 | lobe, roulette]` for each camera-subpath
scattering vertex ($z_1 \dots z_{D-1}$, $D$ = `max_depth`), then `[point u0, u1 | direction
u0, u1 | light choice, side | direction towards a light at infinity u0, u1]` for the emission
and 4 per light-subpath scattering vertex ($y_1 \dots y_{D-2}$).

!!! note "Thesis"
    Chapter 9 (bidirectional methods; title only in the text).

??? cite "References"
    `Veach1997` ch. 10 (bidirectional path tracing, eq. 10.9 MIS weights), §5.3 (adjoint BSDFs
    and shading normals); `Pharr2016` §16.3 (`GenerateCameraSubpath`,
    `GenerateLightSubpath`, `ConnectBDPT`, `MISWeight`); `Pharr2023` §5.4 (splats).
"""

import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

from ..._math import dot
from ...scattering import coordinate_system
from .._materials import HitGeometry
from ._base import AbstractIntegrator, check_path_fields, scene_max_depth
from ._path import _offset, _vertex, shading_frame
from ._ptracer import Splats

__all__ = ["BDPT", "HEURISTICS", "bdpt_mis_weight", "bdpt_sample_dimensions"]

HEURISTICS = ("balance", "power")
_EMISSION_DIMENSIONS = 8
_DIMENSIONS_PER_VERTEX = 4


def bdpt_sample_dimensions(max_depth: int) -> int:
    """Variates one slot consumes: 4 per camera-subpath scattering vertex (`max_depth - 1`),
    8 for the emission and 4 per light-subpath scattering vertex (`max_depth - 2`). [1]"""
    return (
        _DIMENSIONS_PER_VERTEX * max(max_depth - 1, 0)
        + _EMISSION_DIMENSIONS
        + _DIMENSIONS_PER_VERTEX * max(max_depth - 2, 0)
    )


class _Vertices(eqx.Module):
    """Vertices of a batch of subpaths, arrays `(V, n, ...)` (vertex-major)."""

    p: Array  # position (V, n, 3)
    ng: Array  # geometric normal (zero where none)
    ns: Array  # shading normal, turned to the side the path scatters on
    s: Array  # shading tangents: the local frame is (s, t, ns)
    t: Array
    geometry: HitGeometry | None  # for normal and bump maps (None when no material needs it)
    wo: Array  # unit direction towards the previous vertex
    material: Array  # int32
    uv: Array  # (V, n, 2)
    beta: Array  # throughput up to and including the vertex (V, n, k)
    pdf_fwd: Array  # area density of the vertex, from its own subpath
    pdf_rev: Array  # area density of the vertex, from the other direction
    conv_prev: Array  # |cos at previous vertex| / distance^2: solid angle -> area there
    delta: Array  # bool: the vertex scattered by a delta lobe
    valid: Array  # bool: the vertex exists
    surf: Array  # bool: a surface the path may scatter at / connect through
    has_n: Array  # bool: the vertex has a surface (not the pinhole, not a point light)
    hero: Array  # bool: secondary wavelengths terminated before this vertex
    emit: Array  # (V, n, k) radiance emitted towards the previous vertex (camera side)
    emit_pos: Array  # area density of `sample_le` starting at the vertex (camera side)
    emit_dir: Array  # solid-angle density of `sample_le` emitting towards the previous vertex
    at_inf: Array  # bool: a camera ray that left the scene (a vertex on a light at infinity)


def _at(vertices: _Vertices, i) -> _Vertices:
    return jax.tree.map(lambda a: jax.lax.dynamic_index_in_dim(a, i, 0, keepdims=False), vertices)


def _remap0(x):
    return jnp.where(x == 0, 1.0, x)


def bdpt_mis_weight(
    fwd_c: Float[Array, "tc n"],
    rev_c: Float[Array, "tc n"],
    delta_c: Bool[Array, "tc n"],
    t,
    fwd_l: Float[Array, "sl n"],
    rev_l: Float[Array, "sl n"],
    delta_l: Bool[Array, "sl n"],
    light_delta: Bool[Array, " n"],
    s,
    *,
    heuristic: str = "power",
    light_infinite: Bool[Array, " n"] | None = None,
) -> Float[Array, " n"]:
    r"""The MIS weight of strategy $(s, t)$ from the vertex densities (module docstring).

    **Arguments:**

    - `fwd_c`, `rev_c`: `(Tc, n)` area densities of the camera-subpath vertices $z_j$ from the
        camera side and from the light side, with the connection's changes already made
        (entries `j >= t` are ignored; `j = 0` is the camera). [m^-2, or 1 for the camera]
    - `delta_c`: `(Tc, n)` bool, $z_j$ is a specular vertex (False at $z_{t-1}$).
    - `t`: camera vertices of the strategy, an int (may be traced), >= 1.
    - `fwd_l`, `rev_l`, `delta_l`: the same for the light-subpath vertices $y_j$ (`j >= s`
        ignored; `fwd_l[0]` the emitted point's density).
    - `light_delta`: `(n,)` bool, $y_0$ is on a delta light (point, spot).
    - `s`: light vertices of the strategy, an int (may be traced), >= 0.
    - `heuristic`: `"balance"` ($\beta = 1$) or `"power"` ($\beta = 2$).
    - `light_infinite`: `(n,)` bool, the path's light end is at infinity (a light at infinity
        or a directional light), so the strategy $(1, 1)$ does not exist for it (the camera
        cannot be joined to a point at infinity); `None`: no such light.

    **Returns:**

    `(n,)` weights in [0, 1]. [1]

    ??? cite "References"
        `Veach1997` eq. 10.9; `Pharr2016` §16.3.4 (`MISWeight`).
    """
    power = heuristic == "power"

    def sums(fwd, rev, count, prev_delta, delta, first, skip=None):
        j = jnp.arange(fwd.shape[0], dtype=jnp.int32)[:, None]
        r = _remap0(rev) / _remap0(fwd)
        if power:
            r = r * r
        r = jnp.where(j < count, r, 1.0)
        rr = jnp.flip(jnp.cumprod(jnp.flip(r, 0), axis=0), 0)  # rr[i] = prod_{j >= i} r_j
        ok = (j >= first) & (j < count) & ~delta & ~prev_delta
        if skip is not None:
            ok = ok & ~skip
        return jnp.sum(jnp.where(ok, rr, 0.0), axis=0)

    prev_c = jnp.concatenate([jnp.zeros_like(delta_c[:1]), delta_c[:-1]], axis=0)
    prev_l = jnp.concatenate([light_delta[None], delta_l[:-1]], axis=0)
    skip = None
    if light_infinite is not None:  # the camera term j = 1 of a 2-vertex path is (1, 1)
        j = jnp.arange(fwd_c.shape[0], dtype=jnp.int32)[:, None]
        skip = (j == 1) & (s + t == 2) & light_infinite[None]
    total = (
        1.0
        + sums(fwd_c, rev_c, t, prev_c, delta_c, 1, skip)
        + sums(fwd_l, rev_l, s, prev_l, delta_l, 0)
    )
    return 1.0 / total


class BDPT(AbstractIntegrator):
    """Bidirectional path tracing with every connection strategy and MIS (module docstring;
    pbrt's `bdpt`).

    **Arguments:**

    - `max_depth`: largest number of path segments (Mitsuba's meaning; 1 = emitters seen
        directly), a static int >= 1 (default 8). The strategies number about
        `max_depth^2 / 2`, each with a shadow ray.
    - `rr_depth`: segments of a subpath after which Russian roulette starts (default 5).
    - `hide_emitters`: emitters seen directly from the camera are black (both strategies of
        the one-segment paths).
    - `heuristic`: `"power"` (default, pbrt's) or `"balance"` (`Veach1997` eq. 10.9).

    It needs a camera with `sample_wi` (the pinhole camera); every light kind works (area,
    point, spot, directional, constant, envmap; module docstring), and scenes with
    participating media raise `ValueError`. It is rendered through
    `radiometria.render.render`, which calls `radiance_and_splats`.

    !!! note "Thesis"
        Chapter 9 (bidirectional methods; title only in the text).

    ??? cite "References"
        `Veach1997` ch. 10; `Pharr2016` §16.3; `Pharr2023` §5.4.
    """

    NAME: ClassVar[str] = "bdpt"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"max_depth", "rr_depth", "hide_emitters", "heuristic", "samples_per_pass"}
    )
    BIDIRECTIONAL: ClassVar[bool] = True  # the driver calls `radiance_and_splats`
    max_depth: int = eqx.field(static=True, default=8)
    rr_depth: int = eqx.field(static=True, default=5)
    hide_emitters: bool = eqx.field(static=True, default=False)
    heuristic: str = eqx.field(static=True, default="power")
    # `[s, t, weighted]` (int32, traced): evaluate that strategy alone, MIS-weighted or not
    # (`radiometria.render.bdpt_strategy_images`); None: every strategy (the normal image).
    select: Array | None = None

    def __check_init__(self):
        check_path_fields(self)
        if not isinstance(self.heuristic, str) or self.heuristic not in HEURISTICS:
            raise ValueError(
                f"`heuristic` must be one of {list(HEURISTICS)}, got {self.heuristic!r}."
            )

    @classmethod
    def from_properties(cls, params: dict, *, where: str = "scene") -> "BDPT":
        """From a scene file's `max_depth` (default 8; -1 = unbounded, taken as
        `DEFAULT_UNBOUNDED_DEPTH`), `rr_depth` (default 5), `hide_emitters` (default false)
        and `heuristic` (default "power"); errors name `where`."""
        unknown = set(params) - cls.PARAMETERS
        if unknown:
            raise ValueError(
                f"{where}: unknown bdpt parameter(s) {sorted(unknown)}; valid: "
                f"{sorted(cls.PARAMETERS)}."
            )
        try:
            return cls(
                max_depth=scene_max_depth(params),
                rr_depth=params.get("rr_depth", 5),
                hide_emitters=params.get("hide_emitters", False),
                heuristic=params.get("heuristic", "power"),
            )
        except (ValueError, TypeError) as e:
            raise type(e)(f"{where}: bdpt: {e}") from None

    def sample_dimensions(self) -> int:
        return bdpt_sample_dimensions(self.max_depth)

    def radiance(self, scene, origins, directions, wavelength_nm, variates, active):
        """Not available alone: bidirectional path tracing needs the camera (its connections
        and MIS weights); render through `radiometria.render.render`, which calls
        `radiance_and_splats`."""
        raise TypeError(
            "BDPT needs the camera: render it with radiometria.render.render (which calls "
            "BDPT.radiance_and_splats), not through `radiance`."
        )

    # -- subpaths -------------------------------------------------------------------------

    def _walk(self, scene, wl, variates, paths, start, n_steps, first_dim, mode):
        """Extend subpaths from `start = (o, d, beta, pdf_dir, alive, p_prev, ng_prev,
        has_n_prev, hero, inf_prev)` by `n_steps` vertices; the vertex of step `i` scatters
        (BSDF sample with variates from `first_dim + 4 i`) unless it is the last.
        `inf_prev` marks subpaths that start at infinity (a light at infinity or directional:
        `pdf_dir` is then the origin's density on the disk, converted to area by the cosine
        alone). A camera subpath (`mode = "radiance"`) whose ray leaves a scene with a light
        at infinity ends on a vertex at infinity (`at_inf`; pbrt's convention: at the ray's
        origin plus its direction, facing back).
        Returns the vertices `(n_steps, n, ...)` and each step's `pdf_rev` of the vertex
        before it `(n_steps, n)`."""
        dtype = wl.dtype
        n, k = wl.shape
        up = jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0], dtype), (n, 3))
        escapes = mode == "radiance" and _has_light_at_infinity(scene.light)
        disk = _disk_density(scene.light)

        def step(state, i):
            o, d, beta, pdf_dir, alive, p_prev, ng_prev, has_n_prev, hero, inf_prev = state
            v = _vertex(scene, o, d)
            hit = alive & v.valid
            esc = alive & ~v.valid if escapes else jnp.zeros((n,), bool)
            valid = hit | esc
            frame = shading_frame(scene, v)
            material = frame.material
            surf = hit & frame.scatters
            wo = -d
            p = jnp.where(esc[:, None], o + d, v.p)
            ng = jnp.where(esc[:, None], wo, v.n)
            ns = jnp.where(esc[:, None], wo, frame.n)
            to_prev = p_prev - p
            d2 = jnp.maximum(dot(to_prev, to_prev), jnp.finfo(dtype).tiny)
            # solid angle -> area here; from a disk at infinity the cosine alone; to a vertex
            # at infinity none (its density stays per solid angle)
            conv_here = jnp.abs(v.cos_o) / jnp.where(inf_prev, 1.0, d2)
            conv_here = jnp.where(esc, 1.0, conv_here)
            cos_prev = jnp.where(has_n_prev, jnp.abs(dot(ng_prev, wo)), 1.0)
            conv_prev = jnp.where(inf_prev, 1.0, cos_prev / jnp.where(esc, 1.0, d2))
            emit = scene.light.emitted(v.face, v.cos_o, hit, wl, v.uv)
            emit_pos, emit_dir = scene.light.pdf_le(v.face, v.cos_o)
            if escapes:  # pbrt's PdfLightOrigin and PdfLight of a light at infinity
                emit = emit + scene.light.emitted_escaped(d, esc, wl)
                emit_pos = jnp.where(esc, scene.light.pdf_escaped(d), emit_pos)
                emit_dir = jnp.where(esc, disk, emit_dir)

            if escapes:  # a vertex at infinity has no surface; its frame faces back
                s_esc, t_esc = coordinate_system(wo)
                s = jnp.where(esc[:, None], s_esc, frame.s)
                t = jnp.where(esc[:, None], t_esc, frame.t)
            else:
                s, t = frame.s, frame.t

            def to_local(w):
                return jnp.stack([dot(w, s), dot(w, t), dot(w, ns)], axis=-1)

            wo_l = to_local(wo)
            bsdf = scene.materials.bxdf(material, wl, v.uv, frame.geometry)
            u = variates(first_dim + _DIMENSIONS_PER_VERTEX * i, 4, paths).astype(dtype)
            bs = bsdf.sample_f(wo_l, u[:, 2], u[:, 0:2], mode=mode)
            wi = bs.wi[:, 0:1] * s + bs.wi[:, 1:2] * t + bs.wi[:, 2:3] * ns
            wi = wi / jnp.sqrt(jnp.maximum(dot(wi, wi), jnp.finfo(dtype).tiny))[:, None]
            pdf_rev_dir = jnp.where(bs.is_delta, 0.0, bsdf.pdf(bs.wi, wo_l))
            go = surf & (bs.pdf > 0) & (i < n_steps - 1)
            pdf = jnp.where(go, bs.pdf, 1.0)
            if mode == "radiance":
                scale = jnp.abs(bs.wi[:, 2]) / pdf
            else:  # adjoint BSDF with the shading-normal correction (Veach1997 §5.3)
                wo_ng = jnp.abs(dot(wo, v.n))
                scale = jnp.abs(wo_l[:, 2]) * jnp.abs(dot(wi, v.n))
                scale = scale / (jnp.where(wo_ng > 0, wo_ng, 1.0) * pdf)
            new_beta = jnp.where(go[:, None], beta * bs.f * scale[:, None], 0.0)
            q = jax.lax.stop_gradient(jnp.minimum(jnp.max(new_beta, axis=-1), 0.95))
            roulette = i + 1 >= self.rr_depth  # segments traced so far: i + 1
            go = go & (~roulette | (u[:, 3] < q))
            new_beta = jnp.where(
                go[:, None], new_beta / jnp.where(roulette & go, q, 1.0)[:, None], 0.0
            )
            vert = _Vertices(
                p=p,
                ng=ng,
                ns=ns,
                s=s,
                t=t,
                geometry=frame.geometry,
                wo=wo,
                material=material,
                uv=v.uv,
                beta=jnp.where(valid[:, None], beta, 0.0),
                pdf_fwd=jnp.where(valid, pdf_dir * conv_here, 0.0),
                pdf_rev=jnp.zeros((n,), dtype),
                conv_prev=conv_prev,
                delta=valid & bs.is_delta,
                valid=valid,
                surf=surf,
                has_n=hit,
                hero=hero,
                emit=emit,
                emit_pos=emit_pos,
                emit_dir=emit_dir,
                at_inf=esc,
            )
            prev_rev = jnp.where(go, pdf_rev_dir * conv_prev, 0.0)
            hero = hero | (go & bs.terminate_secondary)
            o2 = jnp.where(go[:, None], _offset(v.p, v.n, wi, _scale(scene, v.p)), 0.0)
            d_next = jnp.where(go[:, None], wi, up)
            pdf_next = jnp.where(go & ~bs.is_delta, bs.pdf, 0.0)
            new = (
                o2, d_next, new_beta, pdf_next, go, v.p, v.n, jnp.ones((n,), bool), hero,
                jnp.zeros((n,), bool),
            )  # fmt: skip
            return new, (vert, prev_rev)

        _, (verts, prev_rev) = jax.lax.scan(step, start, jnp.arange(n_steps, dtype=jnp.int32))
        return verts, prev_rev

    def _subpaths(self, scene, camera, origins, directions, wl, variates, active):
        """The camera subpaths `(D + 1, n)` and light subpaths `(D, n)` vertices, and the
        emission variates."""
        dtype = wl.dtype
        n, k = wl.shape
        depth = self.max_depth
        paths = jnp.arange(n, dtype=jnp.int32)
        zero3 = jnp.zeros((n, 3), dtype)
        ones = jnp.ones((n,), dtype)
        falses = jnp.zeros((n,), bool)
        eye = jnp.broadcast_to(camera.to_world[:3, 3].astype(dtype), (n, 3))

        def endpoint(p, ng, beta, pdf_fwd, valid, has_n):
            s, t = coordinate_system(ng)
            geometry = HitGeometry(zero3, zero3, zero3) if scene.materials.needs_geometry else None
            return _Vertices(
                p=p,
                ng=ng,
                ns=ng,
                s=s,
                t=t,
                geometry=geometry,
                wo=zero3,
                material=jnp.zeros((n,), jnp.int32),
                uv=jnp.zeros((n, scene.surface_width), dtype),
                beta=beta,
                pdf_fwd=pdf_fwd,
                pdf_rev=jnp.zeros((n,), dtype),
                conv_prev=ones,
                delta=falses,
                valid=valid,
                surf=falses,
                has_n=has_n,
                hero=falses,
                emit=jnp.zeros((n, k), dtype),
                emit_pos=jnp.zeros((n,), dtype),
                emit_dir=jnp.zeros((n,), dtype),
                at_inf=falses,
            )

        # Camera subpath: z0 the pinhole, z1 .. zD by the camera ray and BSDF samples.
        start = (
            origins,
            directions,
            jnp.ones((n, k), dtype),
            ones,
            active,
            eye,
            zero3,
            falses,
            falses,
            falses,
        )
        cam, rev = self._walk(scene, wl, variates, paths, start, depth, 0, "radiance")
        # z1's density: the camera's W_e cos(theta) per solid angle, converted to area at z1.
        z1 = jax.tree.map(lambda a: a[0], cam)
        cs = camera.sample_wi(z1.p)
        pdf1 = cs.importance * jnp.abs(dot(z1.ng, cs.wi)) / jnp.where(cs.valid, cs.pdf, 1.0)
        cam = eqx.tree_at(
            lambda c: c.pdf_fwd, cam, cam.pdf_fwd.at[0].set(jnp.where(z1.valid, pdf1, 0.0))
        )
        z0 = endpoint(eye, zero3, jnp.ones((n, k), dtype), ones, active, falses)
        cam = jax.tree.map(lambda a, b: jnp.concatenate([a[None], b], 0), z0, cam)
        cam_rev = jnp.concatenate([rev, jnp.zeros((1, n), dtype)], 0)  # step i gives z_i's
        cam = eqx.tree_at(lambda c: c.pdf_rev, cam, cam_rev)

        # Light subpath: y0 on a light (sample_le), y1 .. y(D-1) by BSDF samples. From a light
        # at infinity (or a directional light) y0 stands for the light itself: its density is
        # that of the direction (pbrt's InfiniteLightDensity, the pick included) and y1's that
        # of the ray's origin on the disk, times the cosine at y1.
        first = _DIMENSIONS_PER_VERTEX * max(depth - 1, 0)
        ue = variates(first, _EMISSION_DIMENSIONS, paths).astype(dtype)
        es = scene.light.sample_le(ue[:, 4], ue[:, 0:2], ue[:, 2:4], ue[:, 5], eye, wl).complete()
        ok = active & (es.pdf_pos > 0) & (es.pdf_dir > 0)
        inf = es.at_infinity & ok
        pdf_pos = jnp.where(ok, es.pdf_pos, 1.0)
        has_n = ~es.delta_pos & ~inf
        pdf_y0 = jnp.where(inf, scene.light.pdf_escaped(-es.d), es.pdf_pos)
        y0 = endpoint(
            es.p, es.n, jnp.where(ok[:, None], es.le / pdf_pos[:, None], 0.0),
            jnp.where(ok, pdf_y0, 0.0), ok, has_n,
        )  # fmt: skip
        y0 = eqx.tree_at(lambda y: y.delta, y0, falses)
        if depth >= 2:
            cos_d = jnp.where(~es.delta_pos, jnp.abs(dot(es.n, es.d)), 1.0)
            beta = es.le * (cos_d / (pdf_pos * jnp.where(ok, es.pdf_dir, 1.0)))[:, None]
            o = jnp.where(has_n[:, None], _offset(es.p, es.n, es.d, _scale(scene, es.p)), es.p)
            up = jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0], dtype), (n, 3))
            pdf_next = jnp.where(inf, es.pdf_disk, es.pdf_dir)
            start = (
                jnp.where(ok[:, None], o, 0.0), jnp.where(ok[:, None], es.d, up),
                jnp.where(ok[:, None], beta, 0.0), jnp.where(ok, pdf_next, 0.0), ok,
                es.p, es.n, has_n, falses, inf,
            )  # fmt: skip
            # Step i is y_(i+1), whose variates follow the emission's.
            first_l = first + _EMISSION_DIMENSIONS
            lv, rev = self._walk(
                scene, wl, variates, paths, start, depth - 1, first_l, "importance"
            )
            lv = jax.tree.map(lambda a, b: jnp.concatenate([a[None], b], 0), y0, lv)
            light_rev = jnp.concatenate([rev, jnp.zeros((1, n), dtype)], 0)
            lv = eqx.tree_at(lambda c: c.pdf_rev, lv, light_rev)
        else:
            lv = jax.tree.map(lambda a: a[None], y0)
        return cam, lv, ue, (es.delta_pos | es.delta_dir) & ok, inf

    # -- connections ----------------------------------------------------------------------

    def _strategy(self, scene, camera, cam, lv, ue, light, wl, s, t):
        """Strategy `(s, t)` (traced ints) for every slot: `(value (n, k), raster (n, 2),
        valid (n,), weight (n,))`; `value` is unweighted (camera radiance for `t >= 2`, the
        splat for `t = 1`). `light = (light_delta, light_inf)`: the slot's light is a delta
        light / at infinity (`_subpaths`)."""
        dtype = wl.dtype
        tiny = jnp.finfo(dtype).tiny
        light_delta, light_inf = light
        pt = _at(cam, t - 1)
        qs = _at(lv, jnp.maximum(s - 1, 0))
        cam_end = t == 1
        s0, s1 = s == 0, s == 1

        d = qs.p - pt.p
        d2 = jnp.maximum(dot(d, d), tiny)
        dist = jnp.sqrt(d2)
        w = d / dist[:, None]  # from the camera end towards the light end
        at_infinity = _has_light_at_infinity(scene.light)
        if at_infinity:
            # s = 1 with a light at infinity (or a directional light): y0 stands for the light,
            # not a point, so the camera end samples a direction towards it (next-event
            # estimation, the light picked by the same variate as the light subpath's).
            inf1 = s1 & light_inf
            ls = scene.light.sample_li(pt.p, ue[:, 4], ue[:, 6:8], wl)
            w = jnp.where(inf1[:, None], ls.wi, w)
            d2 = jnp.where(inf1, 1.0, d2)
        cs = camera.sample_wi(qs.p)
        w_q = jnp.where(cam_end, cs.wi, -w)  # from the light end towards the camera end

        # The light end: the emitter seen from the camera end (s = 1), else its BSDF.
        es = scene.light.sample_le(ue[:, 4], ue[:, 0:2], ue[:, 2:4], ue[:, 5], pt.p, wl)
        cos_l = jnp.where(qs.has_n, jnp.abs(dot(qs.ng, w_q)), 1.0)
        pdf_pos = jnp.where(qs.pdf_fwd > 0, qs.pdf_fwd, 1.0)
        val_emit = es.le_observer * (cos_l / pdf_pos)[:, None]
        fq, pq_fwd, pq_rev = _bsdf_eval(scene, qs, w_q, wl, "importance")
        wo_ng = jnp.abs(dot(qs.wo, qs.ng))
        corr = jnp.abs(dot(qs.wo, qs.ns)) * cos_l / jnp.where(wo_ng > 0, wo_ng, 1.0)
        val_surf = qs.beta * fq * corr[:, None]
        val_l = jnp.where(s1, val_emit, val_surf)
        ok_l = qs.valid & (s1 | qs.surf)
        if at_infinity:
            val_inf = ls.radiance / jnp.where(ls.pdf > 0, ls.pdf, 1.0)[:, None]
            val_l = jnp.where(inf1[:, None], val_inf, val_l)
            ok_l = ok_l & (~inf1 | (ls.pdf > 0))

        # The camera end: the pinhole (t = 1) or a surface vertex's BSDF.
        fp, pp_fwd, pp_rev = _bsdf_eval(scene, pt, w, wl, "radiance")
        cos_p = jnp.abs(dot(pt.ns, w))
        conn = pt.beta * fp * (cos_p / d2)[:, None] * val_l
        splat = val_l * (cs.importance / jnp.where(cs.valid, cs.pdf, 1.0))[:, None]
        value = jnp.where(cam_end, splat, conn)
        value = jnp.where(s0, pt.beta * pt.emit, value)

        # Visibility of the connecting segment, offset at both ends.
        scale_p = _scale(scene, pt.p)
        scale_q = _scale(scene, qs.p)
        a = jnp.where(pt.has_n[:, None], _offset(pt.p, pt.ng, w, scale_p), pt.p)
        b = jnp.where(qs.has_n[:, None], _offset(qs.p, qs.ng, -w, scale_q), qs.p)
        ab = b - a
        ab_len = jnp.sqrt(jnp.maximum(dot(ab, ab), tiny))
        seg_ok = (~s0) & ok_l & jnp.where(cam_end, cs.valid, pt.surf)
        tmax = ab_len * (1.0 - 1e-4)
        direction = ab / ab_len[:, None]
        if at_infinity:  # an unbounded shadow ray towards the light at infinity
            tmax = jnp.where(inf1, jnp.inf, tmax)
            direction = jnp.where(inf1[:, None], w, direction)
        tmax = jnp.where(seg_ok, tmax, 0.0)
        visible = ~scene.accelerator.intersect_any(a, direction, tmax)
        valid = jnp.where(s0, pt.valid & (t >= 2), seg_ok & visible)
        if self.hide_emitters:
            valid = valid & (s + t > 2)
        # A delta light is never seen directly (as with `path` and `ptracer`), nor is a light at
        # infinity by a connection to the camera (strategy (1, 1): its y0 is no point).
        valid = valid & ~(s1 & cam_end & (light_delta | light_inf))

        # MIS: the densities the connection changes (pbrt's ConnectBDPT / MISWeight).
        conv_pt = jnp.abs(dot(pt.ng, w)) / d2
        rev_pt = jnp.where(s1, es.pdf_dir_observer * conv_pt, pq_fwd * conv_pt)
        rev_pt = jnp.where(s0, pt.emit_pos, rev_pt)
        rev_ptm = jnp.where(s0, pt.emit_dir, pp_rev) * pt.conv_prev
        conv_qs = jnp.where(qs.has_n, jnp.abs(dot(qs.ng, w_q)), 1.0)
        rev_qs = jnp.where(
            cam_end,
            cs.importance * conv_qs / jnp.where(cs.valid, cs.pdf, 1.0),
            pp_fwd * conv_qs / d2,
        )
        rev_qsm = pq_rev * qs.conv_prev
        fwd_l = lv.pdf_fwd
        if at_infinity:
            # the light at infinity generates pt from the disk (pbrt's PdfLight: the cosine
            # alone), the camera end samples its direction per solid angle (no conversion),
            # and y0's density is that of the direction next-event estimation sampled
            rev_pt = jnp.where(inf1, _disk_density(scene.light) * jnp.abs(dot(pt.ng, w)), rev_pt)
            rev_qs = jnp.where(inf1, pp_fwd, rev_qs)
            fwd_y0 = jnp.where(inf1, scene.light.pdf_escaped(ls.wi), fwd_l[0])
            fwd_l = fwd_l.at[0].set(fwd_y0)

        jc = jnp.arange(cam.pdf_rev.shape[0], dtype=jnp.int32)[:, None]
        rev_c = jnp.where(jc == t - 1, rev_pt[None], cam.pdf_rev)
        rev_c = jnp.where(jc == t - 2, rev_ptm[None], rev_c)
        delta_c = cam.delta & (jc != t - 1)
        jl = jnp.arange(lv.pdf_rev.shape[0], dtype=jnp.int32)[:, None]
        rev_l = jnp.where(jl == s - 1, rev_qs[None], lv.pdf_rev)
        rev_l = jnp.where(jl == s - 2, rev_qsm[None], rev_l)
        delta_l = lv.delta & (jl != s - 1)
        weight = bdpt_mis_weight(
            cam.pdf_fwd, rev_c, delta_c, t, fwd_l, rev_l, delta_l, light_delta, s,
            heuristic=self.heuristic, light_infinite=jnp.where(s0, pt.at_inf, light_inf),
        )  # fmt: skip

        # Dispersion: a path that kept only its hero wavelength counts it alone (x k).
        k = wl.shape[-1]
        hero_only = pt.hero | (~s0 & qs.hero)
        hero = jnp.zeros((1, k), dtype).at[0, 0].set(k)
        value = jnp.where(hero_only[:, None], value[:, :1] * hero, value)
        value = jnp.where(valid[:, None] & jnp.isfinite(value), value, 0.0)
        return value, cs.raster, valid, jnp.where(valid & jnp.isfinite(weight), weight, 0.0)

    def strategies(self) -> tuple[list[tuple[int, int]], list[tuple[int, int]]]:
        """The `(s, t)` pairs evaluated: those with `t >= 2` (camera-ray radiance) and those
        with `t = 1` (splats), all with `s + t >= 2` and `s + t - 1 <= max_depth`."""
        depth = self.max_depth
        cam = [(s, t) for t in range(2, depth + 2) for s in range(0, depth + 2 - t)]
        light = [(s, 1) for s in range(1, depth + 1)]
        return cam, light

    def radiance_and_splats(
        self, scene, camera, origins, directions, wavelength_nm, variates, active
    ) -> tuple[Float[Array, "n k"], Splats]:
        """Trace a camera subpath along each ray and a light subpath per slot, and combine
        them by every strategy (module docstring).

        **Arguments:** as `AbstractIntegrator.radiance`, plus `camera` (with `sample_wi`).

        **Returns:**

        `(radiance (n, k), splats)`: the MIS-weighted sum of the strategies with `t >= 2`
        [W m^-2 sr^-1 nm^-1], and the weighted `t = 1` strategies as `Splats` of shape
        `(max_depth, n, ...)` (row `s - 1` for strategy `(s, 1)`), normalised by the driver as
        light tracing's are.
        """
        if getattr(scene, "media", None) is not None:
            raise ValueError(
                "bdpt does not handle participating media (the scene has media); render it "
                "with the 'volpath' integrator."
            )
        cam, lv, ue, light_delta, light_inf = self._subpaths(
            scene, camera, origins, directions, wavelength_nm, variates, active
        )
        light = (light_delta, light_inf)
        if self.select is not None:
            return self._selected(scene, camera, cam, lv, ue, light, wavelength_nm)
        pairs_c, pairs_l = self.strategies()

        def one(carry, st):
            value, _, _, weight = self._strategy(
                scene, camera, cam, lv, ue, light, wavelength_nm, st[0], st[1]
            )
            return carry + value * weight[:, None], None

        radiance, _ = jax.lax.scan(
            one, jnp.zeros(wavelength_nm.shape, origins.dtype), jnp.asarray(pairs_c, jnp.int32)
        )

        def one_splat(_, st):
            value, raster, valid, weight = self._strategy(
                scene, camera, cam, lv, ue, light, wavelength_nm, st[0], st[1]
            )
            return None, Splats(raster, value * weight[:, None], valid)

        _, splats = jax.lax.scan(one_splat, None, jnp.asarray(pairs_l, jnp.int32))
        return radiance, splats

    def _selected(self, scene, camera, cam, lv, ue, light, wl):
        """One strategy `self.select = [s, t, weighted]` alone: its estimate (MIS-weighted, or
        with weight 1 where it is valid) as the camera-ray radiance (`t >= 2`) or as one row
        of splats (`t = 1`); the other part is zero. The strategy is traced, so one compiled
        step serves every strategy."""
        s, t, weighted = self.select[0], self.select[1], self.select[2]
        value, raster, valid, weight = self._strategy(scene, camera, cam, lv, ue, light, wl, s, t)
        w = jnp.where(weighted != 0, weight, valid.astype(value.dtype))
        contrib = value * w[:, None]
        splat = t == 1
        radiance = jnp.where(splat, 0.0, contrib)
        splats = Splats(raster[None], jnp.where(splat, contrib, 0.0)[None], (valid & splat)[None])
        return radiance, splats


def _lights(light) -> tuple:
    return tuple(getattr(light, "lights", (light,)))


def _has_light_at_infinity(light) -> bool:
    """Whether any of the scene's lights is at infinity or directional (static)."""
    return any(getattr(lt, "bound_radius", None) is not None for lt in _lights(light))


def _disk_density(light) -> float:
    """$1 / \\pi r^2$, the density per unit area of an emitted ray's origin on the disk across
    a light at infinity (`emission_at_infinity`), or 0 in a scene without one (static)."""
    radii = [float(lt.bound_radius) for lt in _lights(light) if getattr(lt, "bound_radius", 0)]
    return 1.0 / (math.pi * radii[0] ** 2) if radii else 0.0


def _scale(scene, p):
    return scene.ray_epsilon * (1.0 + jnp.max(jnp.abs(p), axis=-1))


def _bsdf_eval(scene, v: _Vertices, wi, wl, mode):
    """The BSDF of the vertices `v` from their `wo` to the world directions `wi`: `f (n, k)`,
    the density of sampling `wi` given `wo` and that of `wo` given `wi` (solid angle)."""

    def to_local(w):
        return jnp.stack([dot(w, v.s), dot(w, v.t), dot(w, v.ns)], axis=-1)

    wo_l, wi_l = to_local(v.wo), to_local(wi)
    bsdf = scene.materials.bxdf(v.material, wl, v.uv, v.geometry)
    f = bsdf.f(wo_l, wi_l, mode=mode)
    return f, bsdf.pdf(wo_l, wi_l), bsdf.pdf(wi_l, wo_l)
