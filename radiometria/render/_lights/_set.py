"""The lights of a scene: one plugin per kind present, one light picked per sample by power."""

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..._checks import device_array
from ._area import AreaLight
from ._base import AbstractLight, LightSample
from ._common import pick_row, row_cdf
from ._constant import ConstantLight
from ._envmap import EnvironmentLight

__all__ = ["LightSet"]

_INFINITE = (ConstantLight, EnvironmentLight)


class LightSet(AbstractLight):
    r"""Several light plugins of different kinds as one light (as `MaterialSet` groups
    materials).

    Next-event estimation picks plugin $j$ with probability $P_j = \Phi_j / \sum_i \Phi_i$,
    proportional to its power (`AbstractLight.power`; lights at infinity and directional
    lights count the power falling on a disk of the scene's radius, as in pbrt), re-uses the
    selection variate within the chosen plugin (which picks one of its lights by power, or
    area emitters by their estimated contribution at the shading point, in
    turn), and multiplies the sample's density by $P_j$. The densities the integrator weighs
    BSDF samples against are therefore $P_\mathrm{area}\,p_\mathrm{area}$ for a hit on an
    emissive triangle (`pdf_li`) and $P_\mathrm{env}\,p_\mathrm{env}$ for a ray that escapes
    (`pdf_escaped`), which keeps multiple importance sampling consistent. Delta lights are
    picked the same way and their samples keep `delta = True`.

    A scene has at most one area-light plugin (`AreaLight` holds every emissive triangle)
    and at most one light at infinity (`ConstantLight` or `EnvironmentLight`, as Mitsuba
    allows one environment emitter). Every plugin is evaluated for every path and each path
    keeps its chosen one (`where`), the usual way to vectorise a mixture.

    Build it with `LightSet.from_lights([...], scene_radius=...)`.

    **Fields:**

    - `lights`: the plugins.
    - `cdf`: `(L,)` cumulative selection probabilities; `prob`: `(L,)` the probabilities.
    - `area_index`, `infinite_index`: position of the area / infinite plugin, or -1 (static).

    !!! note "Thesis"
        Chapter 8 (light sources); chapter 7 (MIS).

    ??? cite "References"
        `Pharr2023` §12.6.2 (`PowerLightSampler`); `Veach1997` ch. 9.
    """

    NAME: ClassVar[str] = "light_set"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset()
    lights: tuple[AbstractLight, ...]
    cdf: Float[Array, " L"]
    prob: Float[Array, " L"]
    area_index: int = eqx.field(static=True)
    infinite_index: int = eqx.field(static=True)

    @classmethod
    def from_lights(
        cls,
        lights: "list[AbstractLight]",
        *,
        scene_radius: float,
        scene_center=None,
        dtype=jnp.float32,
    ) -> "LightSet":
        """Group light plugins, with selection probabilities by power (NumPy, outside `jit`).

        **Arguments:**

        - `lights`: the plugins (at most one `AreaLight`, at most one light at infinity).
        - `scene_radius`: radius of the scene's bounding sphere, for the power of lights
            at infinity. [scene units]
        - `scene_center`: `(3,)` centre of that sphere (default: the origin); lights at
            infinity and directional lights start their emitted rays (`sample_le`) on a
            disk of `scene_radius` about it. [scene units]
        """
        lights = list(lights)
        center = np.zeros(3) if scene_center is None else np.asarray(scene_center, float)
        lights = [
            lt.with_bounds(center, float(scene_radius)) if hasattr(lt, "with_bounds") else lt
            for lt in lights
        ]
        if not lights:
            raise ValueError("a LightSet needs at least one light plugin.")
        for light in lights:
            if not isinstance(light, AbstractLight) or isinstance(light, LightSet):
                raise TypeError(f"lights must be light plugins, got {type(light).__name__}.")
        area = [i for i, lt in enumerate(lights) if isinstance(lt, AreaLight)]
        infinite = [i for i, lt in enumerate(lights) if isinstance(lt, _INFINITE)]
        if len(area) > 1:
            raise ValueError("a LightSet takes one AreaLight (it holds every emissive triangle).")
        if len(infinite) > 1:
            raise ValueError(
                f"a scene takes one environment emitter (constant or envmap), got {len(infinite)}."
            )
        power = np.array([max(float(lt.power(scene_radius)), 0.0) for lt in lights])
        cdf = row_cdf(power)
        prob = np.diff(np.concatenate([[0.0], cdf]))
        return cls(
            lights=tuple(lights),
            cdf=device_array(cdf, dtype),
            prob=device_array(prob, dtype),
            area_index=area[0] if area else -1,
            infinite_index=infinite[0] if infinite else -1,
        )

    def sample_li(self, p, u_select, u2, wavelength_nm) -> LightSample:
        j, prob, u_light = pick_row(self.cdf, u_select)
        out = None
        for i, light in enumerate(self.lights):
            s = light.sample_li(p, u_light, u2, wavelength_nm)
            delta = jnp.zeros(s.pdf.shape, bool) if s.delta is None else s.delta
            s = LightSample(wi=s.wi, dist=s.dist, radiance=s.radiance, pdf=s.pdf, delta=delta)
            if out is None:
                out = s
                continue
            mine = j == i
            out = LightSample(
                wi=jnp.where(mine[:, None], s.wi, out.wi),
                dist=jnp.where(mine, s.dist, out.dist),
                radiance=jnp.where(mine[:, None], s.radiance, out.radiance),
                pdf=jnp.where(mine, s.pdf, out.pdf),
                delta=jnp.where(mine, s.delta, out.delta),
            )
        return LightSample(
            wi=out.wi, dist=out.dist, radiance=out.radiance, pdf=out.pdf * prob, delta=out.delta
        )

    def sample_le(self, u_select, u_pos, u_dir, u_side, observer, wavelength_nm):
        """An emitted ray from the plugin picked by power (probability $P_j$, which scales
        `pdf_pos`); every plugin must support `sample_le` (else `ValueError`)."""
        j, prob, u_light = pick_row(self.cdf, u_select)
        out = None
        for i, light in enumerate(self.lights):
            s = light.sample_le(u_light, u_pos, u_dir, u_side, observer, wavelength_nm)
            s = s.complete()
            if out is None:
                out = s
                continue
            mine = j == i
            out = jax.tree.map(
                lambda a, b, m=mine: jnp.where(m.reshape(m.shape + (1,) * (a.ndim - 1)), a, b),
                s,
                out,
            )
        return eqx.tree_at(lambda e: e.pdf_pos, out, out.pdf_pos * prob)

    def pdf_le(self, face, cos_o):
        """The area plugin's `pdf_le`, its position density times its pick probability."""
        if self.area_index < 0:
            return super().pdf_le(face, cos_o)
        i = self.area_index
        pdf_pos, pdf_dir = self.lights[i].pdf_le(face, cos_o)
        return self.prob[i] * pdf_pos, pdf_dir

    def pdf_li(self, face, dist, cos_light, origin=None):
        if self.area_index < 0:
            return jnp.zeros(face.shape, dist.dtype)
        i = self.area_index
        return self.prob[i] * self.lights[i].pdf_li(face, dist, cos_light, origin)

    def emitted(self, face, cos_o, valid, wavelength_nm, uv=None):
        if self.area_index < 0:
            return jnp.zeros(wavelength_nm.shape, cos_o.dtype)
        return self.lights[self.area_index].emitted(face, cos_o, valid, wavelength_nm, uv)

    def emitted_escaped(self, directions, escaped, wavelength_nm):
        if self.infinite_index < 0:
            return jnp.zeros(wavelength_nm.shape, directions.dtype)
        light = self.lights[self.infinite_index]
        return light.emitted_escaped(directions, escaped, wavelength_nm)

    def pdf_escaped(self, directions):
        if self.infinite_index < 0:
            return jnp.zeros(directions.shape[:-1], directions.dtype)
        i = self.infinite_index
        return self.prob[i] * self.lights[i].pdf_escaped(directions)

    def power(self, scene_radius: float) -> float:
        return float(sum(lt.power(scene_radius) for lt in self.lights))
