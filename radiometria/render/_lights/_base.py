"""The light interface of the integrators: next-event sampling, its density, emission at hits
and along rays that escape the scene."""

import abc
from typing import ClassVar

import equinox as eqx
from jaxtyping import Array, Bool, Float, Int


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
        self, face: Int[Array, " n"], dist: Float[Array, " n"], cos_light: Float[Array, " n"]
    ) -> Float[Array, " n"]:
        """Solid-angle density [sr^-1] with which `sample_li` picks the surface point a ray hit
        on triangle `face` at distance `dist` [scene units], where `cos_light` is the cosine
        between the triangle's normal and the direction back to the ray's origin."""

    @abc.abstractmethod
    def emitted(
        self,
        face: Int[Array, " n"],
        cos_o: Float[Array, " n"],
        valid: Bool[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
    ) -> Float[Array, "n k"]:
        """Radiance [W m^-2 sr^-1 nm^-1] leaving the hit on triangle `face` towards the ray's
        origin, where `cos_o` is the cosine between the normal and that direction and
        `valid` marks rays that hit something."""

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

    @abc.abstractmethod
    def power(self, scene_radius: float) -> float:
        """Emitted power of the plugin's lights, averaged over the renderer's wavelength grid,
        for picking among lights (NumPy, outside `jit`). Lights at infinity and directional
        lights count what falls on a disk of radius `scene_radius` [scene units] (pbrt's
        convention). [W nm^-1, or the scene's emission unit x area]"""
