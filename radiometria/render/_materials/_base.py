"""The material interface: a BSDF plugin that owns its parameter table and builds its BxDF.

A material plugin holds the parameters of every material of its kind in a scene, one *row*
per material (spectral parameters as textures, scalars as `(m,)` arrays), and builds the
`radiometria.scattering` BxDF of each path's row at the path's hero wavelengths. The scene's
`MaterialSet` keeps one plugin per kind present and selects per path.
"""

import abc
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from ...scattering import AbstractBxDF, BSDFSample
from .._spectral import SpectralValue
from .._textures import AbstractTexture, TextureSpec, concatenate_textures

__all__ = ["AbstractMaterial", "Properties"]

Properties = dict[str, "SpectralValue | TextureSpec | str | bool | int | AbstractMaterial"]
"""A plugin's parameters as a scene file gives them: name -> number, string, `LinearRGB`
triple, spectrum, texture, or a nested material plugin (`blendbsdf`, `mask`) (Mitsuba 3's
`Properties`)."""


class AbstractMaterial(eqx.Module):
    """A surface material kind (a BSDF plugin) with the parameters of `m` materials as rows.

    **Subclasses provide:**

    - `NAME`: the plugin's name in scene files (Mitsuba 3's BSDF type, e.g. `"diffuse"`).
    - `PARAMETERS`: the parameter names a scene file may give it.
    - `TRANSMISSIVE`: whether light passes through the surface (both sides are boundaries
        of the medium behind it), e.g. dielectrics.
    - a `two_sided` field `(m,)` bool: scatter on both sides (Mitsuba's `twosided`), else
        only on the side the geometric normal points to.
    - `from_properties(params, two_sided=..., where=...)`: one material (one row) from a scene
        file's parameters, with Mitsuba's defaults.
    - `bxdf(row, wavelength_nm)`: the BxDF of row `row[i]` at the wavelengths of path `i`;
        with `USES_UV = True`, `bxdf(row, wavelength_nm, uv)` also gets the hits' surface
        coordinates `uv` `(n, 2)` (or `None`) for its textures.

    Every field has the row axis first, so the materials of one kind in a scene are one
    plugin (`concatenate`), and plugins pass through `jit`, `vmap` and `grad`.

    !!! note "Thesis"
        Chapter 3 (BSDFs of surfaces, eq. 3.4; Fresnel equations 3.13-3.18).

    ??? cite "References"
        `Jakob2022` (Mitsuba 3's BSDF plugins); `Pharr2023` §9.1 (`BxDF` interface).
    """

    NAME: ClassVar[str]
    PARAMETERS: ClassVar[frozenset[str]]
    TRANSMISSIVE: ClassVar[bool] = False
    USES_UV: ClassVar[bool] = False  # bxdf(row, wavelength_nm, uv): textured parameters
    # bxdf(row, wavelength_nm, uv, geometry): the hits' HitGeometry (normal and bump maps, and
    # the composites that pass it on to their nested materials)
    USES_GEOMETRY: ClassVar[bool] = False
    two_sided: eqx.AbstractVar[Bool[Array, " m"]]

    @classmethod
    @abc.abstractmethod
    def from_properties(
        cls, params: Properties, *, two_sided: bool = False, where: str = "scene"
    ) -> "AbstractMaterial":
        """One material from a scene file's parameters; errors name `where`."""

    @abc.abstractmethod
    def bxdf(self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"]) -> AbstractBxDF:
        """The BxDF of row `row[i]` at the wavelengths `wavelength_nm[i]` [nm] of path `i`.

        A plugin whose parameters may be textures (`USES_UV`) takes a third argument, `uv`:
        `(n, 2)` surface coordinates of the hits [1], or `None`."""

    @property
    def n_rows(self) -> int:
        """Number of materials (rows) held."""
        return int(self.two_sided.shape[0])

    @property
    def needs_geometry(self) -> bool:
        """Whether `bxdf` needs the hits' `HitGeometry` (static: from the plugin's kind)."""
        return self.USES_GEOMETRY

    @property
    def tangent_frame(self) -> bool:
        """Whether some row's BxDF is anisotropic (its lobe turns about the normal), so that
        the shading frame's tangent must follow dp/du, as Mitsuba's does. Read from the
        concrete parameters when a `MaterialSet` is built (outside `jit`); False here."""
        return False

    @property
    def transmissive_rows(self) -> Bool[Array, " m"]:
        """`(m,)` bool, rows that transmit (`TRANSMISSIVE` for every row, unless a plugin
        such as a blend of materials decides per row)."""
        return jnp.full(self.two_sided.shape, self.TRANSMISSIVE, bool)


def concatenate(materials: "list[AbstractMaterial]") -> AbstractMaterial:
    """Materials of one kind as one plugin, their rows in order."""
    kinds = {type(m) for m in materials}
    if len(kinds) != 1:
        raise TypeError(f"can only concatenate materials of one kind, got {kinds}.")
    if len(materials) == 1:
        return materials[0]
    kind = kinds.pop()
    if hasattr(kind, "concatenate_rows"):  # composite materials join their nested sets
        return kind.concatenate_rows(materials)

    def join(*xs):
        if isinstance(xs[0], AbstractTexture):  # textures of different kinds: a stack
            return concatenate_textures(list(xs))
        return jnp.concatenate(xs, axis=0)

    return jax.tree.map(join, *materials, is_leaf=lambda x: isinstance(x, AbstractTexture))


def unknown_parameters(params: Properties, cls: type, where: str) -> None:
    """Reject parameters the plugin does not know (nothing is silently ignored)."""
    unknown = sorted(set(params) - cls.PARAMETERS)
    if unknown:
        raise ValueError(
            f"{where}: unsupported parameter(s) {unknown} of the {cls.NAME!r} BSDF; supported: "
            f"{sorted(cls.PARAMETERS)}."
        )


def scalar(params: Properties, name: str, default: float, where: str) -> float:
    """A plain number parameter (`alpha`, ...)."""
    value = params.get(name, default)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{where}: parameter {name!r} must be a number, got {value!r}.")
    return float(value)


class ScaledBxDF(AbstractBxDF):
    """A BxDF whose reflected and transmitted values are scaled by spectral factors.

    Mitsuba's `specular_reflectance` and `specular_transmittance` parameters: `f` is
    multiplied by `reflection` where `wo` and `wi` lie on one side, by `transmission`
    otherwise; sampling and densities are the base BxDF's (the factors are not importance
    sampled, as in Mitsuba).

    !!! note "Thesis"
        Eq. 3.4 (the BxDF), section 3.1.1 (reflected and transmitted parts).

    ??? cite "References"
        `Jakob2022` (`specular_reflectance`, `specular_transmittance`).
    """

    base: AbstractBxDF
    reflection: Float[Array, "n k"]
    transmission: Float[Array, "n k"]

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        reflection = (wo[..., 2] * wi[..., 2] > 0)[..., None]
        scale = jnp.where(reflection, self.reflection, self.transmission)
        return self.base.f(wo, wi, mode=mode) * scale

    def pdf(self, wo, wi) -> Array:
        return self.base.pdf(wo, wi)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        s = self.base.sample_f(wo, u_lobe, u2, mode=mode)
        scale = jnp.where(s.is_transmission[..., None], self.transmission, self.reflection)
        return eqx.tree_at(lambda x: x.f, s, s.f * scale)


def parameters_differ(a, b) -> bool:
    """Whether two parameter pytrees (textures) differ in structure or in any concrete value;
    True when they are not concrete (traced), so that the caller keeps the general path."""
    if jax.tree.structure(a) != jax.tree.structure(b):
        return True
    try:
        return any(
            np.shape(x) != np.shape(y) or not np.array_equal(np.asarray(x), np.asarray(y))
            for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b), strict=True)
        )
    except (TypeError, jax.errors.TracerArrayConversionError):
        return True


def parameter_nonzero(a) -> bool:
    """Whether a parameter pytree (a texture) holds any nonzero value (True when traced)."""
    try:
        return any(np.any(np.asarray(x) != 0) for x in jax.tree.leaves(a))
    except (TypeError, jax.errors.TracerArrayConversionError):
        return True
