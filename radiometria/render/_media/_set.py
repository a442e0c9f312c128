"""The media of a scene: one plugin per kind, and each path's medium selected by index."""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float, Int

from ..._checks import device_array
from ...media import HomogeneousMedium, MediumInteraction, PhaseSample
from ._base import AbstractMediumPlugin

__all__ = ["KEEP_MEDIUM", "VACUUM", "MediumSet"]

VACUUM = -1  # medium index of empty space
KEEP_MEDIUM = -2  # a face that is no medium boundary: a ray crossing it stays in its medium


def _select(mask: Array, a: Array, b: Array) -> Array:
    """`a` where the per-path `mask (n,)` holds, else `b` (arrays with a leading path axis)."""
    return jnp.where(mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, b)


def _concatenate(plugins: list) -> AbstractMediumPlugin:
    if len(plugins) == 1:
        return plugins[0]
    return jax.tree.map(lambda *xs: jnp.concatenate(xs, axis=0), *plugins)


class MediumSet(eqx.Module):
    """A scene's `m` media, grouped into plugins, with per-path queries by medium index.

    Build it with `MediumSet.from_media([...])` from medium plugins in the order of the scene's
    medium indices. Every query takes `medium (n,)` int32, the index of each path's medium, or
    `VACUUM` (-1) for empty space, where nothing scatters and the transmittance is 1.

    **Fields:**

    - `plugins`: one `AbstractMediumPlugin` per kind present (concatenable kinds merged),
        or per medium for kinds that are not (grids).
    - `plugin_of`, `row_of`: `(m,)` int32, the plugin and the row of each medium.

    With several plugins every plugin's estimate is computed and each path takes its own
    (`where`), as `MaterialSet` does for materials.

    !!! note "Thesis"
        Chapter 4 (energy transport in a medium), chapter 9 (volume rendering).

    ??? cite "References"
        `Jakob2022` (media bound to shapes and sensors); `Pharr2023` §11.4, §14.1.
    """

    plugins: tuple[AbstractMediumPlugin, ...]
    plugin_of: Int[Array, " m"]
    row_of: Int[Array, " m"]

    @classmethod
    def from_media(cls, media: "list[AbstractMediumPlugin]") -> "MediumSet":
        """Group medium plugins by kind (outside `jit`)."""
        if not media:
            raise ValueError("a MediumSet needs at least one medium.")
        groups: list[list[AbstractMediumPlugin]] = []
        kinds: list[type | None] = []
        plugin_of, row_of = [], []
        for m in media:
            if not isinstance(m, AbstractMediumPlugin):
                raise TypeError(f"media must be AbstractMediumPlugin plugins, got {type(m)}.")
            kind = type(m) if m.CONCATENABLE else None
            if kind is not None and kind in kinds:
                g = kinds.index(kind)
            else:
                kinds.append(kind)
                groups.append([])
                g = len(groups) - 1
            first = sum(p.n_rows for p in groups[g])
            groups[g].append(m)
            plugin_of += [g] * m.n_rows
            row_of += list(range(first, first + m.n_rows))
        return cls(
            plugins=tuple(_concatenate(g) for g in groups),
            plugin_of=device_array(plugin_of, jnp.int32),
            row_of=device_array(row_of, jnp.int32),
        )

    @property
    def n_media(self) -> int:
        """Number of media `m`."""
        return int(self.plugin_of.shape[0])

    def _parts(self, medium, wavelength_nm):
        """`(media, masks)`: each plugin's medium for every path, and which paths are its."""
        m = jnp.clip(medium, 0, self.n_media - 1)
        row = self.row_of[m]
        inside = medium >= 0
        if len(self.plugins) == 1:
            return [self.plugins[0].medium(row, wavelength_nm)], [inside]
        which = self.plugin_of[m]
        media = [p.medium(jnp.where(which == i, row, 0), wavelength_nm)
                 for i, p in enumerate(self.plugins)]  # fmt: skip
        return media, [inside & (which == i) for i in range(len(self.plugins))]

    def sample_free_flight(
        self,
        medium: Int[Array, " n"],
        origins: Float[Array, "n 3"],
        directions: Float[Array, "n 3"],
        t_max: Float[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        u: Float[Array, "n d"],
        channel: Int[Array, " n"] | None = None,
    ) -> MediumInteraction:
        """Free-flight sampling on `(0, t_max)` [scene units] in each path's medium (a vacuum:
        no event, weight 1); `u` `(n, d)` uniform variates, `d >= 1`. `channel`: sample
        homogeneous media at that wavelength index alone (`HomogeneousMedium`); `pdf` is 1
        where a medium has no per-wavelength density (a vacuum, grids)."""
        n, k = wavelength_nm.shape
        dtype = origins.dtype
        t = jnp.where(medium >= 0, t_max, 0.0)
        ones = jnp.ones((n, k), dtype)
        out = MediumInteraction(t=t_max, scattered=jnp.zeros((n,), bool), weight=ones, pdf=ones)
        media, masks = self._parts(medium, wavelength_nm)
        for med, mask in zip(media, masks, strict=True):
            if isinstance(med, HomogeneousMedium):
                mi = med.sample_free_flight(origins, directions, t, wavelength_nm, u, channel)
            else:
                mi = med.sample_free_flight(origins, directions, t, wavelength_nm, u)
                mi = MediumInteraction(t=mi.t, scattered=mi.scattered, weight=mi.weight, pdf=ones)
            out = jax.tree.map(lambda a, b, mask=mask: _select(mask, a, b), mi, out)
        return out

    def transmittance(
        self,
        medium: Int[Array, " n"],
        origins: Float[Array, "n 3"],
        directions: Float[Array, "n 3"],
        t_max: Float[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        u: Float[Array, "n d"],
    ) -> Float[Array, "n k"]:
        """Transmittance of `(0, t_max)` [scene units] in each path's medium (1 in a vacuum):
        exact for homogeneous media, unbiased estimates for grids. [1]"""
        n, k = wavelength_nm.shape
        out = jnp.ones((n, k), origins.dtype)
        t = jnp.where(medium >= 0, t_max, 0.0)
        media, masks = self._parts(medium, wavelength_nm)
        for med, mask in zip(media, masks, strict=True):
            tr = med.transmittance(origins, directions, t, wavelength_nm, u)
            out = jnp.where(mask[:, None], tr, out)
        return out

    def phase(self, medium: Int[Array, " n"], wo, wi, wavelength_nm) -> Float[Array, " n"]:
        """The phase function `p(wo, wi)` of each path's medium [sr^-1] (0 in a vacuum)."""
        out = jnp.zeros(medium.shape, wo.dtype)
        media, masks = self._parts(medium, wavelength_nm)
        for med, mask in zip(media, masks, strict=True):
            out = jnp.where(mask, med.phase.p(wo, wi), out)
        return out

    def sample_phase(self, medium: Int[Array, " n"], wo, u2, wavelength_nm) -> PhaseSample:
        """Sample `wi` from each path's phase function with variates `u2 (n, 2)`."""
        media, masks = self._parts(medium, wavelength_nm)
        out = None
        for med, mask in zip(media, masks, strict=True):
            s = med.phase.sample_p(wo, u2)
            if out is None:
                out = s
                continue
            out = jax.tree.map(
                lambda a, b, mask=mask: jnp.where(
                    mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, b
                ),
                s,
                out,
            )
        return out
