"""Mitsuba's composite BSDFs, `blendbsdf` and `mask`: materials made of other materials.

**Design.** A composite plugin holds its nested materials as a `MaterialSet` of its own
(`children`) and, per row, the indices of its children in that set (`first`, `second`, or
`nested`). Its BxDF at a hit is built from the children's BxDFs, which the child set selects
per path exactly as the scene's set does for top-level materials, so any kind may be nested
(a composite in a composite too). Rows of one composite kind concatenate by joining their
child sets (`MaterialSet.join`), so a scene with many blends still has one plugin per kind.
The scene loader builds the nested plugins with the registry and passes them to
`from_properties` as the parameters `bsdf_0`, `bsdf_1` (the material floor never sees the
registry). Scalar parameters that may be textures (`weight`, `opacity`) are grey textures
evaluated at the hit's uv.
"""

from typing import ClassVar

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ...scattering import BlendBxDF, MaskBxDF
from ...upsampling import RGBAlbedoSpectrum
from .._spectral import RGB_LUMINANCE, LinearRGB
from .._textures import (
    AbstractTexture,
    ConstantTexture,
    MeshAttributeTexture,
    TextureSpec,
    concatenate_textures,
    texture_parameter,
)
from ._base import AbstractMaterial, Properties, unknown_parameters
from ._set import MaterialSet

__all__ = ["BlendBSDF", "Mask", "scalar_texture"]


def scalar_texture(
    value, name: str, where: str, *, lower: float = 0.0, upper: float = 1.0
) -> AbstractTexture:
    """A one-row grey texture of a scalar parameter given as a number or a `TextureSpec`
    (Mitsuba's `eval_1`): colour texels and colours become their luminance (Rec. 709 Y), so
    the texture's spectrum is flat and its first wavelength's value is the parameter.
    Numbers must lie in `[lower, upper]`. A checkerboard's colours swap places, as in
    Mitsuba 3's scalar checkerboard lookup. A mesh attribute's colours become their
    luminance too (`MeshAttributeTexture`'s `"scalar"` kind)."""
    if isinstance(value, TextureSpec):
        if value.type == "mesh_attribute":
            return MeshAttributeTexture.from_name(value.attribute, None, value.scale)
        if value.type == "bitmap":
            y = np.clip(value.rgb @ RGB_LUMINANCE, lower, upper)
            value = TextureSpec(
                "bitmap", rgb=np.repeat(y[..., None], 3, axis=2), filter_type=value.filter_type,
                wrap_mode=value.wrap_mode, to_uv=value.to_uv, where=value.where,
            )  # fmt: skip
        else:
            colors = tuple(
                float(c.rgb @ RGB_LUMINANCE) if isinstance(c, LinearRGB) else c
                for c in value.colors
            )
            for c in colors:
                if not isinstance(c, float) or not lower <= c <= upper:
                    raise ValueError(
                        f"{where}: parameter {name!r}: checkerboard colours must be numbers in "
                        f"[{lower}, {upper}], got {c!r}."
                    )
            # Mitsuba 3's checkerboard `eval_1` (a scalar lookup) gives `color1` where its
            # spectral `eval` gives `color0` and vice versa (checked against Mitsuba in the
            # tests); scalar checkerboards follow it, so scenes render as in Mitsuba.
            value = TextureSpec(
                "checkerboard", colors=colors[::-1], to_uv=value.to_uv, where=value.where
            )
        return texture_parameter(value, RGBAlbedoSpectrum, name, where)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(
            f"{where}: parameter {name!r} must be a number or a texture, got {value!r}."
        )
    if not lower <= value <= upper:
        raise ValueError(
            f"{where}: parameter {name!r} must lie in [{lower}, {upper}], got {value}."
        )
    return ConstantTexture.from_values([float(value)], RGBAlbedoSpectrum)


def _nested(params: Properties, names: tuple[str, ...], kind: str, where: str) -> list:
    children = [params.get(n) for n in names]
    if not all(isinstance(c, AbstractMaterial) for c in children):
        raise ValueError(
            f"{where}: the {kind!r} BSDF needs {len(names)} nested BSDF(s) (<bsdf> or <ref>), "
            f"got {sum(isinstance(c, AbstractMaterial) for c in children)}."
        )
    for c in children:
        if c.n_rows != 1:
            raise ValueError(f"{where}: a nested BSDF must be one material, got {c.n_rows} rows.")
    return children


def _one_sided(children: MaterialSet, index: Array) -> Array:
    """Whether the child reflects on its front side only (a one-sided, opaque material)."""
    return ~children.two_sided[index] & ~children.transmissive[index]


class BlendBSDF(AbstractMaterial):
    r"""A linear blend of two materials (Mitsuba's `blendbsdf`):
    $f = (1 - w) f_0 + w f_1$ (`radiometria.scattering.BlendBxDF`).

    **Fields:**

    - `children`: the nested materials of every row (module notes).
    - `first`, `second`: `(m,)` int32, each row's two children in `children`.
    - `weight`: grey texture of $w$ in [0, 1] (a number or a texture; Mitsuba requires it).
        [1]
    - `two_sided`: `(m,)` bool (Mitsuba's `twosided` may wrap a blend that does not transmit).
    - `transmits`: `(m,)` bool, rows with a transmitting child.

    !!! note "Thesis"
        Eq. 3.4 (a BSDF; a convex combination of BSDFs is one).

    ??? cite "References"
        `Jakob2022` (`blendbsdf`); `Veach1997` §9.2.
    """

    NAME: ClassVar[str] = "blendbsdf"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"weight", "bsdf_0", "bsdf_1"})
    USES_UV: ClassVar[bool] = True
    USES_GEOMETRY: ClassVar[bool] = True  # passed on to the nested materials
    children: MaterialSet
    first: Int[Array, " m"]
    second: Int[Array, " m"]
    weight: AbstractTexture
    two_sided: Bool[Array, " m"]
    transmits: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        unknown_parameters(params, cls, where)
        if "weight" not in params:
            raise ValueError(f"{where}: the 'blendbsdf' BSDF needs a 'weight' (as in Mitsuba).")
        weight = scalar_texture(params["weight"], "weight", where)
        a, b = _nested(params, ("bsdf_0", "bsdf_1"), cls.NAME, where)
        children = MaterialSet.from_materials([a, b])
        transmits = bool(np.any(np.asarray(children.transmissive)))
        if two_sided and transmits:
            raise ValueError(
                f"{where}: a two-sided blend cannot have a transmitting child (Mitsuba's rule: "
                "twosided nests only materials without transmission)."
            )
        return cls(
            children, device_array([0], jnp.int32), device_array([1], jnp.int32), weight,
            device_array([two_sided], bool), device_array([transmits], bool),
        )  # fmt: skip

    @classmethod
    def concatenate_rows(cls, materials: "list[BlendBSDF]") -> "BlendBSDF":
        children, offsets = MaterialSet.join([m.children for m in materials])
        return cls(
            children,
            jnp.concatenate([m.first + o for m, o in zip(materials, offsets, strict=True)]),
            jnp.concatenate([m.second + o for m, o in zip(materials, offsets, strict=True)]),
            concatenate_textures([m.weight for m in materials]),
            jnp.concatenate([m.two_sided for m in materials]),
            jnp.concatenate([m.transmits for m in materials]),
        )

    @property
    def transmissive_rows(self) -> Bool[Array, " m"]:
        return self.transmits

    @property
    def needs_geometry(self) -> bool:
        return self.children.needs_geometry

    @property
    def tangent_frame(self) -> bool:
        return self.children.tangent_frame

    def bxdf(
        self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"], uv=None, geometry=None
    ):
        first, second = self.first[row], self.second[row]
        w = jnp.clip(self.weight(row, wavelength_nm, uv)[..., 0], 0.0, 1.0)
        return BlendBxDF(
            self.children.bxdf(first, wavelength_nm, uv, geometry),
            self.children.bxdf(second, wavelength_nm, uv, geometry),
            w,
            _one_sided(self.children, first),
            _one_sided(self.children, second),
        )


class Mask(AbstractMaterial):
    r"""A partly transparent material (Mitsuba's `mask`): the nested material with
    probability `opacity`, else straight pass-through (a null interaction), for cut-outs such
    as leaves (`radiometria.scattering.MaskBxDF`).

    **Fields:**

    - `children`: the nested materials of every row (module notes).
    - `nested`: `(m,)` int32, each row's child in `children`.
    - `opacity`: grey texture of the opacity $\alpha$ in [0, 1] (default 0.5). [1]
    - `two_sided`: `(m,)` bool, always False (Mitsuba's `twosided` refuses a mask: it
        transmits; make the nested material two-sided instead).

    !!! note "Thesis"
        Eq. 3.4; chapter 9 (index-matched boundaries).

    ??? cite "References"
        `Jakob2022` (`mask`, `null`).
    """

    NAME: ClassVar[str] = "mask"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset({"opacity", "bsdf_0"})
    TRANSMISSIVE: ClassVar[bool] = True
    USES_UV: ClassVar[bool] = True
    USES_GEOMETRY: ClassVar[bool] = True  # passed on to the nested material
    children: MaterialSet
    nested: Int[Array, " m"]
    opacity: AbstractTexture
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        unknown_parameters(params, cls, where)
        if two_sided:
            raise ValueError(
                f"{where}: a mask transmits, so it cannot be two-sided (Mitsuba's rule); make "
                "its nested BSDF two-sided instead."
            )
        opacity = scalar_texture(params.get("opacity", 0.5), "opacity", where)
        (child,) = _nested(params, ("bsdf_0",), cls.NAME, where)
        return cls(
            MaterialSet.from_materials([child]), device_array([0], jnp.int32), opacity,
            device_array([False], bool),
        )  # fmt: skip

    @classmethod
    def concatenate_rows(cls, materials: "list[Mask]") -> "Mask":
        children, offsets = MaterialSet.join([m.children for m in materials])
        return cls(
            children,
            jnp.concatenate([m.nested + o for m, o in zip(materials, offsets, strict=True)]),
            concatenate_textures([m.opacity for m in materials]),
            jnp.concatenate([m.two_sided for m in materials]),
        )

    @property
    def needs_geometry(self) -> bool:
        return self.children.needs_geometry

    @property
    def tangent_frame(self) -> bool:
        return self.children.tangent_frame

    def bxdf(
        self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"], uv=None, geometry=None
    ):
        nested = self.nested[row]
        a = jnp.clip(self.opacity(row, wavelength_nm, uv)[..., 0], 0.0, 1.0)
        return MaskBxDF(
            self.children.bxdf(nested, wavelength_nm, uv, geometry),
            a,
            _one_sided(self.children, nested),
        )
