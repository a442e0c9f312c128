r"""Mitsuba's `normalmap` and `bumpmap`: a nested material seen in a perturbed shading frame.

Both hold their nested material as a composite does (`_composite`: a `MaterialSet` of
children and per-row indices) and an image per row (`RawImage`, numbers rather than spectra).
At a hit the integrator passes the hit's `HitGeometry` (the surface's partial derivatives
$\partial p/\partial u$, $\partial p/\partial v$ and the geometric normal, in its local
shading frame, whose tangent is $\partial p/\partial u$ made orthogonal to the shading normal,
as Mitsuba's); the plugin computes the perturbed normal $m$ and wraps the nested BxDF in
`PerturbedBxDF`, which evaluates it in a frame around $m$.

- normal map: $m = \mathrm{normalize}(2\,\mathrm{rgb} - 1)$ in the local frame (tangent
  space), the texels taken as stored (give the bitmap `raw=true`, as Mitsuba asks).
- bump map: with the height texture's uv gradient $g$ times `scale`,
  $p_u' = p_u + n\,(g_u - n \cdot p_u)$, $p_v'$ likewise, $m = \mathrm{normalize}(p_u' \times
  p_v')$, flipped to the geometric normal's side.

The BxDF in the perturbed frame has the value $f(m\text{-frame}) \cos\theta_m / \cos\theta$
(the integrators multiply by the cosine to their own normal) and is zero where the incident
direction lies on different sides of the two normals, as in Mitsuba.

Such a BxDF is not reciprocal (the frame follows $\omega_o$, the cosine ratio and the
shadowing term follow $\omega_i$), so light paths (`ptracer`, `bdpt`, `pssmlt`) scatter by
its adjoint $f^*(\omega_o, \omega_i) = f(\omega_i, \omega_o)$ (`mode="importance"`,
`Veach1997` §3.7.6) and estimate the path tracer's image. Mitsuba 3.9's `ptracer` evaluates the
adjoint as the radiance mode instead: on the normal- and bump-mapped test scene (box filter)
its image is 5.6 % darker than its own `path`'s, which it matches without the maps.
"""

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ..._math import dot, safe_div
from ...scattering import AbstractBxDF, BSDFSample
from .._spectral import RGB_LUMINANCE
from .._textures import RawImage, TextureSpec
from ._base import AbstractMaterial, Properties, scalar, unknown_parameters
from ._composite import _nested
from ._set import MaterialSet

__all__ = ["BumpMap", "HitGeometry", "NormalMap", "PerturbedBxDF"]


class HitGeometry(eqx.Module):
    """Differential geometry of surface hits in the integrator's local shading frame.

    **Fields:**

    - `dpdu`, `dpdv`: `(n, 3)` partial derivatives of the surface point [scene units per uv
        unit].
    - `normal`: `(n, 3)` unit geometric normal, on the side of the local +z.
    """

    dpdu: Float[Array, "n 3"]
    dpdv: Float[Array, "n 3"]
    normal: Float[Array, "n 3"]


def _normalize(v):
    length = jnp.sqrt(dot(v, v))[..., None]
    return jnp.where(length > 0, v / jnp.where(length > 0, length, 1.0), 0.0)


class PerturbedBxDF(AbstractBxDF):
    r"""A BxDF evaluated in a frame around a perturbed normal `n` (local coordinates) instead
    of +z, as Mitsuba 3's `normalmap`/`bumpmap` (module notes).

    With `flip_invalid`, a normal facing away from `wo` is mirrored to `(-n_x, -n_y, n_z)`
    (`Schuessler2017`); the frame is `m` with tangent +x made orthogonal to it. With
    `shadowing`, values carry the microfacet shadowing term of `Estevez2019`,
    $G = 2 / (1 + \sqrt{1 + \alpha^2 \tan^2\theta_i})$ with
    $\alpha^2 = \min(\tan^2\theta_m / 8, 1)$ (densities do not).

    **Fields:**

    - `nested`: the BxDF.
    - `n`: `(n, 3)` perturbed normal in local coordinates (any length > 0).
    - `flip_invalid`, `shadowing`: `(n,)` bool, Mitsuba's `flip_invalid_normals` and
        `use_shadowing_function` (both default true).
    """

    nested: AbstractBxDF
    n: Float[Array, "n 3"]
    flip_invalid: Bool[Array, " n"]
    shadowing: Bool[Array, " n"]

    def _frame(self, wo):
        n = self.n
        flip = self.flip_invalid & (wo[..., 2] * dot(wo, n) <= 0)
        n = jnp.where(flip[..., None], jnp.concatenate([-n[..., :2], n[..., 2:]], axis=-1), n)
        m = _normalize(n)
        m = jnp.where((dot(m, m) > 0)[..., None], m, jnp.zeros_like(m).at[..., 2].set(1.0))
        s = jnp.zeros_like(m).at[..., 0].set(1.0) - m * m[..., 0:1]
        s_len = jnp.sqrt(dot(s, s))[..., None]
        s = jnp.where(s_len > 0, s / jnp.where(s_len > 0, s_len, 1.0),
                      jnp.zeros_like(m).at[..., 1].set(1.0))  # fmt: skip
        return s, jnp.cross(m, s), m

    @staticmethod
    def _to(frame, w):
        s, t, m = frame
        return jnp.stack([dot(w, s), dot(w, t), dot(w, m)], axis=-1)

    @staticmethod
    def _from(frame, w):
        s, t, m = frame
        return w[..., 0:1] * s + w[..., 1:2] * t + w[..., 2:3] * m

    def _terminator(self, m, wi):
        def tan2(v):
            c2 = v[..., 2] ** 2
            return safe_div(jnp.maximum(1.0 - c2, 0.0), c2)

        alpha2 = jnp.minimum(0.125 * tan2(m), 1.0)
        g = 2.0 / (1.0 + jnp.sqrt(1.0 + alpha2 * tan2(wi)))
        return jnp.where(self.shadowing, g, 1.0)

    def _value(self, frame, wo, wi, cos_side, mode):
        """The value for a frame: the nested BxDF in it, times the ratio of the cosines of
        `cos_side` (the direction whose cosine the integrator applies in the path-tracing
        sense) to the perturbed and the unperturbed normal and its shadowing term; zero where
        that direction lies on different sides of the two normals."""
        side_m = self._to(frame, cos_side)
        ok = cos_side[..., 2] * side_m[..., 2] > 0
        scale = safe_div(jnp.abs(side_m[..., 2]), jnp.abs(cos_side[..., 2]))
        scale = jnp.where(ok, scale * self._terminator(frame[2], cos_side), 0.0)
        return self.nested.f(self._to(frame, wo), self._to(frame, wi), mode=mode) * scale[..., None]

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        if mode == "importance":
            # The adjoint f*(wo, wi) = f(wi, wo) (Veach1997 §3.7.6): the frame follows the
            # camera side `wi`, the cosine ratio and shadowing the light side `wo`. A normal
            # map is not reciprocal, so evaluating it as in radiance mode (Mitsuba's ptracer)
            # would estimate another image than the path tracer's.
            return self._value(self._frame(wi), wo, wi, wo, mode)
        return self._value(self._frame(wo), wo, wi, wi, mode)

    def pdf(self, wo, wi) -> Array:
        # The density of `sample_f` in either mode: the frame follows the given direction.
        frame = self._frame(wo)
        wi_m = self._to(frame, wi)
        ok = wi[..., 2] * wi_m[..., 2] > 0
        return jnp.where(ok, self.nested.pdf(self._to(frame, wo), wi_m), 0.0)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        """Samples the nested BxDF in the frame around the normal perturbed for `wo` (in
        importance mode too, where the adjoint's frame would follow the unknown sampled
        direction: `pdf` is this sampler's density, and `f` is the adjoint's value)."""
        frame = self._frame(wo)
        s = self.nested.sample_f(self._to(frame, wo), u_lobe, u2, mode=mode)
        wi = self._from(frame, s.wi)
        ok = (wi[..., 2] * s.wi[..., 2] > 0) & (s.pdf > 0)
        if mode == "importance":
            # the adjoint's value: for a delta lobe (zero under `f`) the sample's own weight
            # with this frame's cosine ratio, exact unless the frames of wo and wi differ by
            # a flipped normal; otherwise `f` itself, in the frame of the sampled direction
            w_m = self._to(frame, wo)
            scale = safe_div(jnp.abs(w_m[..., 2]), jnp.abs(wo[..., 2]))
            ok = ok & (wo[..., 2] * w_m[..., 2] > 0)
            delta = s.f * (scale * self._terminator(frame[2], wo))[..., None]
            value = jnp.where(s.is_delta[..., None], delta, self.f(wo, wi, mode=mode))
        else:
            scale = safe_div(jnp.abs(s.wi[..., 2]), jnp.abs(wi[..., 2]))
            value = s.f * (scale * self._terminator(frame[2], wi))[..., None]
        return BSDFSample(
            f=jnp.where(ok[..., None], value, 0.0), wi=wi, pdf=jnp.where(ok, s.pdf, 0.0),
            is_delta=s.is_delta, is_transmission=s.is_transmission & ok,
            eta=jnp.where(ok, s.eta, 1.0), terminate_secondary=s.terminate_secondary & ok,
        )  # fmt: skip


def _image(value, name: str, where: str, grey: bool) -> RawImage:
    if not isinstance(value, TextureSpec) or value.type != "bitmap":
        raise ValueError(f"{where}: parameter {name!r} must be a bitmap texture, got {value!r}.")
    rgb = np.asarray(value.rgb, np.float64)
    values = (rgb @ RGB_LUMINANCE)[..., None] if grey else rgb
    return RawImage.from_array(
        values, filter_type=value.filter_type, wrap_mode=value.wrap_mode, to_uv=value.to_uv
    )


def _flags(params: Properties, where: str) -> dict:
    out = {}
    for name, field in (("flip_invalid_normals", "flip_invalid"),
                        ("use_shadowing_function", "shadowing")):  # fmt: skip
        value = params.get(name, True)
        if not isinstance(value, bool):
            raise ValueError(f"{where}: parameter {name!r} must be a boolean, got {value!r}.")
        out[field] = device_array([value], bool)
    return out


def _lookup(images: tuple, part: Array, uv, method: str):
    out = getattr(images[0], method)(uv)
    for i, img in enumerate(images[1:], start=1):
        out = jnp.where((part == i).reshape(part.shape + (1,) * (out.ndim - 1)),
                        getattr(img, method)(uv), out)  # fmt: skip
    return out


class _Adapter(AbstractMaterial):
    """What the normal- and bump-map plugins share: nested material, images, rows."""

    USES_UV: ClassVar[bool] = True
    USES_GEOMETRY: ClassVar[bool] = True
    children: eqx.AbstractVar[MaterialSet]
    nested: eqx.AbstractVar[Int[Array, " m"]]
    images: eqx.AbstractVar[tuple]
    image_of: eqx.AbstractVar[Int[Array, " m"]]
    two_sided: eqx.AbstractVar[Bool[Array, " m"]]

    @property
    def transmissive_rows(self):
        return self.children.transmissive[self.nested]

    def _nested_bxdf(self, row, wavelength_nm, uv, geometry):
        if geometry is None:
            raise ValueError(
                f"the {self.NAME!r} BSDF needs the hits' differential geometry, which was not "
                "passed (every built-in integrator passes it; a plugin integrator passes the "
                "`geometry` of its `shading_frame`: docs/extending.md)."
            )
        if uv is None:
            uv = jnp.zeros(wavelength_nm.shape[:-1] + (2,), wavelength_nm.dtype)
        return self.children.bxdf(self.nested[row], wavelength_nm, uv, geometry), uv

    @classmethod
    def concatenate_rows(cls, materials):
        children, offsets = MaterialSet.join([m.children for m in materials])
        images, image_of = [], []
        for m in materials:
            image_of.append(m.image_of + len(images))
            images += list(m.images)
        extra = {k: jnp.concatenate([getattr(m, k) for m in materials]) for k in cls._ROWS}
        return cls(
            children=children,
            nested=jnp.concatenate([m.nested + o for m, o in zip(materials, offsets, strict=True)]),
            images=tuple(images), image_of=jnp.concatenate(image_of),
            two_sided=jnp.concatenate([m.two_sided for m in materials]), **extra,
        )  # fmt: skip


class NormalMap(_Adapter):
    r"""Mitsuba's `normalmap`: the nested material with its shading normal taken from an RGB
    image in tangent space, $m = \mathrm{normalize}(2\,\mathrm{rgb} - 1)$ (module notes).

    **Fields:**

    - `children`, `nested`: the nested materials and each row's index into them.
    - `images`: the normal maps (`RawImage`, RGB); `image_of`: `(m,)` each row's image.
    - `two_sided`: `(m,)` bool.

    !!! note "Thesis"
        Eq. 3.4 (a BSDF in a shading frame).

    ??? cite "References"
        `Jakob2022` (`normalmap`); `Pharr2023` §10.5.3 (normal mapping).
    """

    NAME: ClassVar[str] = "normalmap"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"normalmap", "bsdf_0", "flip_invalid_normals", "use_shadowing_function"}
    )
    _ROWS: ClassVar[tuple] = ("flip_invalid", "shadowing")
    children: MaterialSet
    nested: Int[Array, " m"]
    images: tuple
    image_of: Int[Array, " m"]
    flip_invalid: Bool[Array, " m"]
    shadowing: Bool[Array, " m"]
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        unknown_parameters(params, cls, where)
        if "normalmap" not in params:
            raise ValueError(f"{where}: the 'normalmap' BSDF needs a 'normalmap' texture.")
        image = _image(params["normalmap"], "normalmap", where, grey=False)
        (child,) = _nested(params, ("bsdf_0",), cls.NAME, where)
        return cls(
            children=MaterialSet.from_materials([child]), nested=jnp.zeros(1, jnp.int32),
            images=(image,), image_of=jnp.zeros(1, jnp.int32),
            two_sided=device_array([two_sided], bool), **_flags(params, where),
        )  # fmt: skip

    def bxdf(self, row, wavelength_nm, uv=None, geometry=None):
        nested, uv = self._nested_bxdf(row, wavelength_nm, uv, geometry)
        rgb = _lookup(self.images, self.image_of[row], uv, "__call__")
        n = 2.0 * rgb.astype(wavelength_nm.dtype) - 1.0
        return PerturbedBxDF(nested, n, self.flip_invalid[row], self.shadowing[row])


class BumpMap(_Adapter):
    r"""Mitsuba's `bumpmap`: the nested material with its shading normal tilted by the uv
    gradient of a height texture times `scale` (module notes).

    **Fields:**

    - `children`, `nested`: the nested materials and each row's index into them.
    - `images`: the height maps (`RawImage`, one channel: the texels' luminance);
        `image_of`: `(m,)` each row's image.
    - `scale`: `(m,)` factor on the gradient (Mitsuba's `scale`, default 1) [scene units].
    - `two_sided`: `(m,)` bool.

    !!! note "Thesis"
        Eq. 3.4 (a BSDF in a shading frame).

    ??? cite "References"
        `Jakob2022` (`bumpmap`); `Blinn1978`; `Pharr2023` §10.5.2 (bump mapping).
    """

    NAME: ClassVar[str] = "bumpmap"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"texture", "scale", "bsdf_0", "flip_invalid_normals", "use_shadowing_function"}
    )
    _ROWS: ClassVar[tuple] = ("scale", "flip_invalid", "shadowing")
    children: MaterialSet
    nested: Int[Array, " m"]
    images: tuple
    image_of: Int[Array, " m"]
    scale: Float[Array, " m"]
    flip_invalid: Bool[Array, " m"]
    shadowing: Bool[Array, " m"]
    two_sided: Bool[Array, " m"]

    @classmethod
    def from_properties(cls, params: Properties, *, two_sided=False, where="scene"):
        unknown_parameters(params, cls, where)
        if "texture" not in params:
            raise ValueError(f"{where}: the 'bumpmap' BSDF needs a nested height <texture>.")
        image = _image(params["texture"], "texture", where, grey=True)
        (child,) = _nested(params, ("bsdf_0",), cls.NAME, where)
        return cls(
            children=MaterialSet.from_materials([child]), nested=jnp.zeros(1, jnp.int32),
            images=(image,), image_of=jnp.zeros(1, jnp.int32),
            scale=device_array([scalar(params, "scale", 1.0, where)], jnp.float32),
            two_sided=device_array([two_sided], bool), **_flags(params, where),
        )  # fmt: skip

    def bxdf(self, row, wavelength_nm, uv=None, geometry=None):
        nested, uv = self._nested_bxdf(row, wavelength_nm, uv, geometry)
        g = _lookup(self.images, self.image_of[row], uv, "grad")[..., 0, :]
        g = (g * self.scale[row][..., None]).astype(wavelength_nm.dtype)
        dpdu = geometry.dpdu.at[..., 2].set(g[..., 0])
        dpdv = geometry.dpdv.at[..., 2].set(g[..., 1])
        n = jnp.cross(dpdu, dpdv)
        n = jnp.where((dot(n, geometry.normal) < 0)[..., None], -n, n)
        return PerturbedBxDF(nested, n, self.flip_invalid[row], self.shadowing[row])
