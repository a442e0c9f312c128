"""Direct illumination: the `Direct` integrator and `direct_radiance` (thesis ch. 8)."""

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

from ...montecarlo import power_heuristic
from .._render_scene import RenderScene
from ._base import AbstractIntegrator, scene_flag
from ._path import (
    DIMENSIONS_PER_BOUNCE,
    _offset,
    _vertex,
    path_radiance,
    sample_dimensions,
    shading_frame,
    shadow_ray,
)

_SEGMENTS = 2  # the camera segment and one scattering vertex's light and BSDF samples
DIMENSIONS_PER_SAMPLE = 4  # [u0, u1 | light choice or BSDF lobe, unused]


def direct_radiance(
    scene: RenderScene,
    origins: Float[Array, "n 3"],
    directions: Float[Array, "n 3"],
    wavelength_nm: Float[Array, "n k"],
    u: Float[Array, "n d"],
    *,
    emitter_samples: int,
    bsdf_samples: int,
    active: Bool[Array, " n"] | None = None,
    hide_emitters: bool = False,
) -> Float[Array, "n k"]:
    r"""Direct illumination with `emitter_samples` light samples and `bsdf_samples` BSDF
    samples at the first hit, combined by the multi-sample power heuristic (Mitsuba 3's
    `direct` with its `emitter_samples` and `bsdf_samples`).

    With $M$ light and $N$ BSDF samples, each light sample $\omega_i$ (density $p_L$)
    contributes $w_L\, f\, L_e |\cos\theta| / (M p_L)$ and each BSDF sample (density $p_f$)
    that finds an emitter $w_f\, f\, L_e |\cos\theta| / (N p_f)$, with Veach's power heuristic
    over the sample counts, $w_L = (M p_L)^2 / ((M p_L)^2 + (N p_f)^2)$ and symmetrically
    $w_f$ (multi-sample MIS, `Veach1997` §9.2.4). Delta lights and specular lobes take weight 1.
    Emission seen from the camera is added with weight 1 (or not at all with `hide_emitters`).

    **Arguments:**

    - `scene`: the compiled scene (`RenderScene`).
    - `origins`, `directions`: camera rays `(n, 3)`, directions unit length. [scene units]
    - `wavelength_nm`: the hero wavelengths of each path `(n, k)`. [nm]
    - `u`: uniform variates `(n, 4 (emitter_samples + bsdf_samples))` in [0, 1): four per
        light sample `[u0, u1, light choice, unused]`, then four per BSDF sample `[u0, u1,
        lobe, unused]`. [1]
    - `emitter_samples`, `bsdf_samples`: static ints >= 0, not both 0.
    - `active`: optional `(n,)` booleans; inactive rays return 0.
    - `hide_emitters`: emitters seen directly from the camera are black (static bool).

    **Returns:**

    Radiance estimates `(n, k)` [W m^-2 sr^-1 nm^-1, or the unit of the scene's emission].

    !!! note "Thesis"
        Chapter 8 (direct lighting; title only in the text), with the MIS of chapters 6-7.

    ??? cite "References"
        `Veach1997` §9.2 (multi-sample MIS, power heuristic); `Pharr2023` §13.3;
        `Jakob2022` (`direct`).
    """
    m, n_b = _check_counts(emitter_samples, bsdf_samples)
    n_rays, k = wavelength_nm.shape
    dims = DIMENSIONS_PER_SAMPLE * (m + n_b)
    if u.shape != (n_rays, dims):
        raise ValueError(f"`u` must have shape (rays, {dims}) = {(n_rays, dims)}, got {u.shape}.")
    live = jnp.ones((n_rays,), bool) if active is None else jnp.asarray(active, bool)
    dtype = origins.dtype

    v = _vertex(scene, origins, directions)
    le = scene.light.emitted(v.face, v.cos_o, v.valid, wavelength_nm, v.uv)
    le = jnp.where(
        v.valid[:, None], le, scene.light.emitted_escaped(directions, ~v.valid, wavelength_nm)
    )
    radiance = jnp.zeros((n_rays, k), dtype) if hide_emitters else le
    radiance = jnp.where(live[:, None], radiance, 0.0)

    frame = shading_frame(scene, v)
    scatters = live & v.valid & frame.scatters
    wo_l = frame.to_local(-directions)
    bsdf = scene.materials.bxdf(frame.material, wavelength_nm, v.uv, frame.geometry)
    offset = scene.ray_epsilon * (1.0 + jnp.max(jnp.abs(v.p), axis=-1))
    hero = jnp.zeros((1, k), dtype).at[0, 0].set(k)

    def light_sample(total, u_i):
        ls = scene.light.sample_li(v.p, u_i[:, 2], u_i[:, 0:2], wavelength_nm)
        wi_l = frame.to_local(ls.wi)
        f = bsdf.f(wo_l, wi_l) * jnp.abs(wi_l[:, 2:3])
        w = power_heuristic(m, ls.pdf, n_b, bsdf.pdf(wo_l, wi_l))
        if ls.delta is not None:  # no BSDF sample finds a delta light
            w = jnp.where(ls.delta, 1.0, w)
        use = scatters & (ls.pdf > 0)
        origin, direction, tmax = shadow_ray(v.p, v.n, ls.wi, ls.dist, offset)
        use = use & ~scene.accelerator.intersect_any(origin, direction, jnp.where(use, tmax, 0.0))
        c = f * ls.radiance * (w / (m * jnp.where(use, ls.pdf, 1.0)))[:, None]
        return total + jnp.where(use[:, None], c, 0.0), None

    def bsdf_sample(total, u_j):
        bs = bsdf.sample_f(wo_l, u_j[:, 2], u_j[:, 0:2])
        use = scatters & (bs.pdf > 0)
        wi = frame.to_world(bs.wi)
        wi = wi / jnp.sqrt(jnp.sum(wi * wi, axis=-1, keepdims=True))
        o = _offset(v.p, v.n, wi, offset)
        hit = _vertex(scene, o, jnp.where(use[:, None], wi, directions))
        le_b = scene.light.emitted(hit.face, hit.cos_o, hit.valid, wavelength_nm, hit.uv)
        le_b = jnp.where(
            hit.valid[:, None],
            le_b,
            scene.light.emitted_escaped(wi, use & ~hit.valid, wavelength_nm),
        )
        pdf_light = jnp.where(
            hit.valid,
            scene.light.pdf_li(hit.face, hit.t, hit.cos_o, o),
            scene.light.pdf_escaped(wi),
        )
        w = jnp.where(bs.is_delta, 1.0, power_heuristic(n_b, bs.pdf, m, pdf_light))
        weight = bs.f * (jnp.abs(bs.wi[:, 2]) / jnp.where(use, bs.pdf, 1.0))[:, None]
        c = weight * le_b * (w / n_b)[:, None]
        # Through a dispersive interface only the hero wavelength is valid (as in `path`).
        c = jnp.where(bs.terminate_secondary[:, None], c[:, :1] * hero, c)
        return total + jnp.where(use[:, None], c, 0.0), None

    zero = jnp.zeros((n_rays, k), dtype)
    per = u.reshape(n_rays, m + n_b, DIMENSIONS_PER_SAMPLE).transpose(1, 0, 2)
    if m:
        lit, _ = jax.lax.scan(light_sample, zero, per[:m])
        radiance = radiance + lit
    if n_b:
        found, _ = jax.lax.scan(bsdf_sample, zero, per[m:])
        radiance = radiance + found
    return radiance


def _check_counts(emitter_samples, bsdf_samples) -> tuple[int, int]:
    for name, v in (("emitter_samples", emitter_samples), ("bsdf_samples", bsdf_samples)):
        if isinstance(v, bool) or not isinstance(v, int) or v < 0:
            raise ValueError(f"`{name}` must be an int >= 0, got {v!r}.")
    if emitter_samples + bsdf_samples == 0:
        raise ValueError("`emitter_samples` and `bsdf_samples` must not both be 0.")
    return emitter_samples, bsdf_samples


class Direct(AbstractIntegrator):
    """Direct illumination: emission seen from the camera plus, at the first hit,
    `emitter_samples` light samples and `bsdf_samples` BSDF samples combined by multiple
    importance sampling (power heuristic): Mitsuba 3's `direct` integrator.

    With one sample of each (the default) it is the path estimator with two segments and no
    Russian roulette (`path_radiance` with `max_depth=2`); other counts use `direct_radiance`.

    **Arguments:**

    - `emitter_samples`: light samples per hit (Mitsuba's `emitter_samples`, default 1),
        static int >= 0.
    - `bsdf_samples`: BSDF samples per hit (Mitsuba's `bsdf_samples`, default 1), static
        int >= 0; not both 0.
    - `hide_emitters`: emitters seen directly from the camera are black (Mitsuba's
        `hide_emitters`; default False).

    !!! note "Thesis"
        Chapter 8 (direct lighting; title only in the text).

    ??? cite "References"
        `Veach1997` §9.2 (MIS); `Pharr2023` §13.3; `Jakob2022` (`direct`).
    """

    NAME: ClassVar[str] = "direct"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"emitter_samples", "bsdf_samples", "shading_samples", "hide_emitters"}
    )

    emitter_samples: int = eqx.field(static=True, default=1)
    bsdf_samples: int = eqx.field(static=True, default=1)
    hide_emitters: bool = eqx.field(static=True, default=False)

    def __check_init__(self):
        if not isinstance(self.hide_emitters, bool):
            raise TypeError(f"`hide_emitters` must be a bool, got {self.hide_emitters!r}.")
        _check_counts(self.emitter_samples, self.bsdf_samples)

    @classmethod
    def from_properties(cls, params: dict, *, where: str = "scene") -> "Direct":
        """Mitsuba's `direct`: `emitter_samples` and `bsdf_samples` (default 1 each), or
        `shading_samples` for both (not together with either), and `hide_emitters`."""
        counts = {}
        if "shading_samples" in params:
            if "emitter_samples" in params or "bsdf_samples" in params:
                raise ValueError(
                    f"{where}: give either shading_samples or emitter_samples/bsdf_samples, "
                    "not both (Mitsuba's rule)."
                )
            counts = dict.fromkeys(("emitter_samples", "bsdf_samples"), params["shading_samples"])
        else:
            for name in ("emitter_samples", "bsdf_samples"):
                counts[name] = params.get(name, 1)
        try:
            _check_counts(counts["emitter_samples"], counts["bsdf_samples"])
        except ValueError as err:
            raise ValueError(f"{where}: {err}") from None
        return cls(hide_emitters=scene_flag(params, "hide_emitters", False, where), **counts)

    def _single(self) -> bool:
        return self.emitter_samples == 1 and self.bsdf_samples == 1

    def sample_dimensions(self) -> int:
        if self._single():
            return sample_dimensions(_SEGMENTS)
        return DIMENSIONS_PER_SAMPLE * (self.emitter_samples + self.bsdf_samples)

    def radiance(self, scene, origins, directions, wavelength_nm, variates, active):
        if not self._single():
            paths = jnp.arange(origins.shape[0], dtype=jnp.int32)
            return direct_radiance(
                scene,
                origins,
                directions,
                wavelength_nm,
                variates(0, self.sample_dimensions(), paths),
                emitter_samples=self.emitter_samples,
                bsdf_samples=self.bsdf_samples,
                active=active,
                hide_emitters=self.hide_emitters,
            )

        def u(b, paths):
            return variates(DIMENSIONS_PER_BOUNCE * b, DIMENSIONS_PER_BOUNCE, paths)

        return path_radiance(
            scene,
            origins,
            directions,
            wavelength_nm,
            u,
            max_depth=_SEGMENTS,
            rr_depth=_SEGMENTS,
            active=active,
            hide_emitters=self.hide_emitters,
        )
