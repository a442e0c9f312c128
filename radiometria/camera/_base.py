"""The camera interface: rays from raster positions (thesis section 2.3.1)."""

import abc

import equinox as eqx
from jaxtyping import Array, ArrayLike, Float


class AbstractCamera(eqx.Module):
    """A camera model: the ray through each continuous raster position of its film.

    Raster coordinates are continuous pixels, $(0, 0)$ the top-left image corner and pixel
    centres at half-integers (module docstring of `radiometria.camera`). The render driver
    needs only `width`, `height` and `generate_ray`, so any model (pinhole now; orthographic
    and thin lens with the scene-format work) renders through the same code.

    **Subclasses provide:** `width`, `height` (static ints [px]) and `generate_ray`.

    !!! note "Thesis"
        Section 2.3.1 (the camera and its coordinate spaces).

    ??? cite "References"
        `Pharr2023` §5.1 (`Camera` interface); `Jakob2022` (Mitsuba 3's sensors).
    """

    width: eqx.AbstractVar[int]
    height: eqx.AbstractVar[int]

    @abc.abstractmethod
    def generate_ray(
        self, raster_xy: ArrayLike
    ) -> tuple[Float[Array, "*batch 3"], Float[Array, "*batch 3"]]:
        """World-space ray origins and unit directions `(..., 3)` [scene units] through the
        raster positions `raster_xy` `(..., 2)` [px]."""
