"""The texture interface: a spectral quantity looked up per row (material) and position."""

import abc

import equinox as eqx
from jaxtyping import Array, Float, Int


class AbstractTexture(eqx.Module):
    """Spectral values of a material parameter for a batch of hits (thesis ch. 8).

    A texture holds the values of one parameter for several materials at once (one *row* per
    material, as every material plugin stores its parameters), so that one lookup serves every
    path of a batch whatever its material. Implementations are final `equinox` Modules: they
    pass through `jit`, `vmap` and `grad` (a texture's arrays are differentiable).

    ??? cite "References"
        `Pharr2023` §10.3-10.4 (textures); `Jakob2022` (Mitsuba 3's `Texture` interface).
    """

    @property
    @abc.abstractmethod
    def n_rows(self) -> int:
        """Number of rows (materials) the texture holds."""

    @abc.abstractmethod
    def __call__(
        self,
        row: Int[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        uv: Float[Array, "n _"] | None = None,
    ) -> Float[Array, "n k"]:
        """Values of row `row[i]` at the wavelengths of path `i` [nm] and its surface
        coordinates `uv` (ignored by textures that do not vary over the surface): columns
        0 and 1 are (u, v); a scene with mesh attributes adds the barycentrics and the
        triangle's baked attributes after them (`RenderScene.surface_width`)."""
