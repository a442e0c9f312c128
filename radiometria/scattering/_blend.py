r"""Mixtures of BxDFs: a linear blend of two (Mitsuba 3's `blendbsdf`) and a partly transparent
surface (`mask`), with one-sample lobe selection.

Both choose a component with the probability of its weight, sample it, and report for a
non-delta sample the mixture's own value and density at the sampled direction (one-sample
MIS over the components, so `sample_f`, `f` and `pdf` stay consistent for the integrators'
MIS); a delta sample keeps the component's value and discrete probability, each scaled by the
component's weight. The expected sample weight is that of the mixture, as in Mitsuba.
"""

import jax
import jax.numpy as jnp
from jax import Array

from .._checks import as_float_array, check_in_range
from .._math import safe_div
from ._bxdfs import AbstractBxDF, BSDFSample, _dirs

__all__ = ["BlendBxDF", "MaskBxDF"]

_ONE_MINUS = 1.0 - 2.0**-24  # keep rescaled variates in [0, 1) in float32


def _rescale(u: Array, lo: Array | float, width: Array | float) -> Array:
    """(u - lo) / width clipped to [0, 1): the variate reused inside the chosen component."""
    return jnp.clip(safe_div(u - lo, width), 0.0, _ONE_MINUS)


def _active(one_sided: Array, wo: Array) -> Array:
    """1 where the component scatters, else 0 (in `wo`'s dtype): a one-sided component scatters
    only for wo on the side of the normal (+z)."""
    return (~(one_sided & (wo[..., 2] < 0))).astype(wo.dtype)


def _select(mask: Array, a: BSDFSample, b: BSDFSample) -> BSDFSample:
    """`a` where `mask`, else `b`, field by field."""

    def pick(x, y):
        x, y = jnp.broadcast_arrays(x, y)
        m = jnp.reshape(mask, mask.shape + (1,) * (x.ndim - mask.ndim))
        return jnp.where(jnp.broadcast_to(m, x.shape), x, y)

    return jax.tree.map(pick, a, b)


def _with(s: BSDFSample, f: Array, pdf: Array, ok: Array) -> BSDFSample:
    return BSDFSample(
        f=jnp.where(ok[..., None], f, 0.0),
        wi=s.wi,
        pdf=jnp.where(ok, pdf, 0.0),
        is_delta=s.is_delta,
        is_transmission=s.is_transmission & ok,
        eta=jnp.where(ok, s.eta, 1.0),
        terminate_secondary=s.terminate_secondary & ok,
    )


class BlendBxDF(AbstractBxDF):
    r"""Linear blend $f = (1 - w) f_0 + w f_1$ of two BxDFs (Mitsuba's `blendbsdf`).

    `pdf` is $(1 - w) p_0 + w p_1$; `sample_f` picks $f_1$ with probability $w$ (the variate
    `u_lobe` rescaled and passed on) and reports the mixture at the sampled direction (module
    notes).

    **Fields:**

    - `first`, `second`: the BxDFs $f_0$ and $f_1$.
    - `weight`: $w$ in [0, 1], `(...)`: 0 gives `first`, 1 gives `second`. [dimensionless]
    - `first_one_sided`, `second_one_sided`: `(...)` bool; such a component scatters only for
        `wo` on +z (Mitsuba's one-sided BSDFs inside a blend that transmits). Default False.

    ??? cite "References"
        `Jakob2022` (`blendbsdf`); `Veach1997` §9.2 (one-sample model).
    """

    first: AbstractBxDF
    second: AbstractBxDF
    weight: Array
    first_one_sided: Array
    second_one_sided: Array

    def __init__(self, first, second, weight, first_one_sided=False, second_one_sided=False):
        if not isinstance(first, AbstractBxDF) or not isinstance(second, AbstractBxDF):
            raise TypeError("`first` and `second` must be BxDFs (subclasses of AbstractBxDF).")
        self.first, self.second = first, second
        w = as_float_array(weight, "weight")
        self.weight = check_in_range(w, "weight", 0.0, 1.0, unit="dimensionless")
        self.first_one_sided = jnp.asarray(first_one_sided, bool)
        self.second_one_sided = jnp.asarray(second_one_sided, bool)

    def _weights(self, wo):
        w = self.weight
        return (1.0 - w) * _active(self.first_one_sided, wo), w * _active(self.second_one_sided, wo)

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        a, b = self._weights(wo)
        f0, f1 = self.first.f(wo, wi, mode=mode), self.second.f(wo, wi, mode=mode)
        return a[..., None] * f0 + b[..., None] * f1

    def pdf(self, wo, wi) -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        a, b = self._weights(wo)
        return a * self.first.pdf(wo, wi) + b * self.second.pdf(wo, wi)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        w = self.weight
        second = u_lobe < w
        s0 = self.first.sample_f(wo, _rescale(u_lobe, w, 1.0 - w), u2, mode=mode)
        s1 = self.second.sample_f(wo, _rescale(u_lobe, 0.0, w), u2, mode=mode)
        s = _select(second, s1, s0)
        a, b = self._weights(wo)
        scale = jnp.where(second, b, a)
        chosen = jnp.where(second, w, 1.0 - w)
        f = jnp.where(s.is_delta[..., None], scale[..., None] * s.f, self.f(wo, s.wi, mode=mode))
        pdf = jnp.where(s.is_delta, chosen * s.pdf, self.pdf(wo, s.wi))
        return _with(s, f, pdf, (s.pdf > 0) & (scale > 0))


class MaskBxDF(AbstractBxDF):
    r"""A partly transparent surface (Mitsuba's `mask`): $f = \alpha f_n$ plus straight
    transmission, $(1 - \alpha)\,\delta(\omega_i + \omega_o)/|\cos\theta_i|$, as Mitsuba's
    `null`.

    `pdf` is $\alpha p_n$ (the pass-through is a delta lobe); `sample_f` passes through with
    probability $1 - \alpha$ (`is_delta`, `is_transmission`, `eta = 1`, weight 1) and otherwise
    samples the nested BxDF (module notes).

    **Fields:**

    - `nested`: the BxDF of the opaque part.
    - `opacity`: $\alpha$ in [0, 1], `(...)`. [dimensionless]
    - `nested_one_sided`: `(...)` bool; a one-sided nested BxDF scatters only for `wo` on +z
        (from behind, only the pass-through remains, as in Mitsuba). Default False.

    ??? cite "References"
        `Jakob2022` (`mask`, `null`).
    """

    nested: AbstractBxDF
    opacity: Array
    nested_one_sided: Array

    def __init__(self, nested, opacity, nested_one_sided=False):
        if not isinstance(nested, AbstractBxDF):
            raise TypeError("`nested` must be a BxDF (a subclass of AbstractBxDF).")
        self.nested = nested
        a = as_float_array(opacity, "opacity")
        self.opacity = check_in_range(a, "opacity", 0.0, 1.0, unit="dimensionless")
        self.nested_one_sided = jnp.asarray(nested_one_sided, bool)

    def _alpha(self, wo):
        return self.opacity * _active(self.nested_one_sided, wo)

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        return self._alpha(wo)[..., None] * self.nested.f(wo, wi, mode=mode)

    def pdf(self, wo, wi) -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        return self._alpha(wo) * self.nested.pdf(wo, wi)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        a = self.opacity
        nested = u_lobe < a
        s = self.nested.sample_f(wo, _rescale(u_lobe, 0.0, a), u2, mode=mode)
        alpha = self._alpha(wo)
        f = jnp.where(s.is_delta[..., None], alpha[..., None] * s.f, self.f(wo, s.wi, mode=mode))
        pdf = jnp.where(s.is_delta, a * s.pdf, self.pdf(wo, s.wi))
        s = _with(s, f, pdf, (s.pdf > 0) & (alpha > 0))
        c = jnp.abs(wo[..., 2])
        one = jnp.ones(c.shape, s.pdf.dtype)
        through = BSDFSample(
            f=jnp.broadcast_to(safe_div(1.0 - a, c)[..., None], s.f.shape),
            wi=jnp.broadcast_to(-wo, s.wi.shape),
            pdf=jnp.where(c > 0, 1.0 - a, 0.0) * one,
            is_delta=jnp.ones(c.shape, bool),
            is_transmission=c > 0,
            eta=one,
            terminate_secondary=jnp.zeros(c.shape, bool),
        )
        return _select(nested, s, through)
