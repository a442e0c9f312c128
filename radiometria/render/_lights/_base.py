"""The light interface of the integrators: next-event sampling, its density, emission at hits
and along rays that escape the scene."""

import abc
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from ...montecarlo import sample_uniform_disk_concentric
from ...scattering import coordinate_system

__all__ = ["AbstractLight", "EmissionSample", "LightSample", "emission_at_infinity"]


class LightSample(eqx.Module):
    """A sampled point or direction on a light, seen from a shading point (arrays `(n, ...)`).

    **Fields:**

    - `wi`: unit direction from the shading point towards the light `(n, 3)`.
    - `dist`: distance to the sampled point along `wi` (inf for a light at infinity) `(n,)`.
        [scene units]
    - `radiance`: radiance arriving from the sample along `-wi`, unoccluded, `(n, k)`; for a
        delta light (a point, a spot, a direction) the irradiance-like quantity whose ratio to
        `pdf` is the estimate (intensity / distance^2, or irradiance).
        [W m^-2 sr^-1 nm^-1, or W m^-2 nm^-1 for delta lights]
    - `pdf`: density of the sample per unit solid angle at the shading point `(n,)`; for a
        delta light the discrete probability of having chosen it; 0 marks a failed sample.
        [sr^-1, or 1 for delta lights]
    - `delta`: `(n,)` bool, the sample comes from a delta light (no BSDF sample can find it,
        so next-event estimation takes it with MIS weight 1); `None` means no delta light.

    ??? cite "References"
        `Pharr2023` §12.1 (`LightLiSample`), §12.3 (delta lights).
    """

    wi: Float[Array, "n 3"]
    dist: Float[Array, " n"]
    radiance: Float[Array, "n k"]
    pdf: Float[Array, " n"]
    delta: Bool[Array, " n"] | None = None


class EmissionSample(eqx.Module):
    r"""A sampled emitted ray, the start of a light path (pbrt's `SampleLe`; arrays `(n, ...)`).

    **Fields:**

    - `p`: the point on the light `(n, 3)`. [scene units]
    - `n`: the light's unit surface normal at `p` `(n, 3)`, on the emitting side; zero for
        lights without a surface (point, spot).
    - `d`: unit direction of the emitted ray `(n, 3)`.
    - `le`: what leaves `p` along `d`, `(n, k)`: radiance for area lights, intensity for
        point and spot lights. [W m^-2 sr^-1 nm^-1, or W sr^-1 nm^-1]
    - `pdf_pos`: density of `p`, the light's pick probability included: per unit area, or
        the discrete probability for a light without a surface. [m^-2, or 1]
    - `pdf_dir`: solid-angle density of `d` given `p`. [sr^-1]
    - `le_observer`: what leaves `p` towards the `observer` point given to `sample_le`
        (the camera's lens point), `(n, k)`, same unit as `le`.
    - `delta_pos`: `(n,)` bool: `p` is a delta position (point, spot), so no cosine factor
        at the light and no surface to hit.

    - `pdf_dir_observer`: the solid-angle density with which `sample_le` would have emitted
        the direction from `p` towards `observer` `(n,)` (0 outside the emission; for
        bidirectional path tracing's MIS weights). [sr^-1]
    - `at_infinity`: `(n,)` bool: the light is at infinity or directional, so `p` is the
        ray's origin on a disk across `d` (`emission_at_infinity`), not a point on the light.
    - `delta_dir`: `(n,)` bool: `d` is a delta direction (a directional light), so no path
        can reach the light by chance.
    - `pdf_disk`: `(n,)` density per unit area of the origin on that disk, without the
        light's pick probability ($1/\pi r^2$; 0 for lights not at infinity). [m^-2]

    The last three are `None` for lights that never set them (read as False / 0; `complete`
    fills them in).

    The light path's initial throughput is `le |n . d| / (pdf_pos pdf_dir)` (no cosine for
    `delta_pos`), and 0 marks a failed sample (`pdf_pos = 0`).

    ??? cite "References"
        `Pharr2023` §12.1 (`LightLeSample`); `Veach1997` §10.2 (light tracing).
    """

    p: Float[Array, "n 3"]
    n: Float[Array, "n 3"]
    d: Float[Array, "n 3"]
    le: Float[Array, "n k"]
    pdf_pos: Float[Array, " n"]
    pdf_dir: Float[Array, " n"]
    le_observer: Float[Array, "n k"]
    delta_pos: Bool[Array, " n"]
    pdf_dir_observer: Float[Array, " n"] | None = None
    at_infinity: Bool[Array, " n"] | None = None
    delta_dir: Bool[Array, " n"] | None = None
    pdf_disk: Float[Array, " n"] | None = None

    def complete(self) -> "EmissionSample":
        """The same sample with every optional field present: zero densities and False
        flags where the light left them `None` (so samples of several lights can be merged)."""
        zero = jnp.zeros(self.pdf_pos.shape, self.pdf_pos.dtype)
        false = jnp.zeros(self.pdf_pos.shape, bool)

        def fill(x, default):
            return default if x is None else x

        return eqx.tree_at(
            lambda e: (e.pdf_dir_observer, e.at_infinity, e.delta_dir, e.pdf_disk),
            self,
            (
                fill(self.pdf_dir_observer, zero),
                fill(self.at_infinity, false),
                fill(self.delta_dir, false),
                fill(self.pdf_disk, zero),
            ),
            is_leaf=lambda x: x is None,
        )


class AbstractLight(eqx.Module):
    """The emitters of a scene as one plugin (all lights of one kind, as arrays), or a
    `LightSet` of several such plugins.

    The path tracer calls `sample_li` for next-event estimation at every scattering vertex,
    `emitted` where a ray hits a surface, `emitted_escaped` where a ray leaves the scene
    (lights at infinity: `constant`, `envmap`), and `pdf_li` / `pdf_escaped` to weight such
    a hit or escape against next-event estimation by multiple importance sampling. Delta
    lights (`point`, `spot`, `directional`) are only sampled: rays never hit them, so their
    `emitted`, `emitted_escaped`, `pdf_li` and `pdf_escaped` are 0, and their samples carry
    `delta = True`.

    Every plugin also reports its emitted power (`power`), by which a `LightSet` picks one
    light per next-event sample.

    !!! note "Thesis"
        Chapter 8 (light sources in the light transport equation; title only in the text).

    ??? cite "References"
        `Pharr2023` §12 (light sources and their sampling), §12.6 (light sampling by power);
        `Veach1997` ch. 9 (MIS).
    """

    # What a scene file calls the plugin (`<emitter type=...>`) and the parameters it reads.
    NAME: ClassVar[str]
    PARAMETERS: ClassVar[frozenset[str]]

    @abc.abstractmethod
    def sample_li(
        self,
        p: Float[Array, "n 3"],
        u_select: Float[Array, " n"],
        u2: Float[Array, "n 2"],
        wavelength_nm: Float[Array, "n k"],
    ) -> LightSample:
        """Sample a point on the lights as seen from the shading points `p` [scene units],
        with `u_select` choosing a light (or light element) and `u2` a point on it."""

    @abc.abstractmethod
    def pdf_li(
        self,
        face: Int[Array, " n"],
        dist: Float[Array, " n"],
        cos_light: Float[Array, " n"],
        origin: Float[Array, "n 3"] | None = None,
    ) -> Float[Array, " n"]:
        """Solid-angle density [sr^-1] with which `sample_li` picks the surface point a ray hit
        on triangle `face` at distance `dist` [scene units], where `cos_light` is the cosine
        between the triangle's normal and the direction back to the ray's origin `origin`
        (the shading point whose light sample it competes with; a density that depends on
        the shading point, as a sphere's cone, needs it)."""

    @abc.abstractmethod
    def emitted(
        self,
        face: Int[Array, " n"],
        cos_o: Float[Array, " n"],
        valid: Bool[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        uv: Float[Array, "n _"] | None = None,
    ) -> Float[Array, "n k"]:
        """Radiance [W m^-2 sr^-1 nm^-1] leaving the hit on triangle `face` towards the ray's
        origin, where `cos_o` is the cosine between the normal and that direction, `valid`
        marks rays that hit something and `uv` are the hits' surface coordinates [1] (for a
        textured radiance; `None`: looked up at (0, 0))."""

    @abc.abstractmethod
    def emitted_escaped(
        self,
        directions: Float[Array, "n 3"],
        escaped: Bool[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
    ) -> Float[Array, "n k"]:
        """Radiance [W m^-2 sr^-1 nm^-1] arriving from lights at infinity along rays of unit
        direction `directions` that left the scene (`escaped`; 0 elsewhere)."""

    @abc.abstractmethod
    def pdf_escaped(self, directions: Float[Array, "n 3"]) -> Float[Array, " n"]:
        """Solid-angle density [sr^-1] with which `sample_li` picks the unit direction
        `directions` towards a light at infinity (0 for lights that are not at infinity)."""

    def sample_le(
        self,
        u_select: Float[Array, " n"],
        u_pos: Float[Array, "n 2"],
        u_dir: Float[Array, "n 2"],
        u_side: Float[Array, " n"],
        observer: Float[Array, "n 3"],
        wavelength_nm: Float[Array, "n k"],
    ) -> EmissionSample:
        """Sample an emitted ray (light tracing): a light by power (`u_select`), a point on it
        (`u_pos`), a direction (`u_dir`; `u_side` picks the side of a two-sided emitter), and
        the emission towards the points `observer` [scene units] as well. Every built-in
        light implements it; a plugin that does not raises `ValueError` here, so light
        tracing, `bdpt` and `pssmlt` refuse it by name."""
        raise ValueError(
            f"the {getattr(self, 'NAME', type(self).__name__)!r} light cannot start light "
            "paths: its plugin does not implement `sample_le` (light tracing, bdpt and pssmlt "
            "need it)."
        )

    def pdf_le(
        self, face: Int[Array, " n"], cos_o: Float[Array, " n"]
    ) -> tuple[Float[Array, " n"], Float[Array, " n"]]:
        """The densities with which `sample_le` would start a light path at a point of the
        emissive triangle `face` and leave it in a direction at cosine `cos_o` to the
        triangle's normal (pbrt's `PdfLe`): `(pdf_pos, pdf_dir)`, the position's density per
        unit area with the light's pick probability included [m^-2] and the direction's per
        unit solid angle [sr^-1]; 0 where no light of this plugin lies there (the default:
        lights without surfaces)."""
        zero = jnp.zeros(face.shape, cos_o.dtype)
        return zero, zero

    @abc.abstractmethod
    def power(self, scene_radius: float) -> float:
        """Emitted power of the plugin's lights, averaged over the renderer's wavelength grid,
        for picking among lights (NumPy, outside `jit`). Lights at infinity and directional
        lights count what falls on a disk of radius `scene_radius` [scene units] (pbrt's
        convention). [W nm^-1, or the scene's emission unit x area]"""


def emission_at_infinity(
    d: Float[Array, "n 3"],
    u_pos: Float[Array, "n 2"],
    center: Float[Array, " 3"],
    radius: float,
    le: Float[Array, "n k"],
    pdf_dir: Float[Array, " n"],
    pick_prob: Float[Array, " n"],
    *,
    delta_dir: bool = False,
) -> EmissionSample:
    r"""An emitted ray of a light at infinity (or a directional light) travelling along the
    unit directions `d`: its origin uniform on the disk of radius `radius` [scene units]
    about `center` perpendicular to `d`, one radius behind the bounding sphere, so the ray
    crosses the whole scene (pbrt-v4's `SampleLe` of distant and infinite lights).

    `pdf_pos` is $P / (\pi r^2)$ [m^-2] with `pick_prob` $P$, `pdf_dir` the given solid-angle
    density of `d` [sr^-1] (1 for a delta direction, `delta_dir` True: a directional light),
    and `n = d` (the disk's normal, so the throughput $L_e |n \cdot d| / (p_A p_\omega)$ has
    no cosine). The camera never sees the disk, so `le_observer` and `pdf_dir_observer` are
    0; `at_infinity` is True and `pdf_disk` is $1 / \pi r^2$.

    ??? cite "References"
        `Pharr2023` §12.4 (distant lights), §12.5 (infinite lights' `SampleLe`).
    """
    dtype = d.dtype
    s, t = coordinate_system(d)
    disk = sample_uniform_disk_concentric(u_pos, check=False).astype(dtype)
    p = center[None, :] + radius * (disk[:, 0:1] * s + disk[:, 1:2] * t - d)
    n = d.shape[0]
    zero = jnp.zeros((n,), dtype)
    return EmissionSample(
        p=p,
        n=d,
        d=d,
        le=le,
        pdf_pos=pick_prob / (jnp.pi * radius * radius),
        pdf_dir=pdf_dir,
        le_observer=jnp.zeros_like(le),
        delta_pos=jnp.zeros((n,), bool),
        pdf_dir_observer=zero,
        at_infinity=jnp.ones((n,), bool),
        delta_dir=jnp.full((n,), delta_dir, bool),
        pdf_disk=jnp.full((n,), 1.0 / (jnp.pi * radius * radius), dtype),
    )
