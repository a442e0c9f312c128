r"""Orthographic camera (thesis section 2.3.1) in Mitsuba 3's conventions.

Camera space is that of `radiometria.camera.PinholeCamera` ($+z$ forward, $+y$ up, $+x$
towards the image's left). Every ray travels along camera $+z$; the film covers
$x \in [-1, 1]$ and $y \in [-1/a, 1/a]$ of camera space ($a$ = width / height), so the
`to_world` matrix's scale sets the size of the imaged region (Mitsuba's `orthographic`
sensor). Rays start on the near clip plane $z = n$, as Mitsuba's do.
"""

import equinox as eqx
import jax.numpy as jnp

from .._checks import as_float_array, check_last_axis
from .._types import Array, ArrayLike, Float
from ._base import AbstractCamera
from ._pinhole import (
    _check_camera_fields,
    _check_clip,
    _check_film_and_matrix,
    _crop_field,
    _film_window,
    _point_to_world,
    _raster_to_ndc,
    look_at,
)


class OrthographicCamera(AbstractCamera):
    r"""Parallel projection: the ray through raster $(x, y)$ starts at the camera-space point
    $(1 - 2x/W,\ (1 - 2y/H) / a,\ n)$ and runs along $+z$ (thesis section 2.3.1, the
    orthographic limit of eq. 2.30).

    **Fields:**

    - `to_world`: camera-to-world matrix (4, 4); its scale sets the imaged extent (half-width
        1 in camera space). [scene units]
    - `width`, `height`: film size (static). [px]
    - `near_clip`, `far_clip`: clip distances; rays start at `near_clip`. [scene units]
    - `crop`: `None`, or `(offset_x, offset_y, full_width, full_height)` (static): the image
        is that window of a larger film (`PinholeCamera`'s `crop`). [px]

    !!! note "Thesis"
        Section 2.3.1 (camera models and coordinate spaces).

    ??? cite "References"
        `Pharr2023` §5.2.1 (`OrthographicCamera`); `Jakob2022` (`orthographic` sensor).
    """

    to_world: Float[Array, "4 4"]
    width: int = eqx.field(static=True)
    height: int = eqx.field(static=True)
    near_clip: Float[Array, ""] = eqx.field(default=1e-2, converter=jnp.asarray)
    far_clip: Float[Array, ""] = eqx.field(default=1e4, converter=jnp.asarray)
    crop: tuple[int, int, int, int] | None = eqx.field(default=None, static=True)

    def __check_init__(self):
        _check_camera_fields(self)

    @classmethod
    def from_to_world(
        cls,
        to_world: ArrayLike,
        width: int,
        height: int,
        *,
        near_clip: float = 1e-2,
        far_clip: float = 1e4,
        crop_window=None,
    ) -> "OrthographicCamera":
        """An orthographic camera from its camera-to-world matrix.

        **Arguments:**

        - `to_world`: camera-to-world matrix (4, 4), e.g. a Mitsuba sensor's `to_world`
            (scale it to image a region wider than 2 x 2/aspect). [scene units]
        - `width`, `height`: film size, integers >= 1. [px]
        - `near_clip`, `far_clip`: clip distances, `0 < near < far`. [scene units]
        - `crop_window`: `None` or Mitsuba's film crop `(offset_x, offset_y, crop_width,
            crop_height)` of the `width` x `height` film (`PinholeCamera.from_to_world`). [px]

        **Returns:**

        An `OrthographicCamera`.

        !!! note "Thesis"
            Section 2.3.1.

        ??? cite "References"
            `Jakob2022` (`orthographic` sensor).
        """
        m, width, height = _check_film_and_matrix(to_world, width, height)
        near, far = _check_clip(near_clip, far_clip)
        w, h, crop = _crop_field(crop_window, width, height)
        return cls(m, w, h, near, far, crop=crop)

    @classmethod
    def from_look_at(
        cls,
        origin: ArrayLike,
        target: ArrayLike,
        up: ArrayLike,
        half_width: float,
        width: int,
        height: int,
        *,
        near_clip: float = 1e-2,
        far_clip: float = 1e4,
    ) -> "OrthographicCamera":
        """A camera at `origin` looking at `target`, imaging a region `2 half_width` wide.

        **Arguments:**

        - `origin`, `target`: camera position and a point it looks at, (3,). [scene units]
        - `up`: up direction, (3,), not parallel to `target - origin`. [dimensionless]
        - `half_width`: half the width of the imaged region, > 0. [scene units]
        - `width`, `height`, `near_clip`, `far_clip`: as in `from_to_world`. [px],
            [scene units]

        **Returns:**

        An `OrthographicCamera` with `to_world = look_at(...) @ diag(s, s, 1, 1)`,
        `s = half_width`.

        !!! note "Thesis"
            Section 2.3.1.
        """
        s = as_float_array(half_width, "half_width")
        if jnp.shape(s) != () or not float(s) > 0.0:
            raise ValueError(f"`half_width` must be a scalar > 0 [scene units], got {s}.")
        m = look_at(origin, target, up)
        m = m @ jnp.diag(jnp.stack([s, s, 1.0, 1.0]).astype(m.dtype))
        return cls.from_to_world(m, width, height, near_clip=near_clip, far_clip=far_clip)

    def generate_ray(
        self, raster_xy: ArrayLike
    ) -> tuple[Float[Array, "*batch 3"], Float[Array, "*batch 3"]]:
        """World-space rays through raster positions (..., 2) [px]: origins on the near plane
        (..., 3) [scene units] and the common unit direction, camera $+z$ (..., 3) [-].

        !!! note "Thesis"
            Section 2.3.1.
        """
        xy = check_last_axis(as_float_array(raster_xy, "raster_xy"), "raster_xy", 2)
        dtype = xy.dtype
        m = self.to_world.astype(dtype)
        _, _, fw, fh = _film_window(self)
        x, y = _raster_to_ndc(xy, self)
        y = y * (fh / fw)
        z = jnp.broadcast_to(self.near_clip.astype(dtype), x.shape)
        p = jnp.stack([x, y, z], axis=-1)
        o = _point_to_world(m, p)
        d = m[:3, 2] / jnp.linalg.norm(m[:3, 2])
        return o, jnp.broadcast_to(d, o.shape)
