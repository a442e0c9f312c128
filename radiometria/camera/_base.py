"""The camera interface: rays from raster positions (thesis section 2.3.1)."""

import abc
from typing import ClassVar

import equinox as eqx
from jaxtyping import Array, ArrayLike, Bool, Float


class CameraWiSample(eqx.Module):
    r"""A connection from scene points to the camera's lens (pbrt's `CameraWiSample`;
    arrays `(n, ...)`), for light tracing.

    **Fields:**

    - `wi`: unit direction from the scene point towards the lens point `(n, 3)`.
    - `dist`: distance to the lens point `(n,)`. [scene units]
    - `importance`: the camera's importance $W_e$ of the ray from the lens point through
        the scene point, normalised so that its integral over the whole film's solid angle
        (times $\cos\theta$ at the lens) is 1, `(n,)`. [sr^-1]
    - `pdf`: the density of the lens point, expressed per unit solid angle at the scene
        point, $d^2 / (|\cos\theta| A_\mathrm{lens})$ (a pinhole: $d^2/|\cos\theta|$), `(n,)`.
        [sr^-1]
    - `raster`: the raster position the ray reaches, `(n, 2)`. [px]
    - `valid`: `(n,)` bool: the point is in front of the camera and its image lies on the
        film.

    A light-path vertex of throughput $\beta$ adds $\beta f |\cos| W_e / p$ at `raster`.

    ??? cite "References"
        `Pharr2023` §5.2.4 (`PerspectiveCamera::We`, `SampleWi`); `Veach1997` §10.2.
    """

    wi: Float[Array, "n 3"]
    dist: Float[Array, " n"]
    importance: Float[Array, " n"]
    pdf: Float[Array, " n"]
    raster: Float[Array, "n 2"]
    valid: Bool[Array, " n"]


class AbstractCamera(eqx.Module):
    """A camera model: the ray through each continuous raster position of its film.

    Raster coordinates are continuous pixels, $(0, 0)$ the top-left image corner and pixel
    centres at half-integers (module docstring of `radiometria.camera`). The render driver
    needs only `width`, `height`, `APERTURE_VARIATES` and `sample_ray`, so every model
    (pinhole, orthographic, thin lens) renders through the same code.

    **Subclasses provide:** `width`, `height` (static ints [px]) and `generate_ray`; a camera
    with a finite aperture also sets `APERTURE_VARIATES = 2` and overrides `sample_ray`, which
    then receives two more uniform variates per sample (the render driver draws them from the
    sampler right after the film position and wavelength, as a stratified pair).

    !!! note "Thesis"
        Section 2.3.1 (the camera and its coordinate spaces).

    ??? cite "References"
        `Pharr2023` §5.1 (`Camera` interface); `Jakob2022` (Mitsuba 3's sensors).
    """

    # Uniform variates `sample_ray` consumes besides the film position: 0 (a pinhole or an
    # orthographic camera) or 2 (a point on a lens aperture).
    APERTURE_VARIATES: ClassVar[int] = 0

    width: eqx.AbstractVar[int]
    height: eqx.AbstractVar[int]

    @abc.abstractmethod
    def generate_ray(
        self, raster_xy: ArrayLike
    ) -> tuple[Float[Array, "*batch 3"], Float[Array, "*batch 3"]]:
        """World-space ray origins and unit directions `(..., 3)` [scene units] through the
        raster positions `raster_xy` `(..., 2)` [px]."""

    def sample_ray(
        self, raster_xy: ArrayLike, aperture_uv: ArrayLike | None = None
    ) -> tuple[Float[Array, "*batch 3"], Float[Array, "*batch 3"]]:
        """The ray of one camera sample: `generate_ray` for cameras without an aperture.

        **Arguments:**

        - `raster_xy`: raster positions `(..., 2)`. [px]
        - `aperture_uv`: `(..., APERTURE_VARIATES)` uniform variates in [0, 1) that place the
            sample on the aperture, or `None` (the aperture's centre). [dimensionless]

        **Returns:**

        World-space origins and unit directions `(..., 3)`. [scene units], [dimensionless]
        """
        del aperture_uv
        return self.generate_ray(raster_xy)

    def sample_wi(self, p: Float[Array, "n 3"]) -> CameraWiSample:
        """Connect the scene points `p` `(n, 3)` [scene units] to the camera (light
        tracing); cameras that cannot yet raise `TypeError`."""
        raise TypeError(
            f"{type(self).__name__} has no importance function yet: light tracing "
            "(`ptracer`) needs `sample_wi` (the pinhole camera has it)."
        )
