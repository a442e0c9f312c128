"""The light interface of the integrators: next-event sampling, its density, emission at hits."""

import abc

import equinox as eqx
from jaxtyping import Array, Bool, Float, Int


class LightSample(eqx.Module):
    """A sampled point or direction on a light, seen from a shading point (arrays `(n, ...)`).

    **Fields:**

    - `wi`: unit direction from the shading point towards the light `(n, 3)`.
    - `dist`: distance to the sampled point along `wi` (inf for a light at infinity) `(n,)`.
        [scene units]
    - `radiance`: radiance arriving from the sample along `-wi`, unoccluded, `(n, k)`.
        [W m^-2 sr^-1 nm^-1]
    - `pdf`: density of the sample per unit solid angle at the shading point `(n,)`; 0 marks
        a failed sample. [sr^-1]

    ??? cite "References"
        `Pharr2023` §12.1 (`LightLiSample`).
    """

    wi: Float[Array, "n 3"]
    dist: Float[Array, " n"]
    radiance: Float[Array, "n k"]
    pdf: Float[Array, " n"]


class AbstractLight(eqx.Module):
    """The emitters of a scene as one plugin (all lights of one kind, as arrays).

    The path tracer calls `sample_li` for next-event estimation at every scattering vertex,
    `emitted` where a ray hits a surface, and `pdf_li` to weight such a hit against
    next-event estimation by multiple importance sampling.

    !!! note "Thesis"
        Chapter 8 (light sources in the light transport equation; title only in the text).

    ??? cite "References"
        `Pharr2023` §12 (light sources and their sampling); `Veach1997` ch. 9 (MIS).
    """

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
