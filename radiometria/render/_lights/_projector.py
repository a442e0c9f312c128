r"""Projectors (Mitsuba's `projector` emitter): a pinhole that projects an image into the scene.

A projector is the reciprocal of the perspective camera: a point at the origin of its
`to_world` frame looking along the frame's $+z$ axis, with the camera's pixel-to-direction
mapping. Its `irradiance` (a spectrum or a texture over the image) is the irradiance it
casts, divided by $\pi$, on its virtual image plane at $z = 1$, and `scale` multiplies it
(Mitsuba 3's definition). A direction $\ell = (x, y, z)$ in the projector's frame ($z > 0$)
meets that plane at

$$u = \tfrac12 - \frac{x}{2 z \tan(\phi_x/2)}, \qquad
  v = \tfrac12 - \frac{a\, y}{2 z \tan(\phi_x/2)}$$

(Mitsuba's `perspective_projection`: $\phi_x$ the horizontal field of view, $a$ the image's
width / height), and the radiant intensity along it is

$$I(\ell) = \frac{\pi\, s\, E(u, v)}{\cos^3\theta}, \qquad \cos\theta = \hat\ell_z,$$

so that the irradiance on the plane $z = 1$, $I \cos\theta / r^2 = I\cos^3\theta$, is exactly
$\pi s E$: a constant image projected onto any plane facing the projector squarely is
constant, $\pi s E / h^2$ at distance $h$. Outside the image the projector is dark. Its power
is $\Phi = \pi s \bar E A$ with $A = 4 \tan^2(\phi_x/2) / a$ the image's area at $z = 1$.

Light paths (`sample_le`) start with a point uniform on the image ($u, v$ uniform), whose
direction has density $1 / (A \cos^3\theta)$ per unit solid angle, so their throughput is
$\pi s E A$ (Mitsuba samples texels by their value; uniform is unbiased as well).

!!! note "Thesis"
    Chapter 8 (light sources); eq. 1.10-1.12 (intensity and irradiance).

??? cite "References"
    `Jakob2022` (Mitsuba 3's `projector` emitter and `perspective_projection`); `Pharr2023`
    §12.1.3 (goniophotometric and projection lights).
"""

import math
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..._checks import device_array
from ..._math import dot
from ...camera import fov_from_focal_length_deg, fov_x_deg
from .._textures import AbstractTexture, TextureSpec
from ._area import AreaLight, _mean_radiance
from ._base import EmissionSample, LightSample
from ._common import AbstractDeltaLight, direction_to_points, pick_row, row_cdf, to_world_param

__all__ = ["ProjectorLight"]

_FOV_AXES = ("x", "y", "diagonal", "smaller", "larger")


def _resolution(value) -> tuple[int, int]:
    """(width, height) of an irradiance value: a bitmap's texels, else 1 x 1 (Mitsuba's
    `Texture::resolution`)."""
    if isinstance(value, TextureSpec) and value.type == "bitmap":
        h, w = np.asarray(value.rgb).shape[:2]
        return int(w), int(h)
    return 1, 1


def _fov_x(params: dict, aspect: float, where: str) -> float:
    """The horizontal field of view [deg] from `fov` and `fov_axis`, or from `focal_length`
    (35 mm equivalent, on the diagonal; default 50mm), as Mitsuba's `parse_fov`."""
    if "fov" in params and "focal_length" in params:
        raise ValueError(f"{where}: give 'fov' or 'focal_length', not both.")
    axis = params.get("fov_axis", "x")
    if axis not in _FOV_AXES:
        raise ValueError(f"{where}: parameter 'fov_axis' must be one of {list(_FOV_AXES)}, "
                         f"got {axis!r}.")  # fmt: skip
    if "fov" in params:
        fov = params["fov"]
        if not isinstance(fov, int | float) or not 0 < fov < 180:
            raise ValueError(f"{where}: parameter 'fov' must be in (0, 180) [deg], got {fov!r}.")
    else:
        text = str(params.get("focal_length", "50mm")).strip().removesuffix("mm")
        try:
            f_mm = float(text)
        except ValueError:
            f_mm = float("nan")
        if not (math.isfinite(f_mm) and f_mm > 0):
            raise ValueError(f"{where}: parameter 'focal_length' must be a length > 0 in mm "
                             f"(e.g. '50mm'), got {params['focal_length']!r}.")  # fmt: skip
        fov, axis = fov_from_focal_length_deg(f_mm), "diagonal"
    return float(fov_x_deg(fov, aspect, axis))


class ProjectorLight(AbstractDeltaLight):
    r"""Projectors: every `projector` emitter of a scene, one row each (module docstring).

    **Fields:**

    - `position`: `(m, 3)` pinholes. [scene units]
    - `to_world`, `world_to_local`: `(m, 3, 3)` rotations of each frame and their inverses.
    - `tan_half_fov`: `(m,)` $\tan(\phi_x / 2)$; `aspect`: `(m,)` image width / height.
    - `scale`: `(m,)` Mitsuba's `scale`.
    - `irradiance`: texture of $E$, one row per projector (a spectrum: D65-shaped for RGB,
        as Mitsuba's `texture_d65`; a bitmap or checkerboard: its texels' albedo spectra,
        without D65, as Mitsuba 3.9 evaluates a textured emitter). [W m^-2 nm^-1 / pi]
    - `cdf`: `(m,)` cumulative probabilities of picking each projector (by power); `phi`:
        the summed power (static). [W nm^-1]

    !!! note "Thesis"
        Chapter 8 (light sources).

    ??? cite "References"
        `Jakob2022` (Mitsuba 3's `projector`); `Pharr2023` §12.1.3.
    """

    NAME: ClassVar[str] = "projector"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"irradiance", "scale", "to_world", "fov", "fov_axis", "focal_length"}
    )
    position: Float[Array, "m 3"]
    to_world: Float[Array, "m 3 3"]
    world_to_local: Float[Array, "m 3 3"]
    tan_half_fov: Float[Array, " m"]
    aspect: Float[Array, " m"]
    scale: Float[Array, " m"]
    irradiance: AbstractTexture
    cdf: Float[Array, " m"]
    phi: float = eqx.field(static=True)

    @classmethod
    def from_properties(
        cls, params: list[dict], *, where: list[str], dtype=jnp.float32
    ) -> "ProjectorLight":
        """Projectors from scene parameters (Mitsuba's names and defaults): `irradiance` (a
        spectrum, or a `bitmap` / `checkerboard` `TextureSpec`; default 1)
        [W m^-2 nm^-1 / pi], `scale` (default 1, >= 0), `to_world` (position and frame: a
        rotation and a translation), and `fov` [deg] with `fov_axis`, or `focal_length`
        (default `"50mm"`). Bad values raise `ValueError` naming `where`."""
        pos, rot, tans, aspects, scales, values = [], [], [], [], [], []
        for p, w in zip(params, where, strict=True):
            m = to_world_param(p, w)
            r = m[:3, :3]
            if not np.allclose(r.T @ r, np.eye(3), atol=1e-6) or np.linalg.det(r) <= 0:
                raise ValueError(
                    f"{w}: a projector's to_world must be a rotation and a translation (no "
                    "scale, shear or mirror), as a camera's frame."
                )
            value = p.get("irradiance", 1.0)
            if isinstance(value, TextureSpec) and value.type not in ("bitmap", "checkerboard"):
                raise ValueError(f"{w}: parameter 'irradiance': unsupported texture type "
                                 f"{value.type!r}.")  # fmt: skip
            width, height = _resolution(value)
            aspect = width / height
            s = p.get("scale", 1.0)
            if not isinstance(s, int | float) or not (math.isfinite(s) and s >= 0):
                raise ValueError(f"{w}: parameter 'scale' must be a finite number >= 0, got "
                                 f"{s!r}.")  # fmt: skip
            pos.append(m[:3, 3])
            rot.append(r)
            tans.append(math.tan(math.radians(_fov_x(p, aspect, w)) / 2))
            aspects.append(aspect)
            scales.append(float(s))
            values.append(value)
        irradiance = AreaLight.radiance_texture(values, dtype, where=where[0])
        area = 4.0 * np.square(tans) / np.asarray(aspects)
        powers = np.pi * np.asarray(scales) * area * _mean_radiance(irradiance)
        return cls(
            position=device_array(np.stack(pos), dtype),
            to_world=device_array(np.stack(rot), dtype),
            world_to_local=device_array(np.stack([r.T for r in rot]), dtype),
            tan_half_fov=device_array(tans, dtype),
            aspect=device_array(aspects, dtype),
            scale=device_array(scales, dtype),
            irradiance=irradiance,
            cdf=device_array(row_cdf(powers), dtype),
            phi=float(powers.sum()),
        )

    def _intensity(self, j, w, wavelength_nm):
        """Radiant intensity of projectors `j` (n,) along the world directions `w` (n, 3)
        from their pinholes (0 outside the image), and the image density factor
        $1 / \\cos^3\\theta$ (n,). [W sr^-1 nm^-1]"""
        local = jnp.einsum("nij,nj->ni", self.world_to_local[j], w)
        norm = jnp.sqrt(jnp.maximum(dot(local, local), jnp.finfo(w.dtype).tiny))
        cos = local[:, 2] / norm
        front = cos > 0
        z = jnp.where(front, local[:, 2], 1.0)
        t = self.tan_half_fov[j].astype(w.dtype)
        u = 0.5 - 0.5 * local[:, 0] / (z * t)
        v = 0.5 - 0.5 * self.aspect[j].astype(w.dtype) * local[:, 1] / (z * t)
        inside = front & (u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)
        inv_cos3 = jnp.where(inside, 1.0 / jnp.where(front, cos, 1.0) ** 3, 0.0)
        uv = jnp.stack([jnp.clip(u, 0.0, 1.0), jnp.clip(v, 0.0, 1.0)], axis=-1)
        e = self.irradiance(j, wavelength_nm, uv.astype(wavelength_nm.dtype))
        scale = (jnp.pi * self.scale[j].astype(w.dtype) * inv_cos3)[:, None]
        return e * scale, inv_cos3

    def _image_area(self, j, dtype):
        t = self.tan_half_fov[j].astype(dtype)
        return 4.0 * t * t / self.aspect[j].astype(dtype)

    def sample_li(self, p, u_select, u2, wavelength_nm) -> LightSample:
        j, prob, _ = pick_row(self.cdf, u_select)
        wi, dist, dist2, ok = direction_to_points(self.position[j].astype(p.dtype), p)
        intensity, inv_cos3 = self._intensity(j, -wi, wavelength_nm)
        ok = ok & (inv_cos3 > 0)
        return LightSample(
            wi=wi,
            dist=dist,
            radiance=intensity / jnp.where(ok, dist2, 1.0)[:, None],
            pdf=jnp.where(ok, prob, 0.0),
            delta=jnp.ones(dist.shape, bool),
        )

    def power(self, scene_radius: float) -> float:
        return self.phi

    def sample_le(self, u_select, u_pos, u_dir, u_side, observer, wavelength_nm):
        """An emitted ray: a projector by power, a point uniform on its image (`u_dir`) and
        the direction through it (density $1 / (A \\cos^3\\theta)$); the throughput is
        $\\pi s E A$."""
        j, prob, _ = pick_row(self.cdf, u_select)
        dtype = observer.dtype
        t = self.tan_half_fov[j].astype(dtype)
        uv = u_dir.astype(dtype)
        x = (0.5 - uv[:, 0]) * 2.0 * t
        y = (0.5 - uv[:, 1]) * 2.0 * t / self.aspect[j].astype(dtype)
        local = jnp.stack([x, y, jnp.ones_like(x)], axis=-1)
        d = jnp.einsum("nij,nj->ni", self.to_world[j].astype(dtype), local)
        d = d / jnp.sqrt(dot(d, d))[:, None]
        area = self._image_area(j, dtype)
        le, inv_cos3 = self._intensity(j, d, wavelength_nm)
        p = self.position[j].astype(dtype)
        to_observer = direction_to_points(observer, p)[0]
        le_obs, inv_cos3_obs = self._intensity(j, to_observer, wavelength_nm)
        return EmissionSample(
            p=p,
            n=jnp.zeros_like(d),
            d=d,
            le=le,
            pdf_pos=prob,
            pdf_dir=inv_cos3 / area,
            le_observer=le_obs,
            delta_pos=jnp.ones(prob.shape, bool),
            pdf_dir_observer=inv_cos3_obs / area,
        )
