"""Textures of several rows of different kinds (constant, bitmap, ...) as one texture."""

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float, Int

from ..._checks import device_array
from ._base import AbstractTexture
from ._bitmap import BitmapTexture

__all__ = ["TextureStack", "concatenate_textures"]


class TextureStack(AbstractTexture):
    """Rows held by several textures (e.g. a constant reflectance and two images): each
    texture is looked up for every path and each path takes its own row's (`where` selects),
    the usual way to vectorise a mixture.

    **Fields:**

    - `parts`: the textures.
    - `part_of`, `row_of`: `(m,)` int32, the texture and its row of each row.
    """

    parts: tuple[AbstractTexture, ...]
    part_of: Int[Array, " m"]
    row_of: Int[Array, " m"]

    @property
    def n_rows(self) -> int:
        return int(self.part_of.shape[0])

    def __call__(
        self,
        row: Int[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        uv: Float[Array, "n _"] | None = None,
    ) -> Float[Array, "n k"]:
        part, local = self.part_of[row], self.row_of[row]
        out = self.parts[0](local, wavelength_nm, uv)
        for i, p in enumerate(self.parts[1:], start=1):
            out = jnp.where((part == i)[..., None], p(local, wavelength_nm, uv), out)
        return out


def _joinable(a: AbstractTexture, b: AbstractTexture) -> bool:
    """Whether two textures' rows concatenate into one texture of their kind."""
    if type(a) is not type(b) or isinstance(a, BitmapTexture | TextureStack):
        return False
    sa, sb = jax.tree.structure(a), jax.tree.structure(b)
    return sa == sb


def concatenate_textures(textures: "list[AbstractTexture]") -> AbstractTexture:
    """The rows of `textures`, in order, as one texture: textures of one kind that hold rows
    (constant, checkerboard) are concatenated, images stay separate parts of a
    `TextureStack`."""
    if not textures:
        raise ValueError("no textures to concatenate.")
    groups: list[list[AbstractTexture]] = []
    for t in textures:
        if not isinstance(t, AbstractTexture):
            raise TypeError(f"expected an AbstractTexture, got {type(t).__name__}.")
        if groups and _joinable(groups[-1][0], t):
            groups[-1].append(t)
        else:
            groups.append([t])
    parts = [
        g[0] if len(g) == 1 else jax.tree.map(lambda *xs: jnp.concatenate(xs, axis=0), *g)
        for g in groups
    ]
    if len(parts) == 1:
        return parts[0]
    # Parts of one kind that hold rows are merged again (constant, image, constant -> 2 parts).
    merged: list[AbstractTexture] = []
    part_of, row_of = [], []
    for p in parts:
        target = next((i for i, q in enumerate(merged) if _joinable(q, p)), None)
        if target is None:
            merged.append(p)
            target, first = len(merged) - 1, 0
        else:
            first = merged[target].n_rows
            merged[target] = jax.tree.map(
                lambda a, b: jnp.concatenate([a, b], axis=0), merged[target], p
            )
        part_of += [target] * p.n_rows
        row_of += list(range(first, first + p.n_rows))
    if len(merged) == 1:
        return merged[0]
    return TextureStack(
        tuple(merged), device_array(part_of, jnp.int32), device_array(row_of, jnp.int32)
    )
