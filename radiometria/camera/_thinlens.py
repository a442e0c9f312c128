r"""Thin-lens camera (thesis section 2.3.1) in Mitsuba 3's conventions: depth of field.

A thin lens of radius $r$ at the camera's origin, focused at distance $d_f$ along $+z$: the
ray of raster point $(x, y)$ and aperture variates $(u_1, u_2)$ leaves the lens point
$\vec{a} = r\,\mathrm{disk}(u_1, u_2)$ (Shirley and Chiu's concentric map) towards the point
$\vec{f} = d_f\,(x_\mathrm{ndc} \tan\frac{\mathrm{fov}_x}{2},
y_\mathrm{ndc} \tan\frac{\mathrm{fov}_y}{2}, 1)$ on the plane of focus, which the pinhole
camera's ray through the same raster point also reaches. Points on that plane are imaged
sharply; a point at depth $z$ is spread over a disk of diameter
$c = 2 r\,|z - d_f| / z$ measured on the plane of focus (the circle of confusion), i.e.
$c\,W / (2 d_f \tan\frac{\mathrm{fov}_x}{2})$ pixels. As Mitsuba's `thinlens` sensor, rays
start where they cross the near clip plane, and every ray has unit weight.
"""

import equinox as eqx
import jax.numpy as jnp

from .._checks import as_float_array, check_last_axis
from .._types import Array, ArrayLike, Float
from ..montecarlo import sample_uniform_disk_concentric
from ._base import AbstractCamera
from ._pinhole import (
    _check_camera_fields,
    _check_clip,
    _check_film_and_matrix,
    _crop_field,
    _film_window,
    _point_to_world,
    _raster_to_ndc,
    fov_x_deg,
    look_at,
)


def _check_lens(aperture_radius, focus_distance):
    r = as_float_array(aperture_radius, "aperture_radius")
    f = as_float_array(focus_distance, "focus_distance")
    if jnp.shape(r) != () or not float(r) >= 0.0:
        raise ValueError(f"`aperture_radius` must be a scalar >= 0 [scene units], got {r}.")
    if jnp.shape(f) != () or not float(f) > 0.0:
        raise ValueError(f"`focus_distance` must be a scalar > 0 [scene units], got {f}.")
    return r, f


class ThinLensCamera(AbstractCamera):
    r"""Perspective camera with a thin lens: depth of field (module docstring).

    Build it with `ThinLensCamera.from_to_world(...)` or `ThinLensCamera.from_look_at(...)`.
    `sample_ray(raster_xy, aperture_uv)` takes two aperture variates (`APERTURE_VARIATES`);
    `generate_ray` gives the ray through the lens centre (the pinhole camera's).

    **Fields:**

    - `to_world`: camera-to-world matrix, (4, 4). [scene units]
    - `fov_x_deg`: horizontal field of view. [deg]
    - `aperture_radius`: lens radius $r$, >= 0 (0 is a pinhole). [scene units]
    - `focus_distance`: distance $d_f$ of the plane in focus, along $+z$. [scene units]
    - `width`, `height`: film size (static). [px]
    - `near_clip`, `far_clip`: clip distances; rays start at the near plane. [scene units]
    - `crop`: `None`, or `(offset_x, offset_y, full_width, full_height)` (static): the image
        is that window of a larger film (`PinholeCamera`'s `crop`). [px]

    !!! note "Thesis"
        Section 2.3.1 (camera models).

    ??? cite "References"
        `Pharr2023` §5.2.3 (the thin lens model and depth of field); `Shirley1997`
        (concentric disk map); `Jakob2022` (`thinlens` sensor).
    """

    APERTURE_VARIATES = 2

    to_world: Float[Array, "4 4"]
    fov_x_deg: Float[Array, ""]
    aperture_radius: Float[Array, ""]
    focus_distance: Float[Array, ""]
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
        fov_deg: ArrayLike,
        width: int,
        height: int,
        aperture_radius: float,
        focus_distance: float,
        fov_axis: str = "x",
        *,
        near_clip: float = 1e-2,
        far_clip: float = 1e4,
        crop_window=None,
    ) -> "ThinLensCamera":
        """A thin-lens camera from its camera-to-world matrix.

        **Arguments:**

        - `to_world`: camera-to-world matrix (4, 4). [scene units]
        - `fov_deg`: field of view along `fov_axis`, in (0, 180). [deg]
        - `width`, `height`: film size, integers >= 1. [px]
        - `aperture_radius`: lens radius, >= 0. [scene units]
        - `focus_distance`: distance of the plane in focus, > 0. [scene units]
        - `fov_axis`: `"x"` (default, Mitsuba's), `"y"`, `"diagonal"`, `"smaller"`,
            `"larger"` (`radiometria.camera.fov_x_deg`).
        - `near_clip`, `far_clip`: clip distances, `0 < near < far`. [scene units]
        - `crop_window`: `None` or Mitsuba's film crop `(offset_x, offset_y, crop_width,
            crop_height)` of the `width` x `height` film (`PinholeCamera.from_to_world`). [px]

        **Returns:**

        A `ThinLensCamera`.

        !!! note "Thesis"
            Section 2.3.1.

        ??? cite "References"
            `Jakob2022` (`thinlens` sensor).
        """
        m, width, height = _check_film_and_matrix(to_world, width, height)
        fx = fov_x_deg(fov_deg, width / height, fov_axis)
        r, f = _check_lens(aperture_radius, focus_distance)
        near, far = _check_clip(near_clip, far_clip)
        w, h, crop = _crop_field(crop_window, width, height)
        return cls(m, fx, r, f, w, h, near, far, crop=crop)

    @classmethod
    def from_look_at(
        cls,
        origin: ArrayLike,
        target: ArrayLike,
        up: ArrayLike,
        fov_deg: ArrayLike,
        width: int,
        height: int,
        aperture_radius: float,
        focus_distance: float,
        fov_axis: str = "x",
        *,
        near_clip: float = 1e-2,
        far_clip: float = 1e4,
    ) -> "ThinLensCamera":
        """A thin-lens camera at `origin` looking at `target` with `up` up on the image.

        **Arguments:** `origin`, `target`, `up` as in `radiometria.camera.look_at`
        [scene units]; the others as in `from_to_world`.

        **Returns:**

        A `ThinLensCamera` with `to_world = look_at(origin, target, up)`.

        !!! note "Thesis"
            Section 2.3.1.
        """
        return cls.from_to_world(
            look_at(origin, target, up),
            fov_deg,
            width,
            height,
            aperture_radius,
            focus_distance,
            fov_axis,
            near_clip=near_clip,
            far_clip=far_clip,
        )

    def generate_ray(
        self, raster_xy: ArrayLike
    ) -> tuple[Float[Array, "*batch 3"], Float[Array, "*batch 3"]]:
        """Rays through the lens centre (the pinhole camera's), raster positions (..., 2)
        [px] to world-space origins and unit directions (..., 3).

        !!! note "Thesis"
            Section 2.3.1.
        """
        xy = check_last_axis(as_float_array(raster_xy, "raster_xy"), "raster_xy", 2)
        return self.sample_ray(xy, jnp.full(xy.shape, 0.5, xy.dtype))

    def sample_ray(
        self, raster_xy: ArrayLike, aperture_uv: ArrayLike | None = None
    ) -> tuple[Float[Array, "*batch 3"], Float[Array, "*batch 3"]]:
        r"""The ray from the lens point of `aperture_uv` through the focal-plane point of
        `raster_xy` (module docstring).

        **Arguments:**

        - `raster_xy`: raster positions (..., 2). [px]
        - `aperture_uv`: uniform variates (..., 2) in [0, 1), mapped to the lens disk by the
            concentric map; `None` is the lens centre. [dimensionless]

        **Returns:**

        World-space origins (on the near plane) and unit directions, (..., 3) each.
        [scene units], [dimensionless]

        !!! note "Thesis"
            Section 2.3.1.

        ??? cite "References"
            `Pharr2023` §5.2.3; `Jakob2022` (`thinlens`).
        """
        xy = check_last_axis(as_float_array(raster_xy, "raster_xy"), "raster_xy", 2)
        dtype = xy.dtype
        if aperture_uv is None:
            aperture_uv = jnp.full(xy.shape, 0.5, dtype)
        uv = check_last_axis(as_float_array(aperture_uv, "aperture_uv"), "aperture_uv", 2)
        m = self.to_world.astype(dtype)
        tan_x = jnp.tan(jnp.deg2rad(self.fov_x_deg.astype(dtype)) / 2)
        _, _, fw, fh = _film_window(self)
        tan_y = tan_x * (fh / fw)
        x_ndc, y_ndc = _raster_to_ndc(xy, self)
        f = self.focus_distance.astype(dtype)
        focus = jnp.stack(
            [x_ndc * tan_x * f, y_ndc * tan_y * f, jnp.broadcast_to(f, x_ndc.shape)], -1
        )
        lens = self.aperture_radius.astype(dtype) * sample_uniform_disk_concentric(
            uv.astype(dtype), check=False
        )
        lens = jnp.concatenate([lens, jnp.zeros_like(lens[..., :1])], axis=-1)
        lens, focus = jnp.broadcast_arrays(lens, focus)
        d = focus - lens
        d = d / jnp.linalg.norm(d, axis=-1, keepdims=True)
        o = lens + d * (self.near_clip.astype(dtype) / d[..., 2:3])
        o_w = _point_to_world(m, o)
        d_w = jnp.einsum("ij,...j->...i", m[:3, :3], d)
        return o_w, d_w / jnp.linalg.norm(d_w, axis=-1, keepdims=True)
