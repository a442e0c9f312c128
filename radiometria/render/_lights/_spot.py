"""Spot lights (Mitsuba's `spot` emitter): point lights emitting into a cone."""

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..._checks import device_array
from ..._math import dot
from ...montecarlo import sample_uniform_cone
from ...upsampling import RGBAlbedoSpectrum, RGBIlluminantSpectrum
from .._spectral import SpectrumTable
from .._textures import (
    AbstractTexture,
    ConstantTexture,
    TextureSpec,
    concatenate_textures,
    texture_parameter,
)
from ._base import EmissionSample, LightSample
from ._common import (
    AbstractDeltaLight,
    direction_to_points,
    illuminant_table,
    pick_row,
    row_cdf,
    spectral_param,
    to_world_param,
)


def spot_falloff(cos_theta, cutoff, beam_width):
    r"""Mitsuba 3's spot falloff: 1 inside the beam width, falling linearly in the angle to 0
    at the cutoff angle, 0 outside.

    $$f(\theta) = \begin{cases} 1 & \theta \le \theta_b \\
      (\theta_c - \theta)/(\theta_c - \theta_b) & \theta_b < \theta < \theta_c \\
      0 & \theta \ge \theta_c \end{cases}$$

    **Arguments:**

    - `cos_theta`: cosine of the angle to the spot's axis. [1]
    - `cutoff`, `beam_width`: $\theta_c$ and $\theta_b$. [rad]

    **Returns:**

    The falloff in [0, 1]. [1]

    ??? cite "References"
        `Jakob2022` (Mitsuba 3's `spot` emitter, `falloff_curve`).
    """
    xp = jnp if isinstance(cos_theta, jnp.ndarray) else np
    c = xp.clip(cos_theta, -1.0, 1.0)
    width = cutoff - beam_width
    ramp = (cutoff - xp.arccos(c)) / xp.where(width > 0, width, 1.0)
    inside = xp.where(c >= xp.cos(beam_width), 1.0, ramp)
    return xp.where(c > xp.cos(cutoff), inside, 0.0)


def _spot_texture(spec: TextureSpec, where: str) -> AbstractTexture:
    """A spot's `texture` as Mitsuba 3 (3.9) evaluates it: the texels' bounded (albedo)
    spectra, without D65 (checked against Mitsuba's spot read from XML in the tests)."""
    return texture_parameter(spec, RGBAlbedoSpectrum, "texture", where)


class SpotLight(AbstractDeltaLight):
    r"""Spot lights: every `spot` emitter of a scene, one row each.

    A spot at the origin of its `to_world` frame shines along the frame's +z axis with
    intensity $I\,f(\theta)$, where $f$ is Mitsuba's falloff (`spot_falloff`: 1 up to
    `beam_width`, linear in the angle down to 0 at `cutoff_angle`). Next-event estimation picks
    a spot by its power $2\pi \bar I \int_0^{\theta_c} f(\theta)\sin\theta\,d\theta$.

    **Fields:**

    - `position`: `(m, 3)` apexes. [scene units]
    - `world_to_local`: `(m, 3, 3)` inverse of the 3x3 part of each `to_world`.
    - `intensity`: `SpectrumTable`, the on-axis intensity, one row per spot. [W sr^-1 nm^-1]
    - `cos_cutoff`, `cutoff`, `beam_width`: `(m,)` cone angles (cosine; [rad]).
    - `cdf`: `(m,)` cumulative probabilities of picking each spot; `phi`: power (static).
    - `texture`: the spots' `texture`s (Mitsuba's: a bitmap over the spot's image plane,
        the texels' albedo spectra, as Mitsuba renders XML scenes), one row each (1 for
        spots without one), or `None` when no spot has one. Direction $(x, y, z)$ in the
        spot's frame is looked up at
        $uv = (1/2 + x / (2 z \tan\theta_c),\ 1/2 + y / (2 z \tan\theta_c))$ and multiplies
        the intensity. Spots are still picked by their untextured power (unbiased either way).

    !!! note "Thesis"
        Chapter 8 (light sources); eq. 1.10-1.12 (intensity and irradiance).

    ??? cite "References"
        `Pharr2023` §12.1.2 (spotlights); `Jakob2022` (Mitsuba's `spot` emitter).
    """

    NAME: ClassVar[str] = "spot"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"intensity", "cutoff_angle", "beam_width", "to_world", "texture"}
    )
    position: Float[Array, "m 3"]
    world_to_local: Float[Array, "m 3 3"]
    intensity: SpectrumTable
    cutoff: Float[Array, " m"]
    beam_width: Float[Array, " m"]
    cdf: Float[Array, " m"]
    phi: float = eqx.field(static=True)
    texture: AbstractTexture | None = None

    @classmethod
    def from_properties(
        cls, params: list[dict], *, where: list[str], dtype=jnp.float32
    ) -> "SpotLight":
        """Spot lights from scene parameters (Mitsuba's names and defaults): `intensity`
        (default 1) [W sr^-1 nm^-1], `cutoff_angle` (default 20) and `beam_width` (default
        3/4 of the cutoff) [degrees], `to_world` (position and +z axis), `texture` (a bitmap
        `TextureSpec`, class docstring). Bad values raise `ValueError` naming `where`."""
        pos, inv, rows, cut, beam, powers, textures = [], [], [], [], [], [], []
        theta = np.linspace(0.0, np.pi, 20001)
        for p, w in zip(params, where, strict=True):
            m = to_world_param(p, w)
            cutoff = p.get("cutoff_angle", 20.0)
            width = p.get("beam_width", 0.75 * cutoff)
            for name, v in (("cutoff_angle", cutoff), ("beam_width", width)):
                if not isinstance(v, int | float) or not 0 < v <= 90:
                    raise ValueError(f"{w}: parameter '{name}' must be in (0, 90] [deg], got {v}.")
            if width > cutoff:
                raise ValueError(
                    f"{w}: parameter 'beam_width' ({width} deg) must not exceed "
                    f"'cutoff_angle' ({cutoff} deg)."
                )
            c, b = np.radians(cutoff), np.radians(width)
            pos.append(m[:3, 3])
            inv.append(np.linalg.inv(m[:3, :3]))
            row = spectral_param(p, "intensity", w)
            rows.append(row)
            cut.append(c)
            beam.append(b)
            tex = p.get("texture")
            if tex is not None and (not isinstance(tex, TextureSpec) or tex.type != "bitmap"):
                raise ValueError(f"{w}: parameter 'texture' must be a bitmap texture, got {tex!r}.")
            textures.append(
                _spot_texture(tex, w)
                if tex is not None
                else ConstantTexture.from_values([1.0], RGBIlluminantSpectrum, dtype)
            )
            f = spot_falloff(np.cos(theta), c, b) * np.sin(theta)
            powers.append(2.0 * np.pi * row.mean() * np.trapezoid(f, theta))
        return cls(
            position=device_array(np.stack(pos), dtype),
            world_to_local=device_array(np.stack(inv), dtype),
            intensity=illuminant_table(rows, dtype),
            cutoff=device_array(cut, dtype),
            beam_width=device_array(beam, dtype),
            cdf=device_array(row_cdf(np.array(powers)), dtype),
            phi=float(np.sum(powers)),
            texture=concatenate_textures(textures)
            if any(p.get("texture") is not None for p in params)
            else None,
        )

    def _intensity(self, j, w, wavelength_nm):
        """The intensity of spots `j` (n,) along world directions `w` (n, 3) from their apexes,
        with their textures, without the falloff."""
        out = self.intensity(j, wavelength_nm)
        if self.texture is None:
            return out
        local = jnp.einsum("nij,nj->ni", self.world_to_local[j], w)
        z = local[:, 2] * jnp.tan(self.cutoff[j])
        z = jnp.where(jnp.abs(z) > 0, z, 1.0)
        uv = jnp.stack([0.5 + 0.5 * local[:, 0] / z, 0.5 + 0.5 * local[:, 1] / z], axis=-1)
        return out * self.texture(j, wavelength_nm, uv.astype(wavelength_nm.dtype))

    def _falloff(self, j, w):
        """The falloff of spots `j` (n,) along world directions `w` (n, 3) from their apexes."""
        local = jnp.einsum("nij,nj->ni", self.world_to_local[j], w)
        cos = local[:, 2] / jnp.sqrt(jnp.maximum(dot(local, local), 1e-30))
        return spot_falloff(cos, self.cutoff[j], self.beam_width[j])

    def sample_li(self, p, u_select, u2, wavelength_nm) -> LightSample:
        j, prob, _ = pick_row(self.cdf, u_select)
        wi, dist, dist2, ok = direction_to_points(self.position[j], p)
        # The direction from the apex to p in the spot's frame (Mitsuba: to_world^-1 (-wi)).
        falloff = self._falloff(j, -wi)
        scale = falloff / jnp.where(ok, dist2, 1.0)
        le = self._intensity(j, -wi, wavelength_nm) * scale[:, None]
        ok = ok & (falloff > 0)
        return LightSample(
            wi=wi,
            dist=dist,
            radiance=le,
            pdf=jnp.where(ok, prob, 0.0),
            delta=jnp.ones(dist.shape, bool),
        )

    def power(self, scene_radius: float) -> float:
        return self.phi

    def sample_le(self, u_select, u_pos, u_dir, u_side, observer, wavelength_nm):
        """An emitted ray: a spot by power, a uniform direction in its cutoff cone (density
        $1 / 2\\pi(1 - \\cos\\theta_c)$); the throughput is $I f(\\theta)$ over both
        densities."""
        j, prob, _ = pick_row(self.cdf, u_select)
        dtype = observer.dtype
        cos_max = jnp.cos(self.cutoff[j])
        local = sample_uniform_cone(u_dir, cos_max, check=False).astype(dtype)
        to_world = jnp.linalg.inv(self.world_to_local[j])
        d = jnp.einsum("nij,nj->ni", to_world, local)
        d = d / jnp.sqrt(dot(d, d))[:, None]
        to_obs = observer - self.position[j]
        return EmissionSample(
            p=self.position[j],
            n=jnp.zeros_like(d),
            d=d,
            le=self._intensity(j, d, wavelength_nm) * self._falloff(j, d)[:, None],
            pdf_pos=prob,
            pdf_dir=1.0 / (2.0 * jnp.pi * (1.0 - cos_max)),
            le_observer=self._intensity(j, to_obs, wavelength_nm)
            * self._falloff(j, to_obs)[:, None],
            delta_pos=jnp.ones(prob.shape, bool),
            pdf_dir_observer=jnp.where(
                self._falloff(j, to_obs) > 0, 1.0 / (2.0 * jnp.pi * (1.0 - cos_max)), 0.0
            ),
        )
