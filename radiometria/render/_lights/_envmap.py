r"""Environment maps (Mitsuba's `envmap` emitter): radiance at infinity from an
equirectangular image, importance sampled by luminance.

The image's convention is Mitsuba 3's exactly. A direction $d$ in the emitter's frame
($d = $ `to_world`$^{-1}\,d_\mathrm{world}$) has
$u = \operatorname{atan2}(d_x, -d_z)/2\pi$ (wrapped to [0, 1)) and $v = \arccos(d_y)/\pi$, so
$+y$ is up (the image's top row), and $-z$ looks at the middle of the image. Texel column $i$
sits at $u = (i + 1/2)/W$, row $j$ at $v = j/(H - 1)$ (the first and last rows at the poles),
and the radiance between texels is bilinear: the four texels' sigmoid-polynomial spectra
and their scales are interpolated separately and multiplied by D65 (thesis 2.2.3; Mitsuba's
`eval_spectrum`). Next-event estimation picks a cell of that bilinear patchwork with
probability proportional to the cell's mean luminance times $\sin\theta$ (a
`radiometria.montecarlo.PiecewiseConstant2D`), a uniform point in it, and converts the density
per unit area of $(u, v)$ into one per solid angle with the Jacobian
$d\omega = 2\pi^2 \sin\theta\, du\, dv$.
"""

import dataclasses
from pathlib import Path
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..._checks import device_array
from ..._math import acos_fast, atan2_fast, dot, sincos_pi
from ...camera import read_exr, read_hdr
from ...montecarlo import PiecewiseConstant2D
from ...upsampling import (
    RGBIlluminantSpectrum,
    forward_model,
    get_lut,
)
from .._spectral import SpectrumTable, sigmoid_texel_spectra, wavelength_grid_nm
from ._base import LightSample, emission_at_infinity
from ._common import AbstractSurfacelessLight, to_world_param

__all__ = ["EnvironmentLight", "read_envmap"]

_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Y of linear sRGB (IEC 61966-2-1)


def read_envmap(path, where: str = "") -> np.ndarray:
    """An equirectangular environment map as linear RGB `(H, W, 3)` float64.

    **Arguments:**

    - `path`: an OpenEXR file (float or half R, G, B channels) or a Radiance RGBE picture
        (`.hdr`, `.rgbe`, `.pic`; `camera.read_hdr`). [path]
    - `where`: the file and line of the scene that names it, for error messages.

    **Returns:**

    The image, width twice its height, every value finite and >= 0. [the file's unit]

    **Raises:**

    `FileNotFoundError` for a missing file; `ValueError` naming `where` and the file for a
    file that is not a readable OpenEXR or RGBE picture, an image that is not 2:1 or smaller
    than 4 x 2 pixels, or a negative or non-finite value.
    """
    path = Path(path)
    prefix = f"{where}: " if where else ""
    if not path.is_file():
        raise FileNotFoundError(f"{prefix}environment map not found: {path}")
    try:
        rgb, _ = (read_hdr if path.suffix.lower() in (".hdr", ".rgbe", ".pic") else read_exr)(path)
    except (OSError, ValueError) as e:
        raise ValueError(f"{prefix}environment map {str(path)!r}: {e}") from None
    rgb = np.asarray(rgb, np.float64)
    h, w = rgb.shape[:2]
    if w != 2 * h or h < 2:
        raise ValueError(
            f"{prefix}environment map {str(path)!r} is {w} x {h} pixels; an equirectangular "
            "map is twice as wide as high (at least 4 x 2)."
        )
    if not np.all(np.isfinite(rgb)) or np.any(rgb < 0):
        bad = np.argwhere(~np.isfinite(rgb) | (rgb < 0))[0]
        raise ValueError(
            f"{prefix}environment map {str(path)!r}: values must be finite and >= 0, got "
            f"{rgb[tuple(bad)]} at pixel (row {bad[0]}, column {bad[1]})."
        )
    return rgb


class EnvironmentLight(AbstractSurfacelessLight):
    r"""An environment map: radiance at infinity from an equirectangular RGB image (module
    docstring: Mitsuba 3's orientation and interpolation).

    Build it with `EnvironmentLight.from_rgb(rgb, scale=, to_world=)` or from scene
    parameters with `from_properties`.

    **Fields:**

    - `coeffs`: `(3, H, W + 1)` sigmoid-polynomial coefficients of each texel's colour,
        one plane per coefficient (column `W` repeats column 0, for the periodic seam).
        [nm^-2, nm^-1, 1]
    - `texel_scale`: `(H, W + 1)` each texel's brightness $2\max(\mathrm{rgb})$ times `scale`.
    - `d65`: `SpectrumTable`, the D65 illuminant with Y = 1. [1]
    - `distribution`: `PiecewiseConstant2D` over the `(H - 1, W)` cells.
    - `to_world`, `world_to_local`: `(3, 3)` the frame and its inverse.
    - `integral`: $\int L_Y\, d\omega$ of the map's luminance (static, for the power).
    - `bound_center`, `bound_radius`: the scene's bounding sphere (`with_bounds`), where
        emitted rays start (`sample_le`); `None` / 0 until set. [scene units]

    !!! note "Thesis"
        Chapter 8 (light sources); chapters 5-6 (importance sampling); section 2.2.3.

    ??? cite "References"
        `Pharr2023` §12.5.2 (image infinite lights), §A.5.6 (`PiecewiseConstant2D`);
        `Jakob2022` (Mitsuba's `envmap`); `Veach1997` ch. 9 (MIS).
    """

    NAME: ClassVar[str] = "envmap"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"filename", "scale", "to_world"})
    coeffs: Float[Array, "3 h w1"]
    texel_scale: Float[Array, "h w1"]
    d65: SpectrumTable
    distribution: PiecewiseConstant2D
    to_world: Float[Array, "3 3"]
    world_to_local: Float[Array, "3 3"]
    integral: float = eqx.field(static=True)
    bound_center: Float[Array, " 3"] | None = None
    bound_radius: float = eqx.field(static=True, default=0.0)

    def with_bounds(self, center, radius: float) -> "EnvironmentLight":
        """The same light knowing the scene's bounding sphere (`center` `(3,)`, `radius`)
        [scene units], so it can start light paths."""
        return dataclasses.replace(
            self, bound_center=device_array(center, self.to_world.dtype), bound_radius=radius
        )

    @classmethod
    def from_rgb(
        cls, rgb, *, scale: float = 1.0, to_world=None, dtype=jnp.float32
    ) -> "EnvironmentLight":
        """An environment light from an equirectangular linear-sRGB image.

        **Arguments:**

        - `rgb`: `(H, W, 3)` radiance, W = 2 H, finite and >= 0 (white (1, 1, 1) emits D65
            with Y = 1). [W m^-2 sr^-1 nm^-1, or the scene's emission unit]
        - `scale`: a factor on the radiance (Mitsuba's `scale`). [1]
        - `to_world`: `(4, 4)` or `(3, 3)` matrix of the map's frame (default identity).
        - `dtype`: float dtype of the arrays.
        """
        rgb = np.asarray(rgb, np.float64)
        if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.shape[1] != 2 * rgb.shape[0]:
            raise ValueError(f"`rgb` must be (H, 2H, 3), got {rgb.shape}.")
        if rgb.shape[0] < 2:
            raise ValueError(f"`rgb` needs at least 2 rows, got {rgb.shape[0]}.")
        if not np.all(np.isfinite(rgb)) or np.any(rgb < 0):
            raise ValueError("`rgb` values must be finite and >= 0.")
        if not (np.isfinite(scale) and scale >= 0):
            raise ValueError(f"`scale` must be finite and >= 0, got {scale}.")
        m = np.eye(3) if to_world is None else np.asarray(to_world, np.float64)[:3, :3]
        h, w = rgb.shape[:2]
        # Coefficients and scale per texel (Mitsuba's srgb_model_fetch of rgb / (2 max rgb)).
        forward_model("sRGB")
        spectrum = RGBIlluminantSpectrum(get_lut("sRGB"), device_array(rgb))
        coeffs = np.asarray(spectrum.coeffs, np.float64)
        texel_scale = np.asarray(spectrum.scale, np.float64) * scale
        coeffs = np.concatenate([coeffs, coeffs[:, :1]], axis=1)
        texel_scale = np.concatenate([texel_scale, texel_scale[:, :1]], axis=1)
        model = forward_model("sRGB")
        d65 = np.interp(wavelength_grid_nm(), model.wavelengths_nm, model.illuminant)
        # Importance: the mean luminance of each cell's four texels (the integral of the
        # bilinear luminance over the cell) times sin(theta) at the cell's centre.
        lum = rgb @ _LUMINANCE * scale
        lum = np.concatenate([lum, lum[:, :1]], axis=1)
        cell = 0.25 * (lum[:-1, :-1] + lum[:-1, 1:] + lum[1:, :-1] + lum[1:, 1:])
        sin_theta = np.sin(np.pi * (np.arange(h - 1) + 0.5) / (h - 1))
        table = cell * sin_theta[:, None]
        integral = float(table.sum() * 2.0 * np.pi**2 / table.size)
        if not np.any(table > 0):
            table = np.ones_like(table)  # a black map: never sampled (its power is 0)
        return cls(
            coeffs=device_array(np.moveaxis(coeffs, -1, 0), dtype),
            texel_scale=device_array(texel_scale, dtype),
            d65=SpectrumTable(device_array(d65[None, :], dtype)),
            distribution=PiecewiseConstant2D(device_array(table, dtype)),
            to_world=device_array(m, dtype),
            world_to_local=device_array(np.linalg.inv(m), dtype),
            integral=integral,
        )

    @classmethod
    def from_properties(
        cls, params: list[dict], *, where: list[str], dtype=jnp.float32
    ) -> "EnvironmentLight":
        """From scene parameters (Mitsuba's names): `filename` (an equirectangular OpenEXR
        file, `read_envmap`; or `data`, the image already read), `scale` (default 1),
        `to_world`. A scene takes one environment emitter (as in Mitsuba)."""
        if len(params) != 1:
            raise ValueError(f"{where[1]}: a scene takes one environment emitter, got a second.")
        p, w = params[0], where[0]
        if "data" in p:
            rgb = p["data"]
        elif "filename" in p:
            rgb = read_envmap(p["filename"], w)
        else:
            raise ValueError(f"{w}: an envmap emitter needs a 'filename'.")
        scale = p.get("scale", 1.0)
        if not isinstance(scale, int | float) or not (np.isfinite(scale) and scale >= 0):
            raise ValueError(f"{w}: parameter 'scale' must be finite and >= 0, got {scale}.")
        return cls.from_rgb(rgb, scale=float(scale), to_world=to_world_param(p, w), dtype=dtype)

    @property
    def shape(self) -> tuple[int, int]:
        """`(H, W)` of the image."""
        return int(self.coeffs.shape[1]), int(self.coeffs.shape[2]) - 1

    def radiance_uv(self, uv: Float[Array, "n 2"], wavelength_nm: Float[Array, "n k"]):
        """Radiance at image coordinates `uv` in [0, 1)^2 (Mitsuba's bilinear lookup: the
        four texels' spectra and scales interpolated separately; `sigmoid_texel_spectra`).
        [W m^-2 sr^-1 nm^-1]"""
        return self._radiance(uv[:, 0], uv[:, 1], wavelength_nm)

    def _radiance(self, u, v, wavelength_nm):
        """`radiance_uv` of the coordinates as two `(n,)` arrays (never stacked: XLA:CPU
        computes a fusion whose result is `(n, 2)` one element at a time, with everything
        fused into it, such as the `atan2` of `_uv`)."""
        h, w = self.shape
        x = jnp.mod(u - 0.5 / w, 1.0) * w
        y = jnp.clip(v, 0.0, 1.0) * (h - 1)
        ix = jnp.clip(jnp.floor(x).astype(jnp.int32), 0, w - 1)
        iy = jnp.clip(jnp.floor(y).astype(jnp.int32), 0, h - 2)
        wx = x - ix.astype(x.dtype)
        wy = y - iy.astype(y.dtype)
        coeffs = self.coeffs.reshape(3, -1)
        texel_scale = self.texel_scale.reshape(-1)
        lam = wavelength_nm.T
        row = iy * (w + 1) + ix
        s, f = 0.0, 0.0
        for texel, weight in (
            (row, (1 - wy) * (1 - wx)),
            (row + 1, (1 - wy) * wx),
            (row + w + 1, wy * (1 - wx)),
            (row + w + 2, wy * wx),
        ):
            s = s + weight[None, :] * sigmoid_texel_spectra(coeffs, texel, lam)
            f = f + weight * texel_scale[texel]
        d65 = self.d65(jnp.zeros(u.shape, jnp.int32), wavelength_nm)
        return (s * f[None, :]).T.astype(wavelength_nm.dtype) * d65

    def _uv(self, directions):
        """Image coordinates `u`, `v` `(n,)` of world directions, and `sin(theta)`."""
        m = self.world_to_local
        x, y, z = (
            m[i, 0] * directions[:, 0] + m[i, 1] * directions[:, 1] + m[i, 2] * directions[:, 2]
            for i in range(3)
        )
        length = jnp.sqrt(jnp.maximum(x * x + y * y + z * z, 1e-30))
        x, y, z = x / length, y / length, z / length
        u = jnp.mod(atan2_fast(x, -z) / (2.0 * np.pi), 1.0)
        v = acos_fast(jnp.clip(y, -1.0, 1.0)) / np.pi
        return u, v, jnp.sqrt(x * x + z * z)

    def _pdf_uv_to_solid_angle(self, pdf_uv, sin_theta):
        eps = jnp.finfo(sin_theta.dtype).eps
        return pdf_uv / (2.0 * np.pi**2 * jnp.maximum(sin_theta, eps))

    def sample_li(self, p, u_select, u2, wavelength_nm) -> LightSample:
        n = p.shape[0]
        h, w = self.shape
        cell_uv, pdf_uv, _ = self.distribution.sample(u2, check=False)
        u = jnp.mod(cell_uv[:, 0] + 0.5 / w, 1.0)
        v = cell_uv[:, 1]
        sin_theta, cos_theta = sincos_pi(v)  # theta = pi v
        sin_phi, cos_phi = sincos_pi(2.0 * u)  # phi = 2 pi u
        local = jnp.stack([sin_phi * sin_theta, cos_theta, -cos_phi * sin_theta], axis=-1)
        wi = local @ self.to_world.T
        wi = wi / jnp.sqrt(dot(wi, wi))[:, None]
        le = self._radiance(u, v, wavelength_nm)
        return LightSample(
            wi=wi.astype(p.dtype),
            dist=jnp.full((n,), jnp.inf, p.dtype),
            radiance=le.astype(p.dtype),
            pdf=self._pdf_uv_to_solid_angle(pdf_uv, sin_theta).astype(p.dtype),
            delta=jnp.zeros((n,), bool),
        )

    def emitted_escaped(self, directions, escaped, wavelength_nm):
        u, v, _ = self._uv(directions)
        le = self._radiance(u, v, wavelength_nm).astype(directions.dtype)
        return jnp.where(escaped[:, None], le, 0.0)

    def pdf_escaped(self, directions):
        u, v, sin_theta = self._uv(directions)
        w = self.shape[1]
        cell_uv = jnp.stack([jnp.mod(u - 0.5 / w, 1.0), v], axis=-1)
        pdf = self._pdf_uv_to_solid_angle(self.distribution.pdf(cell_uv), sin_theta)
        return pdf.astype(directions.dtype)

    def sample_le(self, u_select, u_pos, u_dir, u_side, observer, wavelength_nm):
        """An emitted ray: a direction from the map's distribution (`u_dir`, the density
        of `sample_li` and `pdf_escaped`) travelling inwards, from a point uniform on the
        disk of the scene's radius across it (`u_pos`)."""
        if self.bound_center is None:
            raise ValueError("an envmap light needs the scene's bounds (`with_bounds`).")
        dtype = observer.dtype
        ls = self.sample_li(observer, u_select, u_dir, wavelength_nm)
        n = observer.shape[0]
        return emission_at_infinity(
            -ls.wi,
            u_pos,
            self.bound_center.astype(dtype),
            self.bound_radius,
            ls.radiance,
            ls.pdf,
            jnp.ones((n,), dtype),
        )

    def power(self, scene_radius: float) -> float:
        return float(np.pi * scene_radius**2 * self.integral)
