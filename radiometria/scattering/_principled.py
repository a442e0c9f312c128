r"""The principled (Disney) BSDF as Mitsuba 3 implements it (`principled`).

Burley's artist-facing model (`Burley2012`, extended to transmission in `Burley2015`): a
sum of lobes, each weighted by the parameters, in the local shading frame (normal +z) with
`wo` towards the viewer and `wi` towards the light. With $h$ the (generalised) half vector
facing +z, $F_d$ the dielectric Fresnel reflectance at $\omega_o\cdot h$ (thesis eq. 3.18),
$w(\mu) = (1 - \mu)^5$ Schlick's weight, `brdf` $= (1 - m)(1 - s_t)$ and `bsdf` $= (1 - m)s_t$
($m$ metallic, $s_t$ spec_trans):

- *diffuse* (front side, reflection): $\mathrm{brdf}\,\frac{C}{\pi}\,[(1 - \tfrac12 w_o)
  (1 - \tfrac12 w_i) + R_r(w_o + w_i + w_ow_i(R_r - 1))]$, $R_r = 2\,r\,(h\cdot\omega_i)^2$
  (Burley's retro-reflection), blended by `flatness` with the Hanrahan-Krueger-like
  $1.25\,(F_{ss}(1/(\cos\theta_o + \cos\theta_i) - \tfrac12) + \tfrac12)$;
- *sheen*: $s\,(1 - m)\,w(h\cdot\omega_i)\,\mathrm{lerp}(1, C/Y, t_s)$, no $1/\pi$ (Mitsuba);
- *main specular reflection*: GGX with $\alpha = r^2$ (stretched by `anisotropic`),
  separable Smith masking, and Mitsuba's blended Fresnel
  $(1 - m)(1 - t)F_d + m\,F_S(C) + (1 - m)\,t\,F_S(R_0(\eta)\,C/Y)$ on the front side
  ($F_S$ Schlick's approximation, $t$ spec_tint, $Y$ the luminance of $C$) and
  $\mathrm{bsdf}\,F_d$ on the back side;
- *main specular transmission*: $\sqrt{C}\,\mathrm{bsdf}$ times Walter's rough dielectric
  transmission (`Walter2007`), with the radiance factor $1/\eta'^2$;
- *clearcoat* (front side): $\tfrac14 c\,F_S(0.04)\,D_{GTR1}(h)\,G_1G_1$ with the GTR1
  ("Berry") distribution of roughness $\mathrm{lerp}(0.1, 0.001, g)$ and separable GGX
  masking of roughness 0.25. Mitsuba keeps no $1/(4\cos\theta_o\cos\theta_i)$ on this lobe;
  neither do we, so that scenes render alike.

Lobes are sampled with Mitsuba's probabilities, from `wo`'s side and $F_d$ at the sampled
normal: front side $\propto$ diffuse $\mathrm{brdf}$, clearcoat $c/4$, transmission
$\mathrm{bsdf}(1 - F_d)$, reflection $1 - \mathrm{bsdf}(1 - F_d)$ (times the sampling rates);
back side: reflection $F_d$, transmission $1 - F_d$. GGX lobes sample visible normals
(`Heitz2018`), clearcoat the GTR1 normals, diffuse the cosine-weighted hemisphere; `pdf` is
the mixture, evaluated with the half vector of the pair.

Energy: the model is not energy conserving for every parameter set. The diffuse and sheen
lobes are added to the specular ones without a $(1 - F)$ factor, and Burley's retro-reflection
exceeds 1 at grazing angles for rough surfaces, so a white base (`base_color` = 1) can reflect
slightly more than it receives (e.g. $\approx 1.016$ at normal incidence, roughness 0, $\eta$ =
1.5). The metallic lobe alone, the dielectric (`spec_trans` = 1) alone in importance transport,
and the diffuse lobe at roughness 0 with $\eta$ = 1 are bounded by 1 (tested).
"""

from typing import ClassVar

import jax.numpy as jnp
from jax import Array

from .._checks import as_float_array, check_in_range
from .._math import safe_div, sincos_pi
from ._bxdfs import (
    AbstractBxDF,
    BSDFSample,
    _broadcast,
    _check_mode,
    _dirs,
    _failed_or,
    _sample_cosine_hemisphere,
    _spectral,
    _u2,
)
from ._directions import _stack3
from ._fresnel import _fr_dielectric_snell
from ._microfacet import TrowbridgeReitzDistribution

__all__ = ["PrincipledBxDF", "PrincipledThinBxDF", "principled_eta"]


def principled_eta(specular) -> Array:
    r"""Mitsuba's map from the `specular` parameter to the relative index of refraction:
    $\eta = 2/(1 - \sqrt{0.08\,s}) - 1$, the inverse of $R_0 = ((\eta - 1)/(\eta + 1))^2 =
    0.08\,s$ (Burley's "specular" is $R_0$ scaled so that 0.5 gives 4 %, $\eta$ = 1.5).

    **Arguments:**

    - `specular`: in [0, 1]. [dimensionless]

    **Returns:**

    $\eta \ge 1$. [dimensionless]

    ??? cite "References"
        `Burley2012`; `Jakob2022` (`principled`).
    """
    s = as_float_array(specular, "specular")
    return 2.0 / (1.0 - jnp.sqrt(0.08 * s)) - 1.0


def _schlick_weight(c: Array) -> Array:
    m = jnp.clip(1.0 - c, 0.0, 1.0)
    return (m * m) * (m * m) * m


def _schlick(r0: Array, cos: Array, eta: Array) -> Array:
    """Mitsuba's `calc_schlick`: Schlick's approximation with the transmitted cosine when the
    light leaves the denser side (`r0` may be spectral: `(..., k)`; `cos`, `eta`: `(...)`)."""
    outside = cos >= 0.0
    eta_it = jnp.where(outside, eta, 1.0 / eta)
    eta_ti = 1.0 / eta_it
    cos_t = jnp.sqrt(jnp.maximum(1.0 - (1.0 - cos * cos) * eta_ti * eta_ti, 0.0))
    w = jnp.where(eta_it > 1.0, _schlick_weight(jnp.abs(cos)), _schlick_weight(cos_t))
    if r0.ndim > w.ndim:
        w = w[..., None]
    return w * (1.0 - r0) + r0


def _gtr1_d(h_z: Array, alpha: Array) -> Array:
    """The GTR1 ("Berry") density of normals (`Burley2012`), 0 for h_z <= 0."""
    a2 = alpha * alpha
    d = (a2 - 1.0) / (jnp.pi * jnp.log(a2) * (1.0 + (a2 - 1.0) * h_z * h_z))
    return jnp.where(d * h_z > 1e-20, d, 0.0)


def _smith_g1_ggx(v: Array, h: Array, ax: "Array | float", ay: "Array | float") -> Array:
    """Separable Smith masking of GGX for one direction, with Mitsuba's orientation rule
    (a microfacet seen from its back masks everything)."""
    z = v[..., 2]
    xy = (ax * v[..., 0]) ** 2 + (ay * v[..., 1]) ** 2
    z2 = jnp.where(z != 0, z * z, 1.0)
    g = 2.0 / (1.0 + jnp.sqrt(1.0 + xy / z2))
    g = jnp.where(xy == 0.0, 1.0, g)
    return jnp.where(jnp.sum(v * h, axis=-1) * z <= 0.0, 0.0, g)


def _dot(a: Array, b: Array) -> Array:
    return jnp.sum(a * b, axis=-1)


def _normalize(v: Array) -> tuple[Array, Array]:
    n2 = jnp.sum(v * v, axis=-1, keepdims=True)
    ok = n2 > 0
    return v / jnp.sqrt(jnp.where(ok, n2, 1.0)), ok[..., 0]


class _AbstractPrincipled(AbstractBxDF):
    """The two principled BxDFs' shared parameter handling: checked fields, then every
    parameter broadcast against the directions at evaluation (`_params`)."""

    _SCALARS: ClassVar[tuple[str, ...]] = ()

    def _set(self, base_color, unit: dict, eta, luminance, rates: dict, **extra) -> None:
        """Check and store `base_color` (>= 0), the `unit` parameters (in [0, 1]), `eta`
        (> 0), `luminance` (default the mean of `base_color`), the sampling `rates` (>= 0) and
        `extra` fields given as `name=(value, upper bound)`."""
        c = _spectral(base_color, "base_color")
        self.base_color = check_in_range(c, "base_color", 0.0, jnp.inf)
        for name, value in unit.items():
            setattr(self, name, check_in_range(as_float_array(value, name), name, 0.0, 1.0))
        for name, (value, upper) in extra.items():
            setattr(self, name, check_in_range(as_float_array(value, name), name, 0.0, upper))
        e = as_float_array(eta, "eta")
        self.eta = check_in_range(e, "eta", 0.0, jnp.inf, closed_lower=False)
        lum = jnp.mean(self.base_color, axis=-1) if luminance is None else luminance
        self.luminance = as_float_array(lum, "luminance")
        for name, value in rates.items():
            setattr(self, name, check_in_range(as_float_array(value, name), name, 0.0, jnp.inf))

    def _params(self, *items):
        out = _broadcast(
            *items, (self.base_color, 1), *((getattr(self, n), 0) for n in self._SCALARS)
        )[1]
        k = len(items)
        return out[:k], dict(zip(("base_color", *self._SCALARS), out[k:], strict=True))


class PrincipledBxDF(_AbstractPrincipled):
    r"""The principled (Disney) BSDF, lobe for lobe as Mitsuba 3's `principled` (module notes).

    Not two-sided: the diffuse, sheen and clearcoat lobes live on the front (+z) side; from
    the back only the dielectric interface scatters (reflection $\mathrm{bsdf}\,F_d$ and
    transmission), so a surface with `spec_trans` = 0 is black from behind.

    **Fields** (batch shape `(...)`, broadcast against the directions):

    - `base_color`: $C$ in [0, 1], `(..., n_lambda)`. [dimensionless]
    - `roughness`, `anisotropic`, `metallic`, `spec_trans`, `spec_tint`, `sheen`,
        `sheen_tint`, `clearcoat`, `clearcoat_gloss`, `flatness`: in [0, 1], `(...)`.
        [dimensionless]
    - `eta`: relative index of refraction inside/outside, > 0, `(...)` (see `principled_eta`
        for Mitsuba's `specular`). [dimensionless]
    - `luminance`: $Y$ of `base_color`, `(...)`, that the tints divide by (Mitsuba: the mean
        over the path's wavelengths of $\bar y(\lambda)\,C(\lambda)$); default the mean of
        `base_color` over its wavelengths. [dimensionless]
    - `specular_sampling_rate`, `clearcoat_sampling_rate`, `diffuse_sampling_rate`:
        Mitsuba's `main_specular_sampling_rate`, `clearcoat_sampling_rate`,
        `diffuse_reflectance_sampling_rate` (default 1), `(...)`. [dimensionless]

    !!! note "Thesis"
        Eq. 3.4 (BSDF), 3.13-3.18 (Fresnel); section 3.1 (diffuse, glossy and specular lobes).

    ??? cite "References"
        `Burley2012`; `Burley2015`; `Jakob2022` (`principled`); `Walter2007`; `Heitz2018`.
    """

    base_color: Array
    roughness: Array
    anisotropic: Array
    metallic: Array
    spec_trans: Array
    eta: Array
    spec_tint: Array
    sheen: Array
    sheen_tint: Array
    clearcoat: Array
    clearcoat_gloss: Array
    flatness: Array
    luminance: Array
    specular_sampling_rate: Array
    clearcoat_sampling_rate: Array
    diffuse_sampling_rate: Array

    def __init__(
        self,
        base_color=0.5,
        roughness=0.5,
        *,
        anisotropic=0.0,
        metallic=0.0,
        spec_trans=0.0,
        eta=1.5,
        spec_tint=0.0,
        sheen=0.0,
        sheen_tint=0.0,
        clearcoat=0.0,
        clearcoat_gloss=0.0,
        flatness=0.0,
        luminance=None,
        specular_sampling_rate=1.0,
        clearcoat_sampling_rate=1.0,
        diffuse_sampling_rate=1.0,
    ):
        unit = {
            "roughness": roughness, "anisotropic": anisotropic, "metallic": metallic,
            "spec_trans": spec_trans, "spec_tint": spec_tint, "sheen": sheen,
            "sheen_tint": sheen_tint, "clearcoat": clearcoat,
            "clearcoat_gloss": clearcoat_gloss, "flatness": flatness,
        }  # fmt: skip
        rates = {
            "specular_sampling_rate": specular_sampling_rate,
            "clearcoat_sampling_rate": clearcoat_sampling_rate,
            "diffuse_sampling_rate": diffuse_sampling_rate,
        }
        self._set(base_color, unit, eta, luminance, rates)

    _SCALARS = (
        "roughness", "anisotropic", "metallic", "spec_trans", "eta", "spec_tint", "sheen",
        "sheen_tint", "clearcoat", "clearcoat_gloss", "flatness", "luminance",
        "specular_sampling_rate", "clearcoat_sampling_rate", "diffuse_sampling_rate",
    )  # fmt: skip

    @staticmethod
    def _alphas(p) -> tuple[Array, Array]:
        """Mitsuba's `calc_dist_params`: alpha = roughness^2 stretched by the anisotropy."""
        r2 = p["roughness"] ** 2
        aspect = jnp.sqrt(1.0 - 0.9 * p["anisotropic"])
        return jnp.maximum(1e-3, r2 / aspect), jnp.maximum(1e-3, r2 * aspect)

    @staticmethod
    def _lobe_probabilities(p, front: Array, F: Array) -> tuple[Array, Array, Array, Array]:
        """(diffuse, clearcoat, transmission, reflection) probabilities, normalised."""
        metal, st = p["metallic"], p["spec_trans"]
        brdf, bsdf = (1.0 - metal) * (1.0 - st), (1.0 - metal) * st
        rate = p["specular_sampling_rate"]
        p_r = jnp.where(front, rate * (1.0 - bsdf * (1.0 - F)), F)
        p_t = jnp.where(front, rate * bsdf * (1.0 - F), 1.0 - F)
        p_c = jnp.where(front, 0.25 * p["clearcoat"] * p["clearcoat_sampling_rate"], 0.0)
        p_d = jnp.where(front, brdf * p["diffuse_sampling_rate"], 0.0)
        tot = p_r + p_t + p_c + p_d
        inv = jnp.where(tot > 0, 1.0 / jnp.where(tot > 0, tot, 1.0), 0.0)
        return p_d * inv, p_c * inv, p_t * inv, p_r * inv

    def _half(self, o: Array, i: Array, p) -> tuple[Array, Array, Array, Array, Array]:
        """(h facing +z, reflect, refract, eta', valid) of the pair."""
        c_o, c_i = o[..., 2], i[..., 2]
        reflect, refract = c_o * c_i > 0, c_o * c_i < 0
        eta = p["eta"]
        eta_path = jnp.where(c_o > 0, eta, 1.0 / eta)
        h, ok = _normalize(o + i * jnp.where(reflect, 1.0, eta_path)[..., None])
        h = jnp.where(h[..., 2:3] < 0, -h, h)
        return h, reflect, refract, eta_path, ok

    def _value(self, o: Array, i: Array, p, mode: str) -> Array:
        """Mitsuba's `eval` divided by |cos theta_i| (our f), `(..., k)`."""
        c_o, c_i = o[..., 2], i[..., 2]
        active = c_o != 0.0
        front = c_o > 0
        base = p["base_color"]
        metal, st = p["metallic"], p["spec_trans"]
        brdf, bsdf = (1.0 - metal) * (1.0 - st), (1.0 - metal) * st
        eta = p["eta"]
        h, reflect, refract, eta_path, ok = self._half(o, i, p)
        active = active & ok
        d_o, d_i = _dot(o, h), _dot(i, h)
        F = _fr_dielectric_snell(d_o, eta, 1.0 / eta)[0]
        side = jnp.where(front, 1.0, -1.0)[..., None]
        m_side = h * side
        compat_r = (_dot(o, m_side) > 0) & (_dot(i, m_side) > 0)
        compat_t = (_dot(o, m_side) > 0) & (_dot(i, -m_side) > 0)
        ax, ay = self._alphas(p)
        e = (h[..., 0] / ax) ** 2 + (h[..., 1] / ay) ** 2 + h[..., 2] ** 2
        d_ggx = 1.0 / (jnp.pi * ax * ay * e * e)
        G = _smith_g1_ggx(o, h, ax, ay) * _smith_g1_ggx(i, h, ax, ay)
        a_o, a_i = jnp.abs(c_o), jnp.abs(c_i)
        safe_o, safe_i = jnp.where(a_o > 0, a_o, 1.0), jnp.where(a_i > 0, a_i, 1.0)
        lum = p["luminance"]
        c_tint = jnp.where(
            (lum > 0)[..., None], base / jnp.where(lum > 0, lum, 1.0)[..., None], 1.0
        )

        # Main specular reflection, with Mitsuba's blended Fresnel.
        tint = p["spec_tint"]
        eta_it = jnp.where(d_o >= 0, eta, 1.0 / eta)
        r0 = ((eta_it - 1.0) / (eta_it + 1.0)) ** 2
        f_front = (
            ((1.0 - metal) * (1.0 - tint) * F)[..., None]
            + metal[..., None] * _schlick(base, d_o, eta)
            + ((1.0 - metal) * tint)[..., None] * _schlick(c_tint * r0[..., None], d_o, eta)
        )
        f_princ = jnp.where(front[..., None], f_front, (bsdf * F)[..., None])
        spec_on = active & reflect & compat_r & (F > 0)
        spec = f_princ * (d_ggx * G / (4.0 * safe_o * safe_i))[..., None]
        value = jnp.where(spec_on[..., None], spec, 0.0)

        # Main specular transmission.
        trans_on = active & (bsdf > 0) & refract & compat_t & (F < 1)
        scale = 1.0 / (eta_path * eta_path) if mode == "radiance" else 1.0
        den = d_o + eta_path * d_i
        den = jnp.where(den != 0, den * den, 1.0)
        t = jnp.abs(scale * (1.0 - F) * d_ggx * G * eta_path**2 * d_o * d_i / (safe_o * den))
        t = jnp.where(trans_on, t / safe_i, 0.0)
        value = value + jnp.sqrt(base) * (bsdf * t)[..., None]

        # Clearcoat (GTR1), no 1/(4 cos cos) as in Mitsuba.
        cc = p["clearcoat"]
        cc_on = active & (cc > 0) & reflect & compat_r & front
        f_cc = _schlick(jnp.full_like(d_o, 0.04), d_o, eta)
        a_cc = 0.1 + (0.001 - 0.1) * p["clearcoat_gloss"]
        g_cc = _smith_g1_ggx(o, h, 0.25, 0.25) * _smith_g1_ggx(i, h, 0.25, 0.25)
        clear = 0.25 * cc * f_cc * _gtr1_d(h[..., 2], a_cc) * g_cc
        value = value + jnp.where(cc_on, clear, 0.0)[..., None]

        # Diffuse, retro-reflection, fake subsurface and sheen.
        diff_on = active & (brdf > 0) & reflect & front
        w_i, w_o = _schlick_weight(a_i), _schlick_weight(a_o)
        f_diff = (1.0 - 0.5 * w_o) * (1.0 - 0.5 * w_i)
        cos_d = _dot(h, i)
        rr = 2.0 * p["roughness"] * cos_d * cos_d
        f_retro = rr * (w_i + w_o + w_i * w_o * (rr - 1.0))
        f_ss90 = rr / 2.0
        f_ss = (1.0 + (f_ss90 - 1.0) * w_i) * (1.0 + (f_ss90 - 1.0) * w_o)
        f_ss = 1.25 * (f_ss * (1.0 / jnp.where(a_o + a_i > 0, a_o + a_i, 1.0) - 0.5) + 0.5)
        flat = p["flatness"]
        lobe = (f_diff + f_retro) * (1.0 - flat) + f_ss * flat
        diffuse = base * (brdf * lobe / jnp.pi)[..., None]
        sh = p["sheen"]
        sheen_on = diff_on & (sh > 0) & (1.0 - metal > 0)
        c_sheen = 1.0 + (c_tint - 1.0) * p["sheen_tint"][..., None]
        sheen = (sh * (1.0 - metal) * _schlick_weight(jnp.abs(cos_d)))[..., None] * c_sheen
        value = value + jnp.where(diff_on[..., None], diffuse, 0.0)
        value = value + jnp.where(sheen_on[..., None], sheen, 0.0)
        return jnp.where(active[..., None], value, 0.0)

    def _pdf(self, o: Array, i: Array, p) -> Array:
        c_o = o[..., 2]
        front = c_o > 0
        metal, st = p["metallic"], p["spec_trans"]
        bsdf = (1.0 - metal) * st
        active = (c_o != 0.0) & (front | (bsdf > 0))  # sample_f's rule
        eta = p["eta"]
        h, reflect, refract, eta_path, ok = self._half(o, i, p)
        active = active & ok
        d_o, d_i = _dot(o, h), _dot(i, h)
        F = _fr_dielectric_snell(d_o, eta, 1.0 / eta)[0]
        p_d, p_c, p_t, p_r = self._lobe_probabilities(p, front, F)
        den = d_o + eta_path * d_i
        dwh = jnp.abs(
            jnp.where(
                reflect,
                safe_div(jnp.ones_like(d_i), 4.0 * d_i),
                safe_div(eta_path * eta_path * d_i, den * den),
            )
        )
        side = jnp.where(front, 1.0, -1.0)[..., None]
        m_side = h * side
        compat_r = (_dot(o, m_side) > 0) & (_dot(i, m_side) > 0) & reflect
        compat_t = (_dot(o, m_side) > 0) & (_dot(i, -m_side) > 0) & refract
        ax, ay = self._alphas(p)
        o_up = o * side
        e = (h[..., 0] / ax) ** 2 + (h[..., 1] / ay) ** 2 + h[..., 2] ** 2
        d_ggx = 1.0 / (jnp.pi * ax * ay * e * e)
        vis = d_ggx * _smith_g1_ggx(o_up, h, ax, ay) * jnp.abs(_dot(o_up, h))
        vis = safe_div(vis, o_up[..., 2])
        a_cc = 0.1 + (0.001 - 0.1) * p["clearcoat_gloss"]
        cc = jnp.where(h[..., 2] < 0, 0.0, h[..., 2] * _gtr1_d(h[..., 2], a_cc))
        pdf = jnp.where(compat_r, (p_r * vis + p_c * cc) * dwh, 0.0)
        pdf = pdf + jnp.where(reflect, p_d * i[..., 2] / jnp.pi, 0.0)
        pdf = pdf + jnp.where(compat_t, p_t * vis * dwh, 0.0)
        return jnp.where(active, pdf, 0.0)

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        _check_mode(mode)
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        (wo, wi), p = self._params((wo, 1), (wi, 1))
        return self._value(wo, wi, p, mode)

    def pdf(self, wo, wi) -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        (wo, wi), p = self._params((wo, 1), (wi, 1))
        return self._pdf(wo, wi, p)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        _check_mode(mode)
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        u2 = _u2(u2)
        (o, u, u2), p = self._params((wo, 1), (u_lobe, 0), (u2, 1))
        c_o = o[..., 2]
        front = c_o > 0
        bsdf = (1.0 - p["metallic"]) * p["spec_trans"]
        side = jnp.where(front, 1.0, -1.0)[..., None]
        ax, ay = self._alphas(p)
        m = TrowbridgeReitzDistribution(ax, ay).sample_wm(o * side, u2)
        d_o = _dot(o, m)
        eta = p["eta"]
        F, _, eta_eff, inv_eta_eff, cos_t, _ = _fr_dielectric_snell(d_o, eta, 1.0 / eta)
        p_d, p_c, p_t, _ = self._lobe_probabilities(p, front, F)
        diffuse = u < p_d
        clear = ~diffuse & (u < p_d + p_c)
        trans = ~diffuse & ~clear & (u < p_d + p_c + p_t)
        # Main specular reflection (thesis eq. 3.8) and refraction (eq. 3.12) about m.
        w_r = 2.0 * d_o[..., None] * m - o
        sign = jnp.where(d_o >= 0, 1.0, -1.0)
        w_t = m * (d_o * inv_eta_eff - sign * cos_t)[..., None] - o * inv_eta_eff[..., None]
        # Clearcoat: a GTR1 normal (Burley2012, eq. in appendix B).
        a2 = (0.1 + (0.001 - 0.1) * p["clearcoat_gloss"]) ** 2
        cos2 = (1.0 - a2 ** (1.0 - u2[..., 1])) / (1.0 - a2)
        sin_t, cos_c = jnp.sqrt(jnp.maximum(0.0, 1.0 - cos2)), jnp.sqrt(jnp.maximum(0.0, cos2))
        sin_phi, cos_phi = sincos_pi(2.0 * u2[..., 0])  # phi = 2 pi u
        m_cc = _stack3(cos_phi * sin_t, sin_phi * sin_t, cos_c)
        w_c = 2.0 * _dot(o, m_cc)[..., None] * m_cc - o
        x, y, z = _sample_cosine_hemisphere(u2[..., 0], u2[..., 1])
        w_d = _stack3(x, y, z)
        wi = jnp.where(
            diffuse[..., None],
            w_d,
            jnp.where(clear[..., None], w_c, jnp.where(trans[..., None], w_t, w_r)),
        )
        normal = jnp.where(clear[..., None], m_cc, m) * side
        compat_in = _dot(o, normal) > 0
        compat_out = jnp.where(trans, _dot(wi, -normal) > 0, _dot(wi, normal) > 0)
        c_i = wi[..., 2]
        side_ok = jnp.where(trans, c_o * c_i < 0, c_o * c_i > 0)
        ok = (c_o != 0) & (front | (bsdf > 0)) & side_ok & (diffuse | (compat_in & compat_out))
        pdf = self._pdf(o, wi, p)
        ok = ok & (pdf > 0)
        sample = BSDFSample(
            f=self._value(o, wi, p, mode),
            wi=wi,
            pdf=pdf,
            is_delta=jnp.zeros(ok.shape, bool),
            is_transmission=trans,
            eta=jnp.where(trans, eta_eff, 1.0),
            terminate_secondary=jnp.zeros(ok.shape, bool),
        )
        return _failed_or(ok, sample)


class PrincipledThinBxDF(_AbstractPrincipled):
    r"""The thin principled BSDF, lobe for lobe as Mitsuba 3's `principledthin`: a
    two-dimensional sheet (leaves, paper, fabric), the same from both sides.

    With `wo` mirrored to +z (and `wi` with it), $h$ the half vector of `wo` and `wi` mirrored
    to +z, $s_t$ spec_trans and $d = $ diff_trans$/2$:

    - *specular reflection*: $s_t\,F_{thin}\,D\,G/(4\cos\theta_o\cos\theta_i)$, GGX of
      $\alpha = r^2$, $F_{thin} = \mathrm{lerp}(F_d, F_S(R_0(\eta)\,C/Y), t)$;
    - *specular transmission*: $s_t\,C\,(1 - F_d)\,D'\,G'/(4\cos\theta_o|\cos\theta_i|)$, the
      microfacet reflection turned to the other side (no bending in a thin sheet), GGX with
      the roughness scaled by $0.65\eta - 0.35$ (`Burley2015`, fig. 15);
    - *diffuse reflection* and *sheen*: as `PrincipledBxDF`, times $(1 - s_t)(1 - d)$;
    - *diffuse transmission*: $(1 - s_t)\,d\,C/\pi$.

    Lobes are chosen with probabilities $\propto s_t/2, s_t/2, (1 - s_t)(1 - d), (1 - s_t)d$
    (times Mitsuba's sampling rates); `eta` of a sample is 1 (both sides are the same medium).

    **Fields** (batch shape `(...)`):

    - `base_color`: $C$, `(..., n_lambda)`. [dimensionless]
    - `roughness`, `anisotropic`, `spec_trans`, `spec_tint`, `sheen`, `sheen_tint`,
        `flatness`: in [0, 1]; `diff_trans`: in [0, 2] (Mitsuba's range). [dimensionless]
    - `eta`: index of the sheet's material, > 0 (default 1.5). [dimensionless]
    - `luminance`: as in `PrincipledBxDF`.
    - `specular_reflectance_sampling_rate`, `specular_transmittance_sampling_rate`,
        `diffuse_reflectance_sampling_rate`, `diffuse_transmittance_sampling_rate`:
        Mitsuba's (default 1). [dimensionless]

    !!! note "Thesis"
        Eq. 3.4, 3.13-3.18; section 3.1 (diffuse and glossy reflection and transmission).

    ??? cite "References"
        `Burley2015`; `Jakob2022` (`principledthin`).
    """

    base_color: Array
    roughness: Array
    anisotropic: Array
    spec_trans: Array
    diff_trans: Array
    eta: Array
    spec_tint: Array
    sheen: Array
    sheen_tint: Array
    flatness: Array
    luminance: Array
    specular_reflectance_sampling_rate: Array
    specular_transmittance_sampling_rate: Array
    diffuse_reflectance_sampling_rate: Array
    diffuse_transmittance_sampling_rate: Array

    def __init__(
        self,
        base_color=0.5,
        roughness=0.5,
        *,
        anisotropic=0.0,
        spec_trans=0.0,
        diff_trans=0.0,
        eta=1.5,
        spec_tint=0.0,
        sheen=0.0,
        sheen_tint=0.0,
        flatness=0.0,
        luminance=None,
        specular_reflectance_sampling_rate=1.0,
        specular_transmittance_sampling_rate=1.0,
        diffuse_reflectance_sampling_rate=1.0,
        diffuse_transmittance_sampling_rate=1.0,
    ):
        unit = {
            "roughness": roughness, "anisotropic": anisotropic, "spec_trans": spec_trans,
            "spec_tint": spec_tint, "sheen": sheen, "sheen_tint": sheen_tint,
            "flatness": flatness,
        }  # fmt: skip
        rates = {
            "specular_reflectance_sampling_rate": specular_reflectance_sampling_rate,
            "specular_transmittance_sampling_rate": specular_transmittance_sampling_rate,
            "diffuse_reflectance_sampling_rate": diffuse_reflectance_sampling_rate,
            "diffuse_transmittance_sampling_rate": diffuse_transmittance_sampling_rate,
        }
        self._set(base_color, unit, eta, luminance, rates, diff_trans=(diff_trans, 2.0))

    _SCALARS = (
        "roughness", "anisotropic", "spec_trans", "diff_trans", "eta", "spec_tint", "sheen",
        "sheen_tint", "flatness", "luminance", "specular_reflectance_sampling_rate",
        "specular_transmittance_sampling_rate", "diffuse_reflectance_sampling_rate",
        "diffuse_transmittance_sampling_rate",
    )  # fmt: skip

    @staticmethod
    def _alphas(p, scaled: bool) -> tuple[Array, Array]:
        r = p["roughness"] * (0.65 * p["eta"] - 0.35) if scaled else p["roughness"]
        return PrincipledBxDF._alphas({"roughness": r, "anisotropic": p["anisotropic"]})

    @staticmethod
    def _probabilities(p) -> tuple[Array, Array, Array, Array]:
        st, dt = p["spec_trans"], 0.5 * p["diff_trans"]
        p_sr = st * p["specular_reflectance_sampling_rate"] / 2.0
        p_st = st * p["specular_transmittance_sampling_rate"] / 2.0
        p_dr = p["diffuse_reflectance_sampling_rate"] * (1.0 - st) * (1.0 - dt)
        p_dt = p["diffuse_transmittance_sampling_rate"] * (1.0 - st) * dt
        tot = p_sr + p_st + p_dr + p_dt
        inv = jnp.where(tot > 0, 1.0 / jnp.where(tot > 0, tot, 1.0), 0.0)
        return p_sr * inv, p_st * inv, p_dr * inv, p_dt * inv

    @staticmethod
    def _frame(o: Array, i: Array):
        """(o, i) mirrored so that o is on +z, the half vector of o and i mirrored to +z."""
        side = jnp.where(o[..., 2:3] < 0, -1.0, 1.0)
        o, i = o * side, i * side
        i_r = jnp.concatenate([i[..., :2], jnp.abs(i[..., 2:])], axis=-1)
        h, ok = _normalize(o + i_r)
        return o, i, i_r, h, ok

    @staticmethod
    def _ggx(h: Array, ax: Array, ay: Array) -> Array:
        e = (h[..., 0] / ax) ** 2 + (h[..., 1] / ay) ** 2 + h[..., 2] ** 2
        return 1.0 / (jnp.pi * ax * ay * e * e)

    def _value(self, o: Array, i: Array, p) -> Array:
        active = o[..., 2] != 0.0
        o, i, _, h, ok = self._frame(o, i)
        active = active & ok
        base = p["base_color"]
        st, dt, eta = p["spec_trans"], 0.5 * p["diff_trans"], p["eta"]
        c_o, c_i = o[..., 2], i[..., 2]
        reflect, refract = c_i > 0, c_i < 0
        d_o = _dot(o, h)
        compat_r = (d_o > 0) & (_dot(i, h) > 0)
        compat_t = (d_o > 0) & (_dot(i, -h) > 0)
        F = _fr_dielectric_snell(d_o, eta, 1.0 / eta)[0]
        a_o, a_i = jnp.abs(c_o), jnp.abs(c_i)
        den = 4.0 * jnp.where(a_o > 0, a_o, 1.0) * jnp.where(a_i > 0, a_i, 1.0)
        lum = p["luminance"]
        pos = (lum > 0)[..., None]
        c_tint = jnp.where(pos, base / jnp.where(pos, lum[..., None], 1.0), 1.0)

        ax, ay = self._alphas(p, scaled=False)
        g = _smith_g1_ggx(o, h, ax, ay) * _smith_g1_ggx(i, h, ax, ay)
        r0 = ((eta - 1.0) / (eta + 1.0)) ** 2
        tint = p["spec_tint"][..., None]
        f_thin = F[..., None] * (1.0 - tint) + tint * _schlick(c_tint * r0[..., None], d_o, eta)
        spec = (st * self._ggx(h, ax, ay) * g / den)[..., None] * f_thin
        value = jnp.where((active & (st > 0) & reflect & compat_r)[..., None], spec, 0.0)

        sx, sy = self._alphas(p, scaled=True)
        g_t = _smith_g1_ggx(o, h, sx, sy) * _smith_g1_ggx(i, h, sx, sy)
        trans = base * (st * (1.0 - F) * self._ggx(h, sx, sy) * g_t / den)[..., None]
        value = value + jnp.where((active & refract & (st > 0) & compat_t)[..., None], trans, 0.0)

        diff_on = active & reflect & (st < 1.0) & (dt < 1.0)
        w_i, w_o = _schlick_weight(a_i), _schlick_weight(a_o)
        f_diff = (1.0 - 0.5 * w_o) * (1.0 - 0.5 * w_i)
        cos_d = _dot(h, i)
        rr = 2.0 * p["roughness"] * cos_d * cos_d
        f_retro = rr * (w_i + w_o + w_i * w_o * (rr - 1.0))
        f_ss = (1.0 + (rr / 2.0 - 1.0) * w_i) * (1.0 + (rr / 2.0 - 1.0) * w_o)
        f_ss = 1.25 * (f_ss * (1.0 / jnp.where(a_o + a_i > 0, a_o + a_i, 1.0) - 0.5) + 0.5)
        flat = p["flatness"]
        lobe = (f_diff + f_retro) * (1.0 - flat) + f_ss * flat
        weight = (1.0 - st) * (1.0 - dt)
        diffuse = base * (weight * lobe / jnp.pi)[..., None]
        c_sheen = 1.0 + (c_tint - 1.0) * p["sheen_tint"][..., None]
        sheen = (p["sheen"] * weight * _schlick_weight(jnp.abs(cos_d)))[..., None] * c_sheen
        value = value + jnp.where(diff_on[..., None], diffuse + sheen, 0.0)

        dt_on = active & refract & (st < 1.0) & (dt > 0.0)
        value = value + jnp.where(dt_on[..., None], base * ((1.0 - st) * dt / jnp.pi)[..., None], 0)
        return jnp.where(active[..., None], value, 0.0)

    def _pdf(self, o: Array, i: Array, p) -> Array:
        active = o[..., 2] != 0.0
        o, i, i_r, h, ok = self._frame(o, i)
        active = active & ok
        reflect, refract = i[..., 2] > 0, i[..., 2] < 0
        p_sr, p_st, p_dr, p_dt = self._probabilities(p)
        d_o = _dot(o, h)
        compat_r = (d_o > 0) & (_dot(i, h) > 0) & reflect
        compat_t = (d_o > 0) & (_dot(i, -h) > 0) & refract
        dwh = jnp.abs(safe_div(jnp.ones_like(d_o), 4.0 * _dot(i_r, h)))

        def visible(ax, ay):
            vis = self._ggx(h, ax, ay) * _smith_g1_ggx(o, h, ax, ay) * jnp.abs(d_o)
            return safe_div(vis, o[..., 2])

        pdf = jnp.where(compat_r, p_sr * visible(*self._alphas(p, False)) * dwh, 0.0)
        pdf = pdf + jnp.where(compat_t, p_st * visible(*self._alphas(p, True)) * dwh, 0.0)
        pdf = pdf + jnp.where(reflect, p_dr * i[..., 2] / jnp.pi, 0.0)
        pdf = pdf + jnp.where(refract, -p_dt * i[..., 2] / jnp.pi, 0.0)
        return jnp.where(active, pdf, 0.0)

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        _check_mode(mode)  # a thin sheet bends no light: both modes agree
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        (wo, wi), p = self._params((wo, 1), (wi, 1))
        return self._value(wo, wi, p)

    def pdf(self, wo, wi) -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        (wo, wi), p = self._params((wo, 1), (wi, 1))
        return self._pdf(wo, wi, p)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        _check_mode(mode)
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        u2 = _u2(u2)
        (o, u, u2), p = self._params((wo, 1), (u_lobe, 0), (u2, 1))
        side = jnp.where(o[..., 2:3] < 0, -1.0, 1.0)
        up = o * side
        p_sr, p_st, p_dr, _ = self._probabilities(p)
        spec_r = u < p_sr
        spec_t = ~spec_r & (u < p_sr + p_st)
        diff_r = ~spec_r & ~spec_t & (u < p_sr + p_st + p_dr)
        glossy = spec_r | spec_t
        ax, ay = self._alphas(p, False)
        sx, sy = self._alphas(p, True)
        ax, ay = jnp.where(spec_t, sx, ax), jnp.where(spec_t, sy, ay)
        m = TrowbridgeReitzDistribution(ax, ay).sample_wm(up, u2)
        w = 2.0 * _dot(up, m)[..., None] * m - up
        w = jnp.where(spec_t[..., None], jnp.concatenate([w[..., :2], -w[..., 2:]], axis=-1), w)
        x, y, z = _sample_cosine_hemisphere(u2[..., 0], u2[..., 1])
        cos_dir = _stack3(x, y, jnp.where(diff_r, z, -z))
        wi_up = jnp.where(glossy[..., None], w, cos_dir)
        compat = (_dot(up, m) > 0) & jnp.where(
            spec_t,
            (_dot(wi_up, -m) > 0) & (wi_up[..., 2] < 0),
            (_dot(wi_up, m) > 0) & (wi_up[..., 2] > 0),
        )
        wi = wi_up * side
        pdf = self._pdf(o, wi, p)
        ok = (o[..., 2] != 0) & (~glossy | compat) & (pdf > 0)
        trans = wi[..., 2] * o[..., 2] < 0
        sample = BSDFSample(
            f=self._value(o, wi, p),
            wi=wi,
            pdf=pdf,
            is_delta=jnp.zeros(ok.shape, bool),
            is_transmission=trans,
            eta=jnp.ones_like(pdf),
            terminate_secondary=jnp.zeros(ok.shape, bool),
        )
        return _failed_or(ok, sample)
