r"""Pinhole camera model and perspective projection (thesis section 2.3.1, eq. 2.28-2.30).

Coordinate spaces (thesis 2.3.1), as this module uses them:

- **object space**: where a shape is defined (meshes carry their own `to_world`);
- **world space**: the scene's common frame;
- **camera space**: origin at the pinhole, $+z$ along the viewing direction, $+y$ up on the
  image, and -- Mitsuba 3's convention, which the reference scenes use -- $+x$ towards the
  image's **left**. The camera's `to_world` matrix maps camera space to world space and equals
  `look_at(origin, target, up)`. (pbrt's camera space is left-handed, $+x$ to the right; the
  thesis's figure 2.5 draws that one. Both put $+z$ forward, so the projection matrix of
  eq. 2.30 is the same; only the last step, NDC to raster, flips $x$ here.)
- **rendering space**: camera-centred but with world-space axes (a translation of world space
  by `-origin`); ray tracers may use it for floating-point precision. Rays from
  `generate_ray` are in world space; subtract the camera origin for rendering space.
- **image space** (normalised device coordinates, NDC): the view frustum mapped onto
  $[-1, 1]^3$ by eq. 2.30 and the perspective divide; $x_\mathrm{ndc}$ follows camera $+x$,
  $y_\mathrm{ndc}$ camera $+y$, $z_\mathrm{ndc} = -1$ on the near and $+1$ on the far plane;
- **raster space**: continuous pixel coordinates, $(0, 0)$ at the image's top-left corner,
  $x$ to the right, $y$ down, pixel $(i, j)$ covering $[i, i+1) \times [j, j+1)$ with its
  centre at $(i + 0.5, j + 0.5)$; $(W, H)$ is the bottom-right corner. With Mitsuba's camera
  space, $x_\mathrm{raster} = W (1 - x_\mathrm{ndc}) / 2$ and
  $y_\mathrm{raster} = H (1 - y_\mathrm{ndc}) / 2$.
"""

import functools
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import as_float_array, check_choice, check_last_axis, check_positive_int
from .._types import Array, ArrayLike, Float
from ._base import AbstractCamera, CameraWiSample

FOV_AXES = ("x", "y", "diagonal", "smaller", "larger")


def _is_concrete(x) -> bool:
    return not isinstance(x, jax.core.Tracer)


def _check_fov(fov_deg: Array, name: str = "fov_deg") -> Array:
    """0 < fov < 180 degrees: a `ValueError` for concrete input, `eqx.error_if` under `jit`."""
    if _is_concrete(fov_deg):
        v = np.asarray(fov_deg)
        if v.ndim != 0:
            raise ValueError(f"`{name}` must be a scalar [deg], got shape {v.shape}.")
        if not (0.0 < float(v) < 180.0):
            raise ValueError(
                f"`{name}` must lie in the open interval (0, 180) [deg], got {float(v)}."
            )
        return fov_deg
    return eqx.error_if(
        fov_deg, (fov_deg <= 0.0) | (fov_deg >= 180.0), f"`{name}` must lie in (0, 180) [deg]."
    )


def _check_matrix4(m, name: str) -> Array:
    m = as_float_array(m, name)
    if m.shape != (4, 4):
        raise ValueError(f"`{name}` must be a 4x4 matrix, got shape {m.shape}.")
    return m


def _check_clip(near, far) -> tuple[Array, Array]:
    near = as_float_array(near, "near")
    far = as_float_array(far, "far")
    if _is_concrete(near) and _is_concrete(far):
        n, f = np.asarray(near), np.asarray(far)
        if np.any(n <= 0) or np.any(f <= n):
            raise ValueError(
                f"Clip distances must satisfy 0 < near < far [scene units], got near={n}, far={f}."
            )
    return near, far


def _check_camera_fields(camera) -> None:
    """The checks every camera's `__check_init__` shares: film size, crop window and a 4x4
    `to_world`."""
    check_positive_int(camera.width, "width")
    check_positive_int(camera.height, "height")
    _check_crop(camera)
    if jnp.shape(camera.to_world) != (4, 4):
        raise ValueError(
            f"`to_world` must be a 4x4 matrix, got shape {jnp.shape(camera.to_world)}."
        )


def _check_film_and_matrix(to_world, width, height) -> tuple[Array, int, int]:
    """`from_to_world`'s first checks, shared by the cameras: `(matrix, width, height)`."""
    width = check_positive_int(width, "width")
    height = check_positive_int(height, "height")
    return _check_matrix4(to_world, "to_world"), width, height


def _check_crop(camera) -> None:
    """A camera's `crop` window `(offset_x, offset_y, full_width, full_height)` [px] must hold
    its `width` x `height` image inside the full film."""
    if camera.crop is None:
        return
    if len(camera.crop) != 4 or not all(isinstance(v, int) for v in camera.crop):
        raise ValueError(
            f"`crop` must be 4 ints (offset_x, offset_y, full_width, full_height) [px], got "
            f"{camera.crop!r}."
        )
    ox, oy, fw, fh = camera.crop
    if ox < 0 or oy < 0 or ox + camera.width > fw or oy + camera.height > fh:
        raise ValueError(
            f"crop window {camera.width} x {camera.height} at ({ox}, {oy}) [px] does not fit in "
            f"the {fw} x {fh} film: need offset >= 0 and offset + size <= film size."
        )


def _crop_field(crop_window, width: int, height: int) -> tuple[int, int, tuple | None]:
    """`(image width, image height, crop field)` of a camera built on a `width` x `height`
    film with Mitsuba's crop window `(offset_x, offset_y, crop_width, crop_height)` [px]
    (`None`: the whole film)."""
    if crop_window is None:
        return width, height, None
    if len(crop_window) != 4:
        raise ValueError(
            "`crop_window` must be (offset_x, offset_y, crop_width, crop_height) [px], got "
            f"{crop_window!r}."
        )
    ox = check_positive_int(crop_window[0] + 1, "crop_offset_x + 1") - 1
    oy = check_positive_int(crop_window[1] + 1, "crop_offset_y + 1") - 1
    cw = check_positive_int(crop_window[2], "crop_width")
    ch = check_positive_int(crop_window[3], "crop_height")
    return cw, ch, (int(ox), int(oy), width, height)


def _film_window(camera) -> tuple[int, int, int, int]:
    """`(offset_x, offset_y, full_width, full_height)` [px] of the camera's image in its film:
    the crop window, or the whole film."""
    return camera.crop if camera.crop is not None else (0, 0, camera.width, camera.height)


def _raster_to_ndc(xy: Array, camera, shift=None) -> tuple[Array, Array]:
    """Raster positions (..., 2) [px] of the camera's image to the full film's
    `(x_ndc, y_ndc)` (x flipped: camera +x is the image's left; y flipped: raster y is down).

    With a crop window (Mitsuba's `crop_offset_*`), raster $(0, 0)$ is the window's corner;
    `shift` is a principal point offset `(2,)` in fractions of the film, added to the film
    position $(x + o_x) / W$, as Mitsuba's `principal_point_offset_*`.
    """
    ox, oy, fw, fh = _film_window(camera)
    u, v = (xy[..., 0] + ox) / fw, (xy[..., 1] + oy) / fh
    if shift is not None:
        u, v = u + shift[0], v + shift[1]
    return 1.0 - 2.0 * u, 1.0 - 2.0 * v


def _point_to_world(m: Array, p: Array) -> Array:
    """Camera-space points (..., 3) to world space by the 4x4 `to_world` matrix `m`."""
    o = jnp.einsum("ij,...j->...i", m[:3, :3], p)
    return o + jnp.broadcast_to(m[:3, 3], o.shape)


def look_at(origin: ArrayLike, target: ArrayLike, up: ArrayLike) -> Float[Array, "4 4"]:
    r"""Camera-to-world matrix of a camera at `origin` looking at `target` (Mitsuba convention).

    The columns are $(\hat{l}, \hat{u}, \hat{d}, \vec{o})$ with
    $\hat{d} = (\vec{t} - \vec{o}) / \lVert\cdot\rVert$ (camera $+z$, forward),
    $\hat{l} = \widehat{\vec{up} \times \hat{d}}$ (camera $+x$, towards the image's left) and
    $\hat{u} = \hat{d} \times \hat{l}$ (camera $+y$, up). This is the `to_world` of a Mitsuba 3
    sensor; the Cornell box camera (origin $(0, 0, 3.9)$ looking at $-z$, up $+y$) gives
    `diag(-1, 1, -1)` plus the translation. pbrt's `LookAt` returns the inverse (world to
    camera) of a left-handed frame whose $+x$ is $-\hat{l}$.

    **Arguments:**

    - `origin`: camera position, shape (3,). [scene units]
    - `target`: a point the camera looks at, shape (3,), different from `origin`. [scene units]
    - `up`: a direction that appears up on the image, shape (3,), not parallel to the
        viewing direction. [dimensionless]

    **Returns:**

    The 4x4 homogeneous camera-to-world matrix (rigid: rotation plus translation).

    !!! note "Thesis"
        Thesis section 2.3.1 (camera space and world space).

    ??? cite "References"
        `Jakob2022` (`Transform4f.look_at`); `Pharr2023` §3.9.
    """
    o = check_last_axis(as_float_array(origin, "origin"), "origin", 3)
    t = check_last_axis(as_float_array(target, "target"), "target", 3)
    u = check_last_axis(as_float_array(up, "up"), "up", 3)
    for name, v in (("origin", o), ("target", t), ("up", u)):
        if v.shape != (3,):
            raise ValueError(f"`{name}` must have shape (3,), got {v.shape}.")
    concrete = not any(isinstance(v, jax.core.Tracer) for v in (o, t, u))
    if concrete:  # checked here, with a plain ValueError; traced values are checked at run time
        d = np.asarray(t, np.float64) - np.asarray(o, np.float64)
        if not np.linalg.norm(d) > 0.0:
            raise ValueError(_LOOK_AT_SAME)
        up = np.asarray(u, np.float64)
        if not np.linalg.norm(np.cross(up, d / np.linalg.norm(d))) > 1e-12 * np.linalg.norm(up):
            raise ValueError(_LOOK_AT_PARALLEL)
    return _look_at(o, t, u, checked=concrete)


_LOOK_AT_SAME = "`target` must differ from `origin` [scene units]."
_LOOK_AT_PARALLEL = "`up` must not be zero or parallel to the viewing direction `target - origin`."


@functools.partial(jax.jit, static_argnames="checked")
def _look_at(o: Array, t: Array, u: Array, checked: bool) -> Array:
    """`look_at` after its argument checks (`checked`: the values too), as one compiled program:
    called eagerly, as the scene loaders do, its dozen operations would each compile on a first
    run (0.2 s)."""
    dtype = jnp.result_type(o.dtype, t.dtype, u.dtype)
    o, t, u = o.astype(dtype), t.astype(dtype), u.astype(dtype)
    d = t - o
    d_norm = jnp.linalg.norm(d)
    if not checked:
        d_norm = eqx.error_if(d_norm, d_norm <= 0.0, _LOOK_AT_SAME)
    d = d / d_norm
    left = jnp.cross(u, d)
    l_norm = jnp.linalg.norm(left)
    if not checked:
        l_norm = eqx.error_if(l_norm, l_norm <= 1e-12 * jnp.linalg.norm(u), _LOOK_AT_PARALLEL)
    left = left / l_norm
    new_up = jnp.cross(d, left)
    m = jnp.stack([left, new_up, d, o], axis=1)
    bottom = jnp.asarray([[0.0, 0.0, 0.0, 1.0]], dtype=dtype)
    return jnp.concatenate([m, bottom], axis=0)


def perspective_frustum(
    left: ArrayLike,
    right: ArrayLike,
    bottom: ArrayLike,
    top: ArrayLike,
    near: ArrayLike,
    far: ArrayLike,
) -> Float[Array, "4 4"]:
    r"""Perspective projection of a general (possibly off-centre) view frustum, thesis eq. 2.30.

    $$P = \begin{bmatrix} \frac{2n}{r-l} & 0 & -\frac{r+l}{r-l} & 0 \\
    0 & \frac{2n}{t-b} & -\frac{t+b}{t-b} & 0 \\
    0 & 0 & \frac{f+n}{f-n} & -\frac{2fn}{f-n} \\ 0 & 0 & 1 & 0 \end{bmatrix}$$

    the product of the shear-and-scale of eq. 2.28 and the depth normalisation of eq. 2.29.
    After the perspective divide by $w = z$, the frustum with near-plane window
    $[l, r] \times [b, t]$ at $z = n$ and far plane $z = f$ maps onto $[-1, 1]^3$ (camera space,
    $+z$ forward; $z_\mathrm{ndc}$ is $-1$ at the near and $+1$ at the far plane).

    **Arguments:**

    - `left`, `right`: $x$ extent of the window on the near plane, `left < right`. [scene units]
    - `bottom`, `top`: $y$ extent of the window on the near plane, `bottom < top`. [scene units]
    - `near`, `far`: distances of the near and far planes, `0 < near < far`. [scene units]

    **Returns:**

    The 4x4 homogeneous projection matrix (camera space to clip space).

    !!! note "Thesis"
        Eq. 2.28-2.30, section 2.3.1.

    ??? cite "References"
        `Pharr2023` §5.2.1; `Ikeuchi2014` (camera models).
    """
    vals = [
        as_float_array(v, n)
        for v, n in zip((left, right, bottom, top), ("left", "right", "bottom", "top"), strict=True)
    ]
    n, f = _check_clip(near, far)
    l, r, b, t = vals  # noqa: E741  (the thesis names them l, r, b, t)
    if all(_is_concrete(v) for v in vals):
        if not (np.all(np.asarray(r) > np.asarray(l)) and np.all(np.asarray(t) > np.asarray(b))):
            raise ValueError(
                f"The frustum window must satisfy left < right and bottom < top [scene units], "
                f"got l={np.asarray(l)}, r={np.asarray(r)}, b={np.asarray(b)}, t={np.asarray(t)}."
            )
    dtype = jnp.result_type(*(v.dtype for v in (l, r, b, t, n, f)))
    l, r, b, t, n, f = (v.astype(dtype) for v in (l, r, b, t, n, f))  # noqa: E741
    zero = jnp.zeros((), dtype)
    one = jnp.ones((), dtype)
    rows = [
        [2 * n / (r - l), zero, -(r + l) / (r - l), zero],
        [zero, 2 * n / (t - b), -(t + b) / (t - b), zero],
        [zero, zero, (f + n) / (f - n), -2 * f * n / (f - n)],
        [zero, zero, one, zero],
    ]
    return jnp.stack([jnp.stack(row) for row in rows])


def fov_x_deg(fov_deg: ArrayLike, aspect: float, fov_axis: str = "x") -> Float[Array, ""]:
    r"""Horizontal field of view equivalent to `fov_deg` measured along `fov_axis` (Mitsuba rule).

    With $a$ = width / height and $T = \tan(\mathrm{fov}/2)$:
    `"x"`: the value is the horizontal fov; `"y"`: $\tan(\mathrm{fov}_x/2) = a T$;
    `"diagonal"`: $\tan(\mathrm{fov}_x/2) = T / \sqrt{1 + 1/a^2}$; `"smaller"`: the fov of the
    shorter side (`"y"` when $a > 1$, else `"x"`); `"larger"`: the fov of the longer side.

    **Arguments:**

    - `fov_deg`: field of view along `fov_axis`, in (0, 180). [deg]
    - `aspect`: image width / height, > 0. [dimensionless]
    - `fov_axis`: one of `"x"`, `"y"`, `"diagonal"`, `"smaller"`, `"larger"`.

    **Returns:**

    The horizontal field of view. [deg]

    !!! note "Thesis"
        Thesis section 2.3.1 (film plane and field of view).

    ??? cite "References"
        `Jakob2022` (perspective sensor, `fov_axis`).
    """
    check_choice(fov_axis, "fov_axis", FOV_AXES)
    aspect = float(aspect)
    if not aspect > 0.0 or not math.isfinite(aspect):
        raise ValueError(f"`aspect` must be a finite value > 0 [dimensionless], got {aspect}.")
    fov = _check_fov(as_float_array(fov_deg, "fov_deg"))
    if fov_axis == "smaller":
        fov_axis = "y" if aspect > 1.0 else "x"
    elif fov_axis == "larger":
        fov_axis = "x" if aspect > 1.0 else "y"
    if fov_axis == "x":
        return fov
    tan_half = jnp.tan(jnp.deg2rad(fov) / 2)
    if fov_axis == "y":
        tan_x = tan_half * aspect
    else:  # diagonal
        tan_x = tan_half / math.sqrt(1.0 + 1.0 / aspect**2)
    return jnp.rad2deg(2 * jnp.arctan(tan_x))


def fov_from_focal_length_deg(focal_length_mm: float) -> float:
    r"""Diagonal field of view of a lens of focal length $f$ on 35 mm film (36 x 24 mm), the
    convention of Mitsuba's `focal_length` parameter (its fov axis is then `"diagonal"`):
    $2 \arctan(\sqrt{36^2 + 24^2} / 2f)$.

    **Arguments:**

    - `focal_length_mm`: the focal length, finite and > 0. [mm]

    **Returns:**

    The diagonal field of view, in (0, 180). [deg]

    !!! note "Thesis"
        Thesis section 2.3.1 (film plane and field of view).

    ??? cite "References"
        `Jakob2022` (perspective sensor, `focal_length`).
    """
    f = float(focal_length_mm)
    if not (math.isfinite(f) and f > 0.0):
        raise ValueError(
            f"`focal_length_mm` must be a finite value > 0 [mm], got {focal_length_mm}."
        )
    return math.degrees(2.0 * math.atan(math.hypot(36.0, 24.0) / (2.0 * f)))


def perspective(
    fov_deg: ArrayLike, aspect: float, near: ArrayLike, far: ArrayLike, *, fov_axis: str = "x"
) -> Float[Array, "4 4"]:
    r"""Symmetric perspective projection matrix (thesis eq. 2.30 with $l = -r$, $b = -t$).

    $r = n \tan(\mathrm{fov}_x/2)$ and $t = r / a$ with $a$ = width / height, so the whole
    image maps onto $x_\mathrm{ndc}, y_\mathrm{ndc} \in [-1, 1]$ and depths $[n, f]$ onto
    $z_\mathrm{ndc} \in [-1, 1]$ after the perspective divide.

    **Arguments:**

    - `fov_deg`: field of view along `fov_axis`, in (0, 180). [deg]
    - `aspect`: image width / height, > 0. [dimensionless]
    - `near`, `far`: clip distances, `0 < near < far`. [scene units]
    - `fov_axis`: which extent `fov_deg` measures: `"x"` (default, as Mitsuba's
        `Transform4f.perspective`), `"y"` (OpenGL's `gluPerspective`), `"diagonal"`,
        `"smaller"` or `"larger"` (see `fov_x_deg`).

    **Returns:**

    The 4x4 projection matrix (camera space to clip space).

    !!! note "Thesis"
        Eq. 2.28-2.30, section 2.3.1.

    ??? cite "References"
        `Pharr2023` §5.2.1; `Jakob2022`.
    """
    fx = fov_x_deg(fov_deg, aspect, fov_axis)
    n, f = _check_clip(near, far)
    dtype = jnp.result_type(fx.dtype, n.dtype, f.dtype)
    n, f = n.astype(dtype), f.astype(dtype)
    r = n * jnp.tan(jnp.deg2rad(fx.astype(dtype)) / 2)
    t = r / float(aspect)
    return perspective_frustum(-r, r, -t, t, n, f)


class PinholeCamera(AbstractCamera):
    r"""Ideal pinhole camera (thesis section 2.3.1) in Mitsuba 3's conventions.

    Build it with `PinholeCamera.from_look_at(...)` or `PinholeCamera.from_to_world(...)`.
    Camera space has $+z$ forward, $+y$ up and $+x$ towards the image's left (module
    docstring); `to_world` maps camera to world space. Raster coordinates are continuous with
    $(0, 0)$ the top-left image corner and pixel centres at half-integers.

    **Fields:**

    - `to_world`: camera-to-world matrix, (4, 4). [scene units]
    - `fov_x_deg`: horizontal field of view (whatever `fov_axis` the constructor got). [deg]
    - `width`, `height`: size of the rendered image in pixels (static). [px]
    - `near_clip`, `far_clip`: clip distances used by `projection_matrix`. [scene units]
    - `principal_point`: `(2,)` offset of the image centre from the optical axis, in
        fractions of the film's width and height (Mitsuba's `principal_point_offset_x/y`:
        raster $x$ of the full film sees the ray that $x + W p_x$ sees without it). [-]
    - `crop`: `None`, or `(offset_x, offset_y, full_width, full_height)` (static): the image
        is the `width` x `height` window at that offset of a `full_width` x `full_height`
        film whose field of view is `fov_x_deg` (Mitsuba's film crop window). [px]

    !!! note "Thesis"
        Thesis section 2.3.1, eq. 2.28-2.30.

    ??? cite "References"
        `Pharr2023` §5.1-5.2; `Jakob2022` (perspective sensor).
    """

    to_world: Float[Array, "4 4"]
    fov_x_deg: Float[Array, ""]
    width: int = eqx.field(static=True)
    height: int = eqx.field(static=True)
    near_clip: Float[Array, ""] = eqx.field(default=1e-2, converter=jnp.asarray)
    far_clip: Float[Array, ""] = eqx.field(default=1e4, converter=jnp.asarray)
    principal_point: Float[Array, "2"] = eqx.field(default=(0.0, 0.0), converter=jnp.asarray)
    crop: tuple[int, int, int, int] | None = eqx.field(default=None, static=True)

    def __check_init__(self):
        _check_camera_fields(self)
        if jnp.shape(self.fov_x_deg) != ():
            raise ValueError(
                f"`fov_x_deg` must be a scalar [deg], got shape {jnp.shape(self.fov_x_deg)}."
            )
        if jnp.shape(self.principal_point) != (2,):
            raise ValueError(
                "`principal_point` must have shape (2,) [fractions of the film], got "
                f"{jnp.shape(self.principal_point)}."
            )

    @classmethod
    def from_to_world(
        cls,
        to_world: ArrayLike,
        fov_deg: ArrayLike,
        width: int,
        height: int,
        fov_axis: str = "smaller",
        *,
        near_clip: float = 1e-2,
        far_clip: float = 1e4,
        principal_point=(0.0, 0.0),
        crop_window=None,
    ) -> "PinholeCamera":
        """A camera from its camera-to-world matrix and field of view.

        **Arguments:**

        - `to_world`: camera-to-world matrix (4, 4), e.g. a Mitsuba sensor's `to_world`.
            [scene units]
        - `fov_deg`: field of view along `fov_axis`, in (0, 180). [deg]
        - `width`, `height`: film size, integers >= 1. [px]
        - `fov_axis`: `"x"`, `"y"`, `"diagonal"`, `"smaller"` (default; pbrt's rule) or
            `"larger"`. Mitsuba's own default is `"x"`.
        - `near_clip`, `far_clip`: clip distances, `0 < near < far`. [scene units]
        - `principal_point`: `(2,)` principal point offset in fractions of the film
            (Mitsuba's `principal_point_offset_x/y`). [-]
        - `crop_window`: `None` (the whole film) or `(offset_x, offset_y, crop_width,
            crop_height)`, Mitsuba's film crop: the camera renders that window of the
            `width` x `height` film. [px]

        **Returns:**

        A `PinholeCamera`.

        !!! note "Thesis"
            Thesis section 2.3.1.

        ??? cite "References"
            `Jakob2022` (perspective sensor).
        """
        m, width, height = _check_film_and_matrix(to_world, width, height)
        fx = fov_x_deg(fov_deg, width / height, fov_axis)
        near, far = _check_clip(near_clip, far_clip)
        w, h, crop = _crop_field(crop_window, width, height)
        return cls(m, fx, w, h, near, far, principal_point=principal_point, crop=crop)

    @classmethod
    def from_look_at(
        cls,
        origin: ArrayLike,
        target: ArrayLike,
        up: ArrayLike,
        fov_deg: ArrayLike,
        width: int,
        height: int,
        fov_axis: str = "smaller",
        *,
        near_clip: float = 1e-2,
        far_clip: float = 1e4,
    ) -> "PinholeCamera":
        """A camera at `origin` looking at `target` with `up` up on the image.

        **Arguments:**

        - `origin`, `target`: camera position and a point it looks at, (3,). [scene units]
        - `up`: up direction, (3,), not parallel to `target - origin`. [dimensionless]
        - `fov_deg`, `width`, `height`, `fov_axis`, `near_clip`, `far_clip`: as in
            `from_to_world`. [deg], [px], [scene units]

        **Returns:**

        A `PinholeCamera` with `to_world = look_at(origin, target, up)`.

        !!! note "Thesis"
            Thesis section 2.3.1.

        ??? cite "References"
            `Jakob2022`; `Pharr2023` §3.9.
        """
        return cls.from_to_world(
            look_at(origin, target, up),
            fov_deg,
            width,
            height,
            fov_axis,
            near_clip=near_clip,
            far_clip=far_clip,
        )

    @property
    def aspect(self) -> float:
        """Aspect ratio width / height of the full film (the crop window's film). [-]"""
        _, _, fw, fh = _film_window(self)
        return fw / fh

    def tan_half_fov(self) -> tuple[Array, Array]:
        """`(tan(fov_x / 2), tan(fov_y / 2))`: the image's half-extents at unit depth. [-]"""
        tan_x = jnp.tan(jnp.deg2rad(self.fov_x_deg) / 2)
        return tan_x, tan_x / self.aspect

    def projection_matrix(self) -> Float[Array, "4 4"]:
        """Camera space to clip space, thesis eq. 2.30 for this camera's frustum. [dimensionless]"""
        return perspective(self.fov_x_deg, self.aspect, self.near_clip, self.far_clip, fov_axis="x")

    def raster_from_ndc(self) -> Float[Array, "4 4"]:
        """Affine map NDC to raster (x flipped: camera +x is the image's left; y down), less
        the principal point offset and the crop window's offset. [px]"""
        ox, oy, fw, fh = (float(v) for v in _film_window(self))
        dtype = np.promote_types(self.to_world.dtype, self.fov_x_deg.dtype)
        tx, ty = jnp.asarray([fw / 2 - ox, fh / 2 - oy], dtype) - jnp.asarray(
            [fw, fh], dtype
        ) * self.principal_point.astype(dtype)
        zero, one = jnp.zeros((), dtype), jnp.ones((), dtype)
        return jnp.stack(
            [
                jnp.stack([jnp.asarray(-fw / 2, dtype), zero, zero, tx]),
                jnp.stack([zero, jnp.asarray(-fh / 2, dtype), zero, ty]),
                jnp.stack([zero, zero, one, zero]),
                jnp.stack([zero, zero, zero, one]),
            ]
        )

    def generate_ray(
        self, raster_xy: ArrayLike
    ) -> tuple[Float[Array, "*batch 3"], Float[Array, "*batch 3"]]:
        """Method form of `radiometria.camera.generate_ray` (same arguments and result). [px]

        !!! note "Thesis"
            Thesis section 2.3.1.
        """
        return generate_ray(self, raster_xy)

    def project(self, points_world: ArrayLike) -> Float[Array, "*batch 2"]:
        """Method form of `radiometria.camera.project` (same arguments and result). [scene units]

        !!! note "Thesis"
            Eq. 2.30.
        """
        return project(self, points_world)

    def importance(self, cos_theta: ArrayLike) -> Array:
        r"""The importance $W_e = 1 / (A \cos^4\theta)$ of a ray leaving the pinhole at angle
        $\theta$ to the optical axis, inside the field of view (pbrt's `PerspectiveCamera::We`
        with a pinhole: lens area 1), where $A = 4 \tan\frac{\mathrm{fov}_x}{2}
        \tan\frac{\mathrm{fov}_y}{2}$ is the film's area at unit distance (times the crop
        window's share of the film). Its integral
        $\int W_e \cos\theta\, d\omega$ over the film's solid angle is 1, so a film position
        drawn uniformly (what `generate_ray` with uniform raster positions does) has the density
        $W_e \cos\theta$ per unit solid angle. [sr^-1]

        !!! note "Thesis"
            Section 2.3.1 (the camera as a measurement).

        ??? cite "References"
            `Pharr2023` §5.2.4 (importance of a perspective camera); `Veach1997` §10.2.
        """
        cos_theta = jnp.asarray(cos_theta)
        tan_x, tan_y = self.tan_half_fov()
        _, _, fw, fh = _film_window(self)
        window = self.width * self.height / (fw * fh)  # the crop window's share of the film
        area = (4.0 * tan_x * tan_y * window).astype(cos_theta.dtype)
        c2 = cos_theta * cos_theta
        ok = cos_theta > 0
        return jnp.where(ok, 1.0 / (area * jnp.where(ok, c2 * c2, 1.0)), 0.0)

    def sample_wi(self, p: ArrayLike) -> CameraWiSample:
        r"""Connect scene points to the pinhole (light tracing; pbrt's
        `PerspectiveCamera::SampleWi` with a pinhole).

        **Arguments:**

        - `p`: scene points `(n, 3)`. [scene units]

        **Returns:**

        A `CameraWiSample`: the unit direction `wi` and distance to the pinhole, the importance
        `importance(cos_theta)` [sr^-1] of the ray through `p`, the density $d^2/\cos\theta$
        of the (fixed) pinhole per unit solid angle at `p` [sr^-1], the raster position of
        `p` (`project`) [px], and `valid` where `p` lies in front of the camera and its image
        on the film $[0, W) \times [0, H)$.

        !!! note "Thesis"
            Section 2.3.1.

        ??? cite "References"
            `Pharr2023` §5.2.4; `Veach1997` §10.2.
        """
        p = jnp.asarray(p)
        dtype = p.dtype
        eye = jnp.broadcast_to(self.to_world[:3, 3].astype(dtype), p.shape)
        forward = self.to_world[:3, 2].astype(dtype)
        forward = jnp.broadcast_to(forward / jnp.sqrt(jnp.sum(forward * forward)), p.shape)
        to_eye = eye - p
        dist = jnp.sqrt(jnp.sum(to_eye * to_eye, axis=-1))
        ok = dist > 0
        wi = to_eye / jnp.where(ok, dist, 1.0)[..., None]
        cos_theta = -jnp.sum(wi * forward, axis=-1)
        raster = project(self, p)
        x, y = raster[..., 0], raster[..., 1]
        on_film = (x >= 0) & (x < self.width) & (y >= 0) & (y < self.height)  # False for NaN
        valid = ok & (cos_theta > 0) & on_film
        raster = jnp.where(valid[..., None], raster, 0.0)
        cos_safe = jnp.where(valid, cos_theta, 1.0)
        return CameraWiSample(
            wi=wi,
            dist=dist,
            importance=jnp.where(valid, self.importance(cos_safe), 0.0),
            pdf=jnp.where(valid, dist * dist / cos_safe, 0.0),
            raster=raster,
            valid=valid,
        )


def generate_ray(
    camera: PinholeCamera, raster_xy: ArrayLike
) -> tuple[Float[Array, "*batch 3"], Float[Array, "*batch 3"]]:
    r"""World-space primary rays through continuous raster positions (inverse of `project`).

    The raster point maps to NDC by $x_\mathrm{ndc} = 1 - 2x/W$, $y_\mathrm{ndc} = 1 - 2y/H$,
    then to the camera-space direction
    $(x_\mathrm{ndc} \tan\frac{\mathrm{fov}_x}{2}, y_\mathrm{ndc} \tan\frac{\mathrm{fov}_y}{2}, 1)$,
    normalised and rotated by `to_world`. The same rays as Mitsuba 3's `perspective` sensor
    `sample_ray(time, wavelength_sample, raster_xy / (W, H), aperture_sample)`.
    Positions outside the image are allowed (filter footprints extend past the border).

    **Arguments:**

    - `camera`: a `PinholeCamera`.
    - `raster_xy`: raster positions (..., 2): $(0, 0)$ is the image's top-left corner and
        pixel $(i, j)$ has its centre at $(i + 0.5, j + 0.5)$. [px]

    **Returns:**

    `(origin, direction)`, each (..., 3): the pinhole position (broadcast) and unit
    directions, in world space and in the dtype of `raster_xy`. [scene units], [dimensionless]

    !!! note "Thesis"
        Thesis section 2.3.1 (inverse of eq. 2.30 followed by the raster transform).

    ??? cite "References"
        `Pharr2023` §5.2.2; `Jakob2022`.
    """
    xy = check_last_axis(as_float_array(raster_xy, "raster_xy"), "raster_xy", 2)
    dtype = xy.dtype
    to_world = camera.to_world.astype(dtype)
    tan_x, tan_y = camera.tan_half_fov()
    tan_x, tan_y = tan_x.astype(dtype), tan_y.astype(dtype)
    x_ndc, y_ndc = _raster_to_ndc(xy, camera, camera.principal_point.astype(dtype))
    d_cam = jnp.stack([x_ndc * tan_x, y_ndc * tan_y, jnp.ones_like(x_ndc)], axis=-1)
    d = jnp.einsum("ij,...j->...i", to_world[:3, :3], d_cam)
    d = d / jnp.linalg.norm(d, axis=-1, keepdims=True)
    o = jnp.broadcast_to(to_world[:3, 3], d.shape)
    return o, d


def project(camera: PinholeCamera, points_world: ArrayLike) -> Float[Array, "*batch 2"]:
    r"""Raster positions of world-space points (thesis eq. 2.30, perspective divide, raster map).

    $\vec{p}_\mathrm{cam} = M_\mathrm{to\,world}^{-1} \vec{p}$, then the clip-space point
    $P \vec{p}_\mathrm{cam}$ of eq. 2.30, the perspective divide by $w = z_\mathrm{cam}$, and
    $x = W (1 - x_\mathrm{ndc}) / 2$, $y = H (1 - y_\mathrm{ndc}) / 2$. `generate_ray` inverts it.

    **Arguments:**

    - `camera`: a `PinholeCamera`.
    - `points_world`: points (..., 3). [scene units]

    **Returns:**

    Continuous raster positions (..., 2) [px]; NaN for points with $z_\mathrm{cam} \le 0$
    (at or behind the pinhole), which have no image. Points outside the field of view give
    positions outside $[0, W] \times [0, H]$.

    !!! note "Thesis"
        Eq. 2.28-2.30, section 2.3.1.

    ??? cite "References"
        `Pharr2023` §5.2.1.
    """
    p = check_last_axis(as_float_array(points_world, "points_world"), "points_world", 3)
    dtype = p.dtype
    world_to_camera = jnp.linalg.inv(camera.to_world.astype(dtype))
    m = (
        camera.raster_from_ndc().astype(dtype)
        @ camera.projection_matrix().astype(dtype)
        @ world_to_camera
    )
    ph = jnp.concatenate([p, jnp.ones_like(p[..., :1])], axis=-1)
    clip = jnp.einsum("ij,...j->...i", m, ph)
    w = clip[..., 3]
    front = w > 0
    w_safe = jnp.where(front, w, 1.0)  # double where: no inf/NaN in the gradient
    xy = clip[..., :2] / w_safe[..., None]
    return jnp.where(front[..., None], xy, jnp.nan)
