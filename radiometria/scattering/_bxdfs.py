r"""BxDFs: the BRDF of thesis eq. 3.4 and its transmissive counterpart, with sampling and pdfs.

Every BxDF is an `equinox.Module` in the local shading frame (normal $+z$, thesis convention:
the normal points out of the surface) with three methods, as pbrt's `BxDF`:

- `f(wo, wi)`: the BxDF value $f(\omega_o, \omega_i) = dL_o/(L_i\cos\theta_i\,d\omega_i)$
  (thesis eq. 3.4): **without** the cosine factor $|\cos\theta_i|$. Shape `(..., n_lambda)`.
  Mitsuba's `BSDF.eval` returns $f\,|\cos\theta_i|$ instead.
- `sample_f(wo, u_lobe, u2)`: one importance sample as a `BSDFSample` (value, direction, pdf,
  delta flag, ...), like pbrt's `Sample_f`. The Monte Carlo weight of the sample is
  `f * |wi_z| / pdf` (`BSDFSample.weight()`).
- `pdf(wo, wi)`: the solid-angle density of `sample_f` producing `wi`, `(...)`. Delta
  (specular) lobes give 0 here, as their density is not a function.

Directions `wo` (towards the viewer, i.e. the direction radiance leaves in) and `wi` (towards
the light) both point away from the surface and are unit vectors (not checked: see
`radiometria.scattering` for the policy). Batch axes of the directions, the uniform variates and
the BxDF's parameters broadcast together.

**Spectral parameters.** Reflectances, `eta` and `k` are arrays `(..., n_lambda)` over the
wavelengths a renderer carries (4 hero wavelengths in `radiometria.render`); a scalar parameter
counts as `n_lambda = 1` and broadcasts against any wavelength count downstream. Roughness
(`alpha`) and Oren-Nayar's `sigma` are not spectral, shape `(...)`.

**Dispersion.** A dielectric whose `eta` varies across the wavelengths refracts each wavelength
into a different direction. With `dispersion=True`, `f` is exact per wavelength (the half
vector is recomputed for each wavelength's `eta`); `pdf` and `sample_f` use the first ("hero")
wavelength, `eta[..., 0]`, to choose the direction and report the hero's pdf.
Reflection serves every wavelength (its direction does not depend on `eta`); for a
*transmission* sample the secondary wavelengths get `f = 0` and `terminate_secondary = True`, as
pbrt does (`SampledWavelengths::TerminateSecondary`): from then on the path carries the hero
wavelength only, and the renderer must reweight it (pbrt divides the hero's wavelength pdf by
`n_lambda`). A constant `eta` (the common case) never terminates. The static flag
`dispersion` is detected at construction from a concrete `eta` (any variation along the last
axis); a traced `eta` (a BxDF built inside `jit`) counts as dispersive unless the caller passes
`dispersion=False`, which promises a constant `eta` and evaluates everything once with
`eta[..., 0]` (about n_lambda times less work).

**Sidedness.** As in pbrt, the reflective BxDFs here are symmetric: they reflect in whichever
hemisphere `wo` lies. `TwoSidedBxDF(front, back)` gives the two sides different BxDFs, each
evaluated in its own frame (Mitsuba's `twosided`).

**Failed samples** (e.g. a microfacet that reflects below the horizon, `wo` exactly grazing)
have `pdf = 0` and `f = 0`; a renderer terminates the path there.

**Parameter validation** happens once, in each constructor (out-of-range values raise, also
under `jit`, via `equinox.error_if`); the methods themselves do no checks, for speed. Uniform
variates are expected in [0, 1).
"""

import abc

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from .._checks import as_float_array, check_choice, check_in_range
from .._math import disk_concentric_xy, safe_div
from ._directions import _inv_norm, _sqrt_clamped, _stack3, _xyz, coordinate_system
from ._fresnel import _check_eta, _check_k, _fr_conductor, _fr_dielectric_snell
from ._microfacet import (
    BeckmannDistribution,
    TrowbridgeReitzDistribution,
    _D_den,
    _slope_root,
)

__all__ = [
    "AbstractBxDF",
    "BSDFSample",
    "ConductorBxDF",
    "DielectricBxDF",
    "DiffuseBxDF",
    "DiffuseTransmissionBxDF",
    "OrenNayarBxDF",
    "RetroreflectiveBxDF",
    "RoughConductorBxDF",
    "RoughDielectricBxDF",
    "TwoSidedBxDF",
]

_MODES = ("radiance", "importance")


# --------------------------------------------------------------------------------------------
# Helpers


def _spectral(x, name: str) -> Array:
    """A per-wavelength parameter: at least 1-D, wavelengths on the last axis."""
    x = as_float_array(x, name)
    return x[None] if x.ndim == 0 else x


def _broadcast(*items: tuple[Array, int]) -> tuple[tuple[int, ...], list[Array]]:
    """Broadcast arrays over their batch axes; each item is (array, number of core axes)."""
    shapes = [a.shape[: a.ndim - k] for a, k in items]
    try:
        batch = tuple(np.broadcast_shapes(*shapes))
    except ValueError:
        raise ValueError(f"Batch shapes do not broadcast: {shapes}.") from None
    return batch, [jnp.broadcast_to(a, batch + a.shape[a.ndim - k :]) for a, k in items]


def _spectral_pair(a: Array, b: Array) -> tuple[Array, Array]:
    """Broadcast two spectral parameters to a common shape (checked at construction)."""
    try:
        shape = np.broadcast_shapes(a.shape, b.shape)
    except ValueError:
        raise ValueError(
            f"Spectral parameters do not broadcast: {a.shape} and {b.shape}."
        ) from None
    return jnp.broadcast_to(a, shape), jnp.broadcast_to(b, shape)


def _dirs(*ws) -> list[Array]:
    out = []
    for name, w in ws:
        w = as_float_array(w, name)
        if w.ndim == 0 or w.shape[-1] != 3:
            raise ValueError(f"`{name}` must have a last axis of length 3, got shape {w.shape}.")
        out.append(w)
    return out


def _u2(u2) -> Array:
    u2 = as_float_array(u2, "u2")
    if u2.ndim == 0 or u2.shape[-1] != 2:
        raise ValueError(f"`u2` must have a last axis of length 2, got shape {u2.shape}.")
    return u2


def _sample_cosine_hemisphere(u0: Array, u1: Array) -> tuple[Array, Array, Array]:
    """Malley's method on the concentric disk mapping (pbrt-v4 A.5.3); returns x, y, z >= 0."""
    x, y = disk_concentric_xy(u0, u1)
    z = _sqrt_clamped(1.0 - x * x - y * y)
    return x, y, z


def _mirror_xy(w: Array) -> Array:
    """Mirror reflection about +z: (-x, -y, z) (thesis eq. 3.8 in the local frame)."""
    return jnp.concatenate([-w[..., :2], w[..., 2:]], axis=-1)


def _detect_dispersion(eta: Array, dispersion: bool | None) -> bool:
    """Static flag: does `eta` vary along the wavelength axis? Traced input counts as yes."""
    if dispersion is not None:
        return bool(dispersion)
    if isinstance(eta, jax.core.Tracer):
        return True
    e = np.asarray(eta)
    return bool(np.any(e != e[..., :1]))


def _check_mode(mode: str) -> str:
    return check_choice(mode, "mode", _MODES)


class BSDFSample(eqx.Module):
    """Result of `AbstractBxDF.sample_f` (pbrt's `BSDFSample`).

    **Fields:**

    - `f`: BxDF value for the sampled pair, `(..., n_lambda)`, without the cosine factor.
        For a delta lobe it is the value that makes `f * |wi_z| / pdf` the sample weight, i.e.
        `F / |cos theta_i|` (`Pharr2023` section 9.2). [sr^-1]
    - `wi`: sampled direction `(..., 3)`, local frame, pointing away from the surface. [unit vector]
    - `pdf`: solid-angle density of `wi`, `(...)`; for a delta lobe the discrete probability of
        choosing that lobe. 0 marks a failed sample. [sr^-1 or dimensionless]
    - `is_delta`: True for a specular (Dirac delta) lobe, `(...)`. Such samples must not be
        combined with light sampling by MIS.
    - `is_transmission`: True when `wi` lies on the other side of the surface, `(...)`.
    - `eta`: relative index of refraction crossed, $\\eta_t/\\eta_i$ seen from `wo`'s side
        (1 for reflection), `(...)`, for Russian roulette bookkeeping as in pbrt. [dimensionless]
    - `terminate_secondary`: True when only the hero wavelength (index 0) is valid from this
        sample on (transmission through a dispersive dielectric), `(...)`.
    """

    f: Array
    wi: Array
    pdf: Array
    is_delta: Array
    is_transmission: Array
    eta: Array
    terminate_secondary: Array

    def weight(self) -> Array:
        """Monte Carlo weight `f |cos theta_i| / pdf`, `(..., n_lambda)`; 0 for a failed sample."""
        return safe_div(self.f * jnp.abs(self.wi[..., 2:3]), self.pdf[..., None])


def _failed_or(ok: Array, s: BSDFSample, *, masked: bool = False) -> BSDFSample:
    """Zero f and pdf where `ok` is False (`masked`: they already are, leave them)."""
    return BSDFSample(
        f=s.f if masked else jnp.where(ok[..., None], s.f, 0.0),
        wi=s.wi,
        pdf=s.pdf if masked else jnp.where(ok, s.pdf, 0.0),
        is_delta=s.is_delta,
        is_transmission=s.is_transmission & ok,
        eta=jnp.where(ok, s.eta, 1.0),
        terminate_secondary=s.terminate_secondary & ok,
    )


class AbstractBxDF(eqx.Module):
    """Interface of every BxDF: `f`, `sample_f`, `pdf` in the local shading frame (normal +z).

    The BxDF is the one of thesis eq. 3.4; the interface follows pbrt's `BxDF` (`Pharr2023`
    section 9.1).
    """

    @abc.abstractmethod
    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        """BxDF value $f(\\omega_o, \\omega_i)$ (thesis eq. 3.4), `(..., n_lambda)`. [sr^-1]"""

    @abc.abstractmethod
    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        """Importance-sample `wi` given `wo`; `u_lobe` `(...)`, `u2` `(..., 2)` in [0, 1)."""

    @abc.abstractmethod
    def pdf(self, wo, wi) -> Array:
        """Solid-angle density of `sample_f` producing `wi` (0 for delta lobes), `(...)`. [sr^-1]"""

    def f_pdf_sample(
        self, wo, wi, u_lobe, u2, *, mode: str = "radiance"
    ) -> tuple[Array, Array, BSDFSample]:
        """`(f(wo, wi), pdf(wo, wi), sample_f(wo, u_lobe, u2))` in one call: what a path
        tracer asks at each vertex (the BxDF and density in next-event estimation's direction
        `wi`, and the next direction). The default makes the three calls; a BxDF that is a
        mixture of kinds over a batch (the renderer's `MaterialSet`) evaluates each kind once,
        on its own paths, instead of three times."""
        return self.f(wo, wi, mode=mode), self.pdf(wo, wi), self.sample_f(wo, u_lobe, u2, mode=mode)


class _AbstractDeltaBxDF(AbstractBxDF):
    """A BxDF of delta lobes only (smooth conductor, dielectric, thin dielectric): `f` and
    `pdf` are 0, shaped by the directions and the spectral `eta` field."""

    eta: eqx.AbstractVar[Array]

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        _check_mode(mode)
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        batch, _ = _broadcast((wo, 1), (wi, 1), (self.eta, 1))
        return jnp.zeros(batch + self.eta.shape[-1:], self.eta.dtype)

    def pdf(self, wo, wi) -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        batch, _ = _broadcast((wo, 1), (wi, 1), (self.eta, 1))
        return jnp.zeros(batch, jnp.result_type(wo.dtype, self.eta.dtype))


# --------------------------------------------------------------------------------------------
# Lambertian


class DiffuseBxDF(AbstractBxDF):
    r"""Lambertian reflection, $f = R/\pi$ (thesis section 3.1, "Diffuse Reflection").

    A Lambertian surface reflects radiance equally in all directions; the reflected radiance
    follows Lambert's cosine law in intensity. Its directional-hemispherical reflectance is $R$
    for every incident direction. Sampled with the cosine-weighted hemisphere,
    $p(\omega_i) = |\cos\theta_i|/\pi$, so the sample weight is exactly $R$.

    **Fields:**

    - `reflectance`: $R$ in [0, 1], `(..., n_lambda)`. [dimensionless]

    !!! note "Thesis"
        Section 3.1 (diffuse reflection), eq. (3.4).

    ??? cite "References"
        `Lambert1760`; `Pharr2023` section 9.2.
    """

    reflectance: Array

    def __init__(self, reflectance):
        r = _spectral(reflectance, "reflectance")
        self.reflectance = check_in_range(r, "reflectance", 0.0, 1.0, unit="dimensionless")

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        _check_mode(mode)
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        _, (wo, wi, r) = _broadcast((wo, 1), (wi, 1), (self.reflectance, 1))
        same = wo[..., 2] * wi[..., 2] > 0
        return jnp.where(same[..., None], r * (1.0 / jnp.pi), 0.0)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        _check_mode(mode)
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        u2 = _u2(u2)
        _, (wo, u_lobe, u2, r) = _broadcast((wo, 1), (u_lobe, 0), (u2, 1), (self.reflectance, 1))
        x, y, z = _sample_cosine_hemisphere(u2[..., 0], u2[..., 1])
        # Sample in wo's hemisphere.
        z = jnp.where(wo[..., 2] < 0, -z, z)
        ok = (wo[..., 2] != 0) & (z != 0)
        s = BSDFSample(
            f=jnp.broadcast_to(r * (1.0 / jnp.pi), r.shape),
            wi=_stack3(x, y, z),
            pdf=jnp.abs(z) * (1.0 / jnp.pi),
            is_delta=jnp.zeros(z.shape, bool),
            is_transmission=jnp.zeros(z.shape, bool),
            eta=jnp.ones_like(z),
            terminate_secondary=jnp.zeros(z.shape, bool),
        )
        return _failed_or(ok, s)

    def pdf(self, wo, wi) -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        _, (wo, wi) = _broadcast((wo, 1), (wi, 1))
        batch = np.broadcast_shapes(wo.shape[:-1], self.reflectance.shape[:-1])
        same = wo[..., 2] * wi[..., 2] > 0
        return jnp.broadcast_to(jnp.where(same, jnp.abs(wi[..., 2]) * (1.0 / jnp.pi), 0.0), batch)


# --------------------------------------------------------------------------------------------
# Oren-Nayar


class OrenNayarBxDF(AbstractBxDF):
    r"""Oren-Nayar reflection from a rough surface of Lambertian V-cavities.

    Two variants, chosen with the static `model` field:

    - `"qualitative"` (default): the qualitative model of `Oren1994` (pbrt-v3),
      $$f = \frac{R}{\pi}\left(A + B\max(0, \cos(\varphi_i - \varphi_o))
        \sin\alpha\tan\beta\right),$$
      $$A = 1 - \frac{\sigma^2}{2(\sigma^2 + 0.33)},\quad B = \frac{0.45\sigma^2}{\sigma^2 + 0.09},
        \quad \alpha = \max(\theta_i,\theta_o),\ \beta = \min(\theta_i,\theta_o),$$
      with $\sigma$ the standard deviation of the facet slope angle in radians, [0, pi/2].
      The model is a fit, not exactly energy conserving: for $R = 1$ its directional albedo
      exceeds 1 by up to about 0.5 % near grazing `wo` when $\sigma$ is small
      (`tests/scattering/test_bxdfs.py` measures it).
    - `"fujii"`: Fujii's improved Oren-Nayar model (`Fujii2012`, the single-scattering lobe
      of OpenPBR's EON, `Portsmouth2024`),
      $$f = \frac{R}{\pi}\,\frac{1 + \sigma\,s/t}{1 + (\tfrac12 - \tfrac{2}{3\pi})\sigma},\quad
        s = \omega_i\cdot\omega_o - \cos\theta_i\cos\theta_o,\quad
        t = \begin{cases}\max(\cos\theta_i, \cos\theta_o) & s > 0\\ 1 & s \le 0\end{cases}$$
      with a dimensionless roughness $\sigma \in [0, 1]$. Its directional albedo is at most
      $R$ (exactly $R$ at grazing incidence), so it passes the white furnace test.

    Both are reciprocal, give the Lambertian BRDF for $\sigma = 0$ and are sampled with the
    cosine-weighted hemisphere (pdf $|\cos\theta_i|/\pi$).

    **Fields:**

    - `reflectance`: $R$ in [0, 1], `(..., n_lambda)`. [dimensionless]
    - `sigma`: roughness, `(...)`: slope-angle standard deviation [rad] in [0, pi/2] for
        `"qualitative"`, dimensionless in [0, 1] for `"fujii"`.
    - `model`: `"qualitative"` or `"fujii"`.

    !!! note "Thesis"
        Section 3.1 (diffuse and retroreflective reflection), eq. (3.4).

    ??? cite "References"
        `Oren1994`; `Pharr2016` section 8.4.2; `Fujii2012`; `Portsmouth2024`.
    """

    reflectance: Array
    sigma: Array
    model: str = eqx.field(static=True)

    def __init__(self, reflectance, sigma, *, model: str = "qualitative"):
        self.model = check_choice(model, "model", ("qualitative", "fujii"))
        r = _spectral(reflectance, "reflectance")
        self.reflectance = check_in_range(r, "reflectance", 0.0, 1.0, unit="dimensionless")
        s = as_float_array(sigma, "sigma")
        if model == "qualitative":
            self.sigma = check_in_range(s, "sigma", 0.0, float(np.pi / 2), unit="rad")
        else:
            self.sigma = check_in_range(s, "sigma", 0.0, 1.0, unit="dimensionless")

    def _value(self, wo: Array, wi: Array, r: Array, sigma: Array) -> Array:
        zo, zi = jnp.abs(wo[..., 2]), jnp.abs(wi[..., 2])
        # cos(phi_i - phi_o) sin(theta_i) sin(theta_o) = wi_xy . wo_xy  (= s of Fujii's model)
        dxy = wi[..., 0] * wo[..., 0] + wi[..., 1] * wo[..., 1]
        cos_b = jnp.maximum(zo, zi)
        if self.model == "qualitative":
            s2 = sigma * sigma
            A = 1.0 - s2 / (2.0 * (s2 + 0.33))
            B = 0.45 * s2 / (s2 + 0.09)
            # sin(alpha) tan(beta) = sin_a sin_b / cos_b, beta the angle nearer the normal
            # (larger |cos|); times cos(dphi) the sines combine into the dot product.
            g = A + B * safe_div(jnp.maximum(0.0, dxy), cos_b)
        else:
            t = jnp.where(dxy > 0, cos_b, 1.0)
            g = (1.0 + sigma * safe_div(dxy, t)) / (1.0 + (0.5 - 2.0 / (3.0 * np.pi)) * sigma)
        same = wo[..., 2] * wi[..., 2] > 0
        g = jnp.where(same, g, 0.0) * (1.0 / jnp.pi)
        return g[..., None] * r

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        _check_mode(mode)
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        _, (wo, wi, r, sigma) = _broadcast((wo, 1), (wi, 1), (self.reflectance, 1), (self.sigma, 0))
        return self._value(wo, wi, r, sigma)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        _check_mode(mode)
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        u2 = _u2(u2)
        _, (wo, u_lobe, u2, r, sigma) = _broadcast(
            (wo, 1), (u_lobe, 0), (u2, 1), (self.reflectance, 1), (self.sigma, 0)
        )
        x, y, z = _sample_cosine_hemisphere(u2[..., 0], u2[..., 1])
        z = jnp.where(wo[..., 2] < 0, -z, z)
        wi = _stack3(x, y, z)
        z = wi[..., 2]
        ok = (wo[..., 2] != 0) & (z != 0)
        s = BSDFSample(
            f=self._value(wo, wi, r, sigma),
            wi=wi,
            pdf=jnp.abs(z) * (1.0 / jnp.pi),
            is_delta=jnp.zeros(z.shape, bool),
            is_transmission=jnp.zeros(z.shape, bool),
            eta=jnp.ones_like(z),
            terminate_secondary=jnp.zeros(z.shape, bool),
        )
        return _failed_or(ok, s)

    def pdf(self, wo, wi) -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        _, (wo, wi, _s) = _broadcast((wo, 1), (wi, 1), (self.sigma, 0))
        same = wo[..., 2] * wi[..., 2] > 0
        batch = np.broadcast_shapes(wo.shape[:-1], self.reflectance.shape[:-1])
        return jnp.broadcast_to(jnp.where(same, jnp.abs(wi[..., 2]) * (1.0 / jnp.pi), 0.0), batch)


# --------------------------------------------------------------------------------------------
# Diffuse transmission


class DiffuseTransmissionBxDF(AbstractBxDF):
    r"""Lambertian reflection and Lambertian transmission (thesis section 3.1, diffuse BTDF).

    $$f(\omega_o, \omega_i) = \begin{cases} R/\pi & \omega_i \text{ on the side of } \omega_o\\
      T/\pi & \omega_i \text{ on the other side}\end{cases}$$

    A thin translucent sheet (paper, a lamp shade, a leaf) that scatters uniformly into both
    hemispheres, as pbrt-v4's `DiffuseTransmissionBxDF`. Its directional albedo is $R + T$
    for every incident direction, from either side, so $R + T \le 1$ (checked). No refraction
    happens, so there is no radiance factor: `mode` does not change `f`, and the BxDF is
    reciprocal across the sheet as well, $f(\omega_o, \omega_i) = f(\omega_i, \omega_o)$.

    Sampling (`Pharr2023` section 9.2): reflection with probability
    $p_r = \max_\lambda R/(\max_\lambda R + \max_\lambda T)$, otherwise transmission, each with
    a cosine-weighted hemisphere, so
    $p(\omega_i) = (p_r \text{ or } 1 - p_r)|\cos\theta_i|/\pi$. A black sheet
    ($R = T = 0$) samples transmission, with value and weight 0.

    **Fields:**

    - `reflectance`: $R$ in [0, 1], `(..., n_lambda)`. [dimensionless]
    - `transmittance`: $T$ in [0, 1], `(..., n_lambda)`, with $R + T \le 1$. [dimensionless]

    !!! note "Thesis"
        Section 3.1 (diffuse reflection; transmission "analogous to the BRDF", the BTDF),
        eq. (3.2), (3.4).

    ??? cite "References"
        `Lambert1760`; `Pharr2023` section 9.2 (`DiffuseTransmissionBxDF`, pbrt-v4).
    """

    reflectance: Array
    transmittance: Array

    def __init__(self, reflectance, transmittance):
        r = _spectral(reflectance, "reflectance")
        t = _spectral(transmittance, "transmittance")
        r = check_in_range(r, "reflectance", 0.0, 1.0, unit="dimensionless")
        t = check_in_range(t, "transmittance", 0.0, 1.0, unit="dimensionless")
        r, t = _spectral_pair(r, t)
        # Energy conservation, thesis eq. (3.2): absorptance = 1 - R - T >= 0.
        t = eqx.error_if(
            t,
            r + t > 1.0 + 1e-12,
            "`reflectance` + `transmittance` must be <= 1 [dimensionless] (energy "
            "conservation, thesis eq. 3.2); got a sum > 1.",
        )
        self.reflectance, self.transmittance = r, t

    def _p_reflect(self) -> Array:
        """Probability of sampling reflection, `(...)` (0.5 for a black sheet)."""
        pr = jnp.max(self.reflectance, axis=-1)
        pt = jnp.max(self.transmittance, axis=-1)
        return safe_div(pr, pr + pt)

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        _check_mode(mode)
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        _, (wo, wi, r, t) = _broadcast(
            (wo, 1), (wi, 1), (self.reflectance, 1), (self.transmittance, 1)
        )
        cc = wo[..., 2] * wi[..., 2]
        v = jnp.where((cc > 0)[..., None], r, jnp.where((cc < 0)[..., None], t, 0.0))
        return v * (1.0 / jnp.pi)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        _check_mode(mode)
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        u2 = _u2(u2)
        _, (wo, u_lobe, u2, r, t, pr) = _broadcast(
            (wo, 1),
            (u_lobe, 0),
            (u2, 1),
            (self.reflectance, 1),
            (self.transmittance, 1),
            (self._p_reflect(), 0),
        )
        x, y, z = _sample_cosine_hemisphere(u2[..., 0], u2[..., 1])
        reflect = u_lobe < pr
        # Reflection: wo's hemisphere; transmission: the other one.
        flip = (wo[..., 2] < 0) == reflect
        z = jnp.where(flip, -z, z)
        p_lobe = jnp.where(reflect, pr, 1.0 - pr)
        ok = (wo[..., 2] != 0) & (z != 0) & (p_lobe > 0)
        s = BSDFSample(
            f=jnp.where(reflect[..., None], r, t) * (1.0 / jnp.pi),
            wi=_stack3(x, y, z),
            pdf=p_lobe * jnp.abs(z) * (1.0 / jnp.pi),
            is_delta=jnp.zeros(z.shape, bool),
            is_transmission=~reflect,
            eta=jnp.ones_like(z),
            terminate_secondary=jnp.zeros(z.shape, bool),
        )
        return _failed_or(ok, s)

    def pdf(self, wo, wi) -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        _, (wo, wi, pr) = _broadcast((wo, 1), (wi, 1), (self._p_reflect(), 0))
        cc = wo[..., 2] * wi[..., 2]
        p_lobe = jnp.where(cc > 0, pr, jnp.where(cc < 0, 1.0 - pr, 0.0))
        return p_lobe * jnp.abs(wi[..., 2]) * (1.0 / jnp.pi)


# --------------------------------------------------------------------------------------------
# Retroreflection


def _power(c: Array, n: Array) -> Array:
    """c**n for c in (0, 1], n >= 0, with finite gradients; 0 where c <= 0."""
    pos = c > 0
    return jnp.where(pos, jnp.exp(n * jnp.log(jnp.where(pos, c, 1.0))), 0.0)


class RetroreflectiveBxDF(AbstractBxDF):
    r"""Retroreflection: a normalised cosine-power lobe around the direction of incidence.

    $$f(\omega_o, \omega_i) = R\,\frac{n + 2}{2\pi}\,\max(0, \omega_o\cdot\omega_i)^n
      \quad(\omega_i, \omega_o \text{ on the same side})$$

    With both directions pointing away from the surface, $\omega_i = \omega_o$ is the
    retroreflection (back towards the source): this is the Lafortune lobe
    $(C_x u_x v_x + C_y u_y v_y + C_z u_z v_z)^n$ with $C_x = C_y = C_z = 1$, the retroreflective
    case of `Lafortune1997` (the mirror lobe has $C_x = C_y = -1$), with the energy-conserving
    normalisation $(n + 2)/(2\pi)$ of the modified Phong model (`Lafortune1994`). It is
    reciprocal ($\omega_o\cdot\omega_i$ is symmetric). Its directional albedo is exactly $R$ at
    normal incidence and below $R$ elsewhere (the lobe is cut by the horizon and tilted away
    from the normal; for a narrow lobe it tends to $R\cos\theta_o$), so it conserves energy
    for every $R \le 1$. The exponent $n$ sets the width of the lobe (larger is narrower).

    Sampling draws $\omega_i$ from the lobe itself, $p(\omega_i) = \frac{n+1}{2\pi}
    (\omega_o\cdot\omega_i)^n$ over the half-space $\omega_o\cdot\omega_i > 0$ (`Lafortune1994`,
    on the concentric disk mapping); a direction below the horizon is a failed sample
    (`pdf = 0`), so `pdf` integrates to 1 minus the failure probability (1 at normal
    incidence), as for the microfacet BxDFs.

    **Fields:**

    - `reflectance`: $R$ in [0, 1], `(..., n_lambda)`. [dimensionless]
    - `exponent`: lobe exponent $n \ge 0$, `(...)`. [dimensionless]

    !!! note "Thesis"
        Section 3.1 ("Retroreflective Material"), eq. (3.4).

    ??? cite "References"
        `Lafortune1997`; `Lafortune1994`; `Pharr2023` section 9.1.
    """

    reflectance: Array
    exponent: Array

    def __init__(self, reflectance, exponent):
        r = _spectral(reflectance, "reflectance")
        self.reflectance = check_in_range(r, "reflectance", 0.0, 1.0, unit="dimensionless")
        n = as_float_array(exponent, "exponent")
        self.exponent = check_in_range(n, "exponent", 0.0, np.inf, unit="dimensionless")

    @staticmethod
    def _lobe(wo: Array, wi: Array, n: Array) -> tuple[Array, Array]:
        """(c^n, ok): the lobe value and where the pair lies in the lobe, same side."""
        c = jnp.sum(wo * wi, axis=-1)
        ok = (wo[..., 2] * wi[..., 2] > 0) & (c > 0)
        return jnp.where(ok, _power(c, n), 0.0), ok

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        _check_mode(mode)
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        _, (wo, wi, r, n) = _broadcast((wo, 1), (wi, 1), (self.reflectance, 1), (self.exponent, 0))
        cn, _ = self._lobe(wo, wi, n)
        return (cn * (n + 2.0) * (0.5 / jnp.pi))[..., None] * r

    def pdf(self, wo, wi) -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        _, (wo, wi, n) = _broadcast((wo, 1), (wi, 1), (self.exponent, 0))
        batch = np.broadcast_shapes(wo.shape[:-1], self.reflectance.shape[:-1])
        cn, _ = self._lobe(wo, wi, n)
        return jnp.broadcast_to(cn * (n + 1.0) * (0.5 / jnp.pi), batch)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        _check_mode(mode)
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        u2 = _u2(u2)
        _, (wo, _u, u2, r, n) = _broadcast(
            (wo, 1), (u_lobe, 0), (u2, 1), (self.reflectance, 1), (self.exponent, 0)
        )
        # Concentric disk point (dx, dy) with rho^2 uniform in [0, 1]: the power-cosine lobe's
        # inversion is cos(alpha) = (1 - rho^2)^(1/(n+1)), and (dx, dy)/rho a uniform azimuth.
        dx, dy = disk_concentric_xy(u2[..., 0], u2[..., 1])
        rho2 = dx * dx + dy * dy
        log_c = jnp.log1p(-jnp.minimum(rho2, 1.0)) / (n + 1.0)
        cos_a = jnp.exp(log_c)
        sin2_a = -jnp.expm1(2.0 * log_c)
        # sin(alpha)/rho -> sqrt(2/(n+1)) as rho -> 0.
        pos = rho2 > 0
        scale = jnp.where(
            pos, _sqrt_clamped(sin2_a / jnp.where(pos, rho2, 1.0)), jnp.sqrt(2.0 / (n + 1.0))
        )
        s, t = coordinate_system(wo)
        wi = (dx * scale)[..., None] * s + (dy * scale)[..., None] * t + cos_a[..., None] * wo
        cn, ok = self._lobe(wo, wi, n)
        s_ = BSDFSample(
            f=(cn * (n + 2.0) * (0.5 / jnp.pi))[..., None] * r,
            wi=wi,
            pdf=cn * (n + 1.0) * (0.5 / jnp.pi),
            is_delta=jnp.zeros(ok.shape, bool),
            is_transmission=jnp.zeros(ok.shape, bool),
            eta=jnp.ones(ok.shape, wi.dtype),
            terminate_secondary=jnp.zeros(ok.shape, bool),
        )
        return _failed_or(ok, s_)


# --------------------------------------------------------------------------------------------
# Smooth conductor


class ConductorBxDF(_AbstractDeltaBxDF):
    r"""Smooth conductor: perfect specular reflection weighted by the conductor Fresnel term.

    $f(\omega_o, \omega_i) = F_r(\cos\theta_o; \eta, \kappa)\,
    \delta(\omega_i - \omega_r)/|\cos\theta_i|$, with $\omega_r$ the mirror direction
    (thesis eq. 3.7-3.8) and $F_r$ from thesis eq. 3.13-3.18. `f` and `pdf` are 0 (a delta
    lobe); `sample_f` returns the mirror direction with `pdf = 1`, `is_delta = True`.

    **Fields:**

    - `eta`, `k`: relative complex index of refraction $\eta + i\kappa$ of the metal over the
        outside medium, `(..., n_lambda)`, `eta > 0`, `k >= 0` (tabulated metals:
        `radiometria.scattering.conductor_ior`). [dimensionless]

    !!! note "Thesis"
        Section 3.1 ("Perfectly Specular Reflection"), 3.1.1, eq. (3.7)-(3.8), (3.13)-(3.18).

    ??? cite "References"
        `Pharr2023` section 9.3.
    """

    eta: Array
    k: Array

    def __init__(self, eta, k):
        eta = _check_eta(_spectral(eta, "eta"))
        k = _check_k(_spectral(k, "k"))
        self.eta, self.k = _spectral_pair(eta, k)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        _check_mode(mode)
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        u2 = _u2(u2)
        _, (wo, _u, _v, eta, k) = _broadcast(
            (wo, 1), (u_lobe, 0), (u2, 1), (self.eta, 1), (self.k, 1)
        )
        wi = _mirror_xy(wo)
        c = jnp.abs(wi[..., 2])
        F = _fr_conductor(c[..., None], eta, k)
        ok = c > 0
        s = BSDFSample(
            f=safe_div(F, c[..., None]),
            wi=wi,
            pdf=jnp.ones_like(c),
            is_delta=jnp.ones(c.shape, bool),
            is_transmission=jnp.zeros(c.shape, bool),
            eta=jnp.ones_like(c),
            terminate_secondary=jnp.zeros(c.shape, bool),
        )
        return _failed_or(ok, s)


# --------------------------------------------------------------------------------------------
# Smooth dielectric


def _dispersive(eta: Array) -> Array:
    """True where eta differs across the wavelength axis, `(...)`."""
    return jnp.any(eta != eta[..., :1], axis=-1)


def _hero_only(x: Array) -> Array:
    """Zero all but the first entry of the last axis."""
    mask = jnp.arange(x.shape[-1]) == 0
    return jnp.where(mask, x, 0.0)


class DielectricBxDF(_AbstractDeltaBxDF):
    r"""Smooth dielectric interface: specular reflection and refraction (thesis 3.1.1).

    One of the two delta lobes is chosen with probability $F_r$ (reflection, thesis eq. 3.18)
    or $1 - F_r$ (transmission):

    - reflection: $\omega_i = \omega_r$ (eq. 3.8), $f = F_r/|\cos\theta_i|$, pdf $= F_r$;
    - transmission: $\omega_i = \omega_t$ (eq. 3.12), $f = (1 - F_r)/|\cos\theta_i| \cdot
      1/\eta'^2$ in radiance transport, pdf $= 1 - F_r$,

    where $\eta'$ is the relative index $\eta_t/\eta_i$ seen from `wo`'s side ($\eta$ for `wo`
    outside, $1/\eta$ inside). The factor $1/\eta'^2$ is the $(\eta_t/\eta_i)^2$ radiance factor
    of thesis eq. 3.15-3.16 written for light travelling from `wi` to `wo` (the radiance that
    arrives at `wo`'s side is scaled by $(\eta_{wo}/\eta_{wi})^2 = 1/\eta'^2$; see
    `fresnel_dielectric_transmittance`). It is omitted for `mode="importance"`.

    Total internal reflection makes $F_r = 1$. `eta = 1` (index matched) transmits straight
    through. For spectrally varying `eta` see the module notes on dispersion.

    **Fields:**

    - `eta`: relative index of refraction $\eta_t/\eta_i$ of the inside over the outside
        (the side the normal points to), > 0, `(..., n_lambda)`. [dimensionless]
    - `dispersion`: static; whether `eta` varies with wavelength (see the module notes).

    !!! note "Thesis"
        Section 3.1.1, eq. (3.7)-(3.18).

    ??? cite "References"
        `Pharr2023` section 9.5; `Walter2007`.
    """

    eta: Array
    dispersion: bool = eqx.field(static=True)

    def __init__(self, eta, *, dispersion: bool | None = None):
        self.eta = _check_eta(_spectral(eta, "eta"))
        self.dispersion = _detect_dispersion(self.eta, dispersion)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        _check_mode(mode)
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        u2 = _u2(u2)
        # 1 / eta once per material, before broadcasting over the batch.
        _, (wo, u_lobe, _v, eta, inv_eta) = _broadcast(
            (wo, 1), (u_lobe, 0), (u2, 1), (self.eta, 1), (1.0 / self.eta, 1)
        )
        ox, oy, oz = _xyz(wo)
        # The hero wavelength (index 0) chooses the lobe and the refracted direction.
        R_h, _, etap_h, inv_etap_h, cos_t, _ = _fr_dielectric_snell(
            oz, eta[..., 0], inv_eta[..., 0]
        )
        reflect = u_lobe < R_h
        # Reflection about +z (thesis eq. 3.8): (-x, -y, z). Refraction (thesis eq. 3.12)
        # through +z with the hero's relative index: (-x / eta', -y / eta', -+cos_t), on the
        # opposite side of wo.
        scale = jnp.where(reflect, 1.0, inv_etap_h)
        iz = jnp.where(reflect, oz, jnp.where(oz < 0, cos_t, -cos_t))
        wi = _stack3(-ox * scale, -oy * scale, iz)
        c = jnp.abs(iz)
        if self.dispersion:
            # Every wavelength's own Fresnel term; secondaries end at a transmission.
            R, _, _, inv_etap, _, _ = _fr_dielectric_snell(oz[..., None], eta, inv_eta)
            disp = _dispersive(eta)
        else:
            R, inv_etap = R_h[..., None], inv_etap_h[..., None]
            disp = jnp.zeros(c.shape, bool)
        T = 1.0 - R
        ft = T if mode == "importance" else T * (inv_etap * inv_etap)
        ft = jnp.where(disp[..., None], _hero_only(ft), ft)
        pdf = jnp.where(reflect, R_h, 1.0 - R_h)
        ok = (c > 0) & (pdf > 0)
        pdf = jnp.where(ok, pdf, 0.0)
        # 1/|cos theta_i|, and 0 (= 1/inf) for a failed sample.
        inv_c = 1.0 / jnp.where(ok, c, jnp.inf)
        f = jnp.where(reflect[..., None], R, ft) * inv_c[..., None]
        f = jnp.broadcast_to(f, eta.shape)
        s = BSDFSample(
            f=f,
            wi=wi,
            pdf=pdf,
            is_delta=jnp.ones(c.shape, bool),
            is_transmission=~reflect,
            eta=jnp.where(reflect, 1.0, etap_h),
            terminate_secondary=~reflect & disp,
        )
        return _failed_or(ok, s, masked=True)


# --------------------------------------------------------------------------------------------
# Rough conductor


def _check_masking(masking: str) -> str:
    return check_choice(masking, "masking", ("height_correlated", "separable"))


_DISTRIBUTIONS = {"ggx": TrowbridgeReitzDistribution, "beckmann": BeckmannDistribution}


def _make_distribution(distribution: str, alpha_x, alpha_y):
    """The microfacet distribution named `distribution` ("ggx" or "beckmann")."""
    if not isinstance(distribution, str):
        raise TypeError(
            f"`distribution` must be a name ('ggx' or 'beckmann'), got {type(distribution)}."
        )
    name = check_choice(distribution, "distribution", tuple(_DISTRIBUTIONS))
    return _DISTRIBUTIONS[name](alpha_x, alpha_y)


def _is_ggx(distribution) -> bool:
    """GGX has closed forms in which the cosines cancel (the fast path of the rough BxDFs)."""
    return isinstance(distribution, TrowbridgeReitzDistribution)


def _at(distribution, ax: Array, ay: Array):
    """`distribution` with its roughness replaced by the batch-broadcast `ax`, `ay` (already
    validated at construction, so not checked again)."""
    return eqx.tree_at(lambda d: (d.alpha_x, d.alpha_y), distribution, (ax, ay))


def _generic_terms(distribution, o, i, m, ax, ay, masking: str):
    r"""(D(m), Lambda(wo), G) of any distribution, vectors as (x, y, z); G is the
    height-correlated $1/(1 + \Lambda_o + \Lambda_i)$ or the separable $G_1G_1$."""
    d = _at(distribution, ax, ay)
    D = d._D_xyz(*m)
    lo, li = d._lambda_xyz(*o), d._lambda_xyz(*i)
    if masking == "height_correlated":
        G = 1.0 / (1.0 + lo + li)
    else:
        G = 1.0 / ((1.0 + lo) * (1.0 + li))
    return D, lo, G


def _sample_m(distribution, o, ax, ay, u0, u1) -> tuple[Array, Array, Array]:
    """A visible microfacet normal for `o` = (x, y, z), as (x, y, z) (both distributions
    sample component-wise)."""
    return _at(distribution, ax, ay)._sample_wm_xyz(*o, u0, u1)


class RoughConductorBxDF(AbstractBxDF):
    r"""Rough conductor: Torrance-Sparrow microfacet BRDF, GGX or Beckmann distribution.

    $$f(\omega_o, \omega_i) = \frac{D(\omega_h)\,F_r(|\omega_o\cdot\omega_h|)\,
      G(\omega_o, \omega_i)}{4\,|\cos\theta_o|\,|\cos\theta_i|},\qquad
      \omega_h = \frac{\omega_o + \omega_i}{\|\omega_o + \omega_i\|}$$

    $F_r$ is the conductor Fresnel term (thesis eq. 3.13-3.18), $D$ the microfacet distribution
    (`TrowbridgeReitzDistribution`, "ggx", or `BeckmannDistribution`, "beckmann") and
    $G$ Smith's masking-shadowing: height-correlated (`masking="height_correlated"`, pbrt-v4,
    `Heitz2014`) or separable $G_1G_1$ (`masking="separable"`, Mitsuba 3). Sampled with the
    distribution of visible normals (`Heitz2018`):
    $p(\omega_i) = D_{\omega_o}(\omega_h)/(4|\omega_o\cdot\omega_h|)$.

    Single scattering only: energy reflected more than once between microfacets is lost, so
    the white-furnace albedo is below 1 for rough surfaces (see `fig_3_albedo_roughness`).

    **Fields:**

    - `alpha_x`, `alpha_y`: roughness in (0, 1], `(...)` (`alpha_y` defaults to `alpha_x`).
        [dimensionless]
    - `eta`, `k`: relative complex index of refraction, `(..., n_lambda)`. [dimensionless]
    - `masking`: `"height_correlated"` (default) or `"separable"`.
    - `distribution`: `"ggx"` (default) or `"beckmann"` (Mitsuba 3's default); stored as the
        distribution object in the field `distribution`.

    !!! note "Thesis"
        Section 3.1 ("Glossy Specular Reflection"), eq. (3.4), (3.13)-(3.18).

    ??? cite "References"
        `Torrance1967`; `Walter2007`; `Heitz2014`; `Heitz2018`; `Pharr2023` section 9.6.
    """

    distribution: TrowbridgeReitzDistribution | BeckmannDistribution
    eta: Array
    k: Array
    masking: str = eqx.field(static=True)

    def __init__(
        self,
        alpha_x,
        eta,
        k,
        alpha_y=None,
        *,
        masking: str = "height_correlated",
        distribution: str = "ggx",
    ):
        self.distribution = _make_distribution(distribution, alpha_x, alpha_y)
        eta = _check_eta(_spectral(eta, "eta"))
        k = _check_k(_spectral(k, "k"))
        self.eta, self.k = _spectral_pair(eta, k)
        self.masking = _check_masking(masking)

    def _bcast_all(self, *items):
        d = self.distribution
        return _broadcast(*items, (d.alpha_x, 0), (d.alpha_y, 0), (self.eta, 1), (self.k, 1))

    def _eval(self, o, i, m, ax, ay, ok, dot) -> tuple[Array, Array]:
        r"""(D G / (4 |cos cos|), pdf) for the microfacet normal `m` (unit, facing +z), zero where
        not `ok`; `dot` = |wo . wm| > 0 is needed for the pdf. Vectors as (x, y, z).

        With $G_1(\omega) = 2|z|/(|z| + r)$ (`TrowbridgeReitzDistribution.G1`) the cosines
        cancel: $DG_1G_1/(4|z_oz_i|) = 1/(D^{-1}(|z_o| + r_o)(|z_i| + r_i))$ (separable),
        $DG/(4|z_oz_i|) = 1/(2D^{-1}(|z_i|r_o + |z_o|r_i))$ (height-correlated), and
        $D_{\omega_o}(\omega_m)/(4|\omega_o\cdot\omega_m|) = 1/(2D^{-1}(|z_o| + r_o))$.
        """
        (ox, oy, oz), (ix, iy, iz), (mx, my, mz) = o, i, m
        aoz, aiz = jnp.abs(oz), jnp.abs(iz)
        ok_p = ok & (dot > 0)
        if not _is_ggx(self.distribution):
            # Any distribution: v = D G / (4 |z_o z_i|), p = D G_1(wo) / (4 |z_o|).
            D, lo, G = _generic_terms(self.distribution, o, i, m, ax, ay, self.masking)
            v = jnp.where(ok, D * G / jnp.where(ok, 4.0 * aoz * aiz, 1.0), 0.0)
            p = jnp.where(ok_p, D / jnp.where(ok_p, 4.0 * aoz * (1.0 + lo), 1.0), 0.0)
            return v, p
        ro, ri = _slope_root(ox, oy, oz, ax, ay), _slope_root(ix, iy, iz, ax, ay)
        go = aoz + ro
        d_inv = _D_den(mx, my, mz, ax, ay)
        # Each result ends in its division (0 = 1/inf where masked), so XLA's CPU backend
        # computes it once instead of in every wavelength of the consumer.
        if self.masking == "height_correlated":
            v = 0.5 / jnp.where(ok, d_inv * (aiz * ro + aoz * ri), jnp.inf)
            p = 0.5 / jnp.where(ok_p, d_inv * go, jnp.inf)
        else:
            gi = aiz + ri
            v = 1.0 / jnp.where(ok, d_inv * go * gi, jnp.inf)
            p = jnp.where(ok_p, 0.5 * v * gi, 0.0)
        return v, p

    def _half(self, wo, wi, ax, ay):
        """(D G / (4 |cos cos|), |wo . wm|, pdf) at the half vector of `wo` and `wi` (zero where
        wi = -wo or the two lie on opposite sides)."""
        o, i = _xyz(wo), _xyz(wi)
        hx, hy, hz = o[0] + i[0], o[1] + i[1], o[2] + i[2]
        n2 = hx * hx + hy * hy + hz * hz
        nonzero = n2 > 0
        norm = jnp.sqrt(jnp.where(nonzero, n2, 1.0))
        # Face the half vector forward (+z): sample_wm only produces m_z > 0 (D is even).
        inv = jnp.where(hz < 0, -1.0, 1.0) / norm
        dot = jnp.abs(o[0] * hx + o[1] * hy + o[2] * hz) / norm
        ok = (o[2] * i[2] > 0) & nonzero
        v, p = self._eval(o, i, (hx * inv, hy * inv, hz * inv), ax, ay, ok, dot)
        return v, dot, p

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        _check_mode(mode)
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        _, (wo, wi, ax, ay, eta, k) = self._bcast_all((wo, 1), (wi, 1))
        v, dot, _ = self._half(wo, wi, ax, ay)
        return v[..., None] * _fr_conductor(dot[..., None], eta, k)

    def pdf(self, wo, wi) -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        _, (wo, wi, ax, ay, _e, _k) = self._bcast_all((wo, 1), (wi, 1))
        return self._half(wo, wi, ax, ay)[2]

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        _check_mode(mode)
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        u2 = _u2(u2)
        _, (wo, _u, u2, ax, ay, eta, k) = self._bcast_all((wo, 1), (u_lobe, 0), (u2, 1))
        o = ox, oy, oz = _xyz(wo)
        m = mx, my, mz = _sample_m(self.distribution, o, ax, ay, u2[..., 0], u2[..., 1])
        # wi = reflect(wo, wm)   (thesis eq. 3.8); wm is the half vector of wo and wi.
        c = ox * mx + oy * my + oz * mz
        i = 2.0 * c * mx - ox, 2.0 * c * my - oy, 2.0 * c * mz - oz
        dot = jnp.abs(c)
        ok = (oz * i[2] > 0) & (dot > 0)
        v, pdf = self._eval(o, i, m, ax, ay, ok, dot)
        s = BSDFSample(
            f=v[..., None] * _fr_conductor(dot[..., None], eta, k),
            wi=_stack3(*i),
            pdf=pdf,
            is_delta=jnp.zeros(ok.shape, bool),
            is_transmission=jnp.zeros(ok.shape, bool),
            eta=jnp.ones(ok.shape, wo.dtype),
            terminate_secondary=jnp.zeros(ok.shape, bool),
        )
        return _failed_or(ok, s, masked=True)


# --------------------------------------------------------------------------------------------
# Rough dielectric


class RoughDielectricBxDF(AbstractBxDF):
    r"""Rough dielectric interface: microfacet reflection and transmission (`Walter2007`), with
    the GGX or Beckmann distribution.

    With the generalised half vector $\omega_m \propto \eta'\omega_i + \omega_o$ (facing +z),
    $\eta' = 1$ for reflection and $\eta'$ = relative index seen from `wo` for transmission:

    $$f_r = \frac{D(\omega_m) F G}{4|\cos\theta_o\cos\theta_i|},\qquad
      f_t = \frac{D(\omega_m)(1 - F) G}{(\omega_i\cdot\omega_m + \omega_o\cdot\omega_m/\eta')^2}
      \left|\frac{(\omega_i\cdot\omega_m)(\omega_o\cdot\omega_m)}{\cos\theta_i\cos\theta_o}\right|
      \frac{1}{\eta'^2}$$

    with $F = F_r(\omega_o\cdot\omega_m; \eta)$ (thesis eq. 3.18); the last factor is the
    radiance factor of eq. 3.15-3.16 (omitted for `mode="importance"`). Microfacets seen from
    their back are discarded. Sampling: a visible normal (`Heitz2018`), then reflection with
    probability $F$ or refraction (thesis eq. 3.12) otherwise.

    **Fields:**

    - `alpha_x`, `alpha_y`: roughness in (0, 1], `(...)`. [dimensionless]
    - `eta`: relative index of refraction inside/outside, > 0, `(..., n_lambda)`. [dimensionless]
    - `masking`: `"height_correlated"` (default) or `"separable"` (Mitsuba 3).
    - `distribution`: `"ggx"` (default) or `"beckmann"` (Mitsuba 3's default); stored as the
        distribution object in the field `distribution`.
    - `dispersion`: static; whether `eta` varies with wavelength (see the module notes).

    !!! note "Thesis"
        Section 3.1 (glossy reflection and transmission), 3.1.1.

    ??? cite "References"
        `Walter2007`; `Heitz2018`; `Pharr2023` section 9.7.
    """

    distribution: TrowbridgeReitzDistribution | BeckmannDistribution
    eta: Array
    masking: str = eqx.field(static=True)
    dispersion: bool = eqx.field(static=True)

    def __init__(
        self,
        alpha_x,
        eta,
        alpha_y=None,
        *,
        masking: str = "height_correlated",
        dispersion: bool | None = None,
        distribution: str = "ggx",
    ):
        self.distribution = _make_distribution(distribution, alpha_x, alpha_y)
        self.eta = _check_eta(_spectral(eta, "eta"))
        self.masking = _check_masking(masking)
        self.dispersion = _detect_dispersion(self.eta, dispersion)

    def _bcast_all(self, *items):
        d = self.distribution
        # 1 / eta once per material, before broadcasting over the batch.
        return _broadcast(
            *items, (d.alpha_x, 0), (d.alpha_y, 0), (self.eta, 1), (1.0 / self.eta, 1)
        )

    def _eval(self, o, i, ax, ay, eta, inv_eta, mode, m=None, mask=True) -> tuple[Array, Array]:
        """(f, pdf) for one eta per sample: `eta` and `inv_eta = 1 / eta` of shape `(...)`,
        vectors as (x, y, z).

        The generalised half vector $\\omega_m \\propto \\eta'\\omega_i + \\omega_o$ faces +z;
        back-facing microfacets are discarded (`Walter2007`, `Pharr2023` 9.7). `m`, when given,
        is that half vector (known in `sample_f`); f and pdf are zero where `mask` is False.
        With $G_1(\\omega) = 2|z|/(|z| + r)$ the cosines cancel: $DG/|z_oz_i| = g/D^{-1}$ with
        $g = 4/((|z_o| + r_o)(|z_i| + r_i))$ (separable) or $2/(|z_i|r_o + |z_o|r_i)$
        (height-correlated), and
        $D_{\\omega_o}(\\omega_m) = 2|\\omega_o\\cdot\\omega_m|/((|z_o| + r_o)D^{-1})$. With
        $S = \\eta'\\,\\omega_i\\cdot\\omega_m + \\omega_o\\cdot\\omega_m$ ($\\eta'$ times the
        denominator of the class formula) the transmission terms read
        $f_t = (1 - F)\\,g\\,|\\omega_i\\cdot\\omega_m\\,\\omega_o\\cdot\\omega_m|/(D^{-1}S^2)$ and
        $p_t = 2(1 - F)|\\omega_i\\cdot\\omega_m\\,\\omega_o\\cdot\\omega_m|\\,\\eta'^2 /
        ((|z_o| + r_o)D^{-1}S^2)$, so f and pdf of both lobes share one denominator.
        """
        (ox, oy, oz), (ix, iy, iz) = o, i
        reflect = oz * iz > 0
        etap = jnp.where(reflect, 1.0, jnp.where(oz > 0, eta, inv_eta))
        if m is None:
            hx, hy, hz = ix * etap + ox, iy * etap + oy, iz * etap + oz
            inv, nonzero = _inv_norm(hx, hy, hz)
            inv = jnp.where(hz < 0, -inv, inv)
            mx, my, mz = hx * inv, hy * inv, hz * inv
        else:
            (mx, my, mz), nonzero = m, True
        dot_o = ox * mx + oy * my + oz * mz
        dot_i = ix * mx + iy * my + iz * mz
        valid = (oz != 0) & (iz != 0) & nonzero & (dot_i * iz > 0) & (dot_o * oz > 0)
        F = _fr_dielectric_snell(dot_o, eta, inv_eta)[0]
        aoz, aiz = jnp.abs(oz), jnp.abs(iz)
        etap2 = etap * etap
        t = (1.0 - F) * jnp.abs(dot_i * dot_o)
        t_f = t * etap2 if mode == "importance" else t  # the 1/eta'^2 radiance factor
        if not _is_ggx(self.distribution):
            # Any distribution: f_r = D G F / (4|z_o z_i|), f_t = D G t_f / (|z_o z_i| S^2),
            # p_r = D G_1(wo) F / (4|z_o|), p_t = D G_1(wo) t eta'^2 / (|z_o| S^2).
            D, lo, G = _generic_terms(self.distribution, o, i, (mx, my, mz), ax, ay, self.masking)
            s = etap * dot_i + dot_o
            den = aoz * jnp.where(reflect, 4.0, s * s)
            use = valid & mask & (den > 0)
            den = jnp.where(use, den, 1.0)
            f = jnp.where(use, D * G * jnp.where(reflect, F, t_f) / (aiz * den), 0.0)
            pdf = jnp.where(use, D * jnp.where(reflect, F, t * etap2) / ((1.0 + lo) * den), 0.0)
            return f, pdf
        ro, ri = _slope_root(ox, oy, oz, ax, ay), _slope_root(ix, iy, iz, ax, ay)
        go = aoz + ro
        if self.masking == "height_correlated":
            gn, gd = 2.0, aiz * ro + aoz * ri
        else:
            gn, gd = 4.0, go * (aiz + ri)
        s = etap * dot_i + dot_o
        den = _D_den(mx, my, mz, ax, ay) * gd * go * jnp.where(reflect, 1.0, s * s)
        # Masked as 1/inf = 0, so that f and pdf end in their division: XLA's CPU backend then
        # computes them once instead of in every consumer (every wavelength of f).
        den = jnp.where(valid & mask & (den > 0), den, jnp.inf)
        f = (go * gn) * jnp.where(reflect, 0.25 * F, t_f) / den
        pdf = gd * jnp.where(reflect, 0.5 * F, 2.0 * t * etap2) / den
        return f, pdf

    def _spectral_f(self, o, i, ax, ay, eta, inv_eta, mode) -> Array:
        """Per-wavelength f `(..., n_lambda)`: the geometry is recomputed for every wavelength's
        eta when `dispersion`, else computed once with `eta[..., 0]` and broadcast."""
        if not self.dispersion:
            f, _ = self._eval(o, i, ax, ay, eta[..., 0], inv_eta[..., 0], mode)
            return jnp.broadcast_to(f[..., None], eta.shape)
        o_l = tuple(c[..., None] for c in o)
        i_l = tuple(c[..., None] for c in i)
        f, _ = self._eval(o_l, i_l, ax[..., None], ay[..., None], eta, inv_eta, mode)
        return f

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        _check_mode(mode)
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        _, (wo, wi, ax, ay, eta, inv_eta) = self._bcast_all((wo, 1), (wi, 1))
        return self._spectral_f(_xyz(wo), _xyz(wi), ax, ay, eta, inv_eta, mode)

    def pdf(self, wo, wi) -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        _, (wo, wi, ax, ay, eta, inv_eta) = self._bcast_all((wo, 1), (wi, 1))
        o, i = _xyz(wo), _xyz(wi)
        return self._eval(o, i, ax, ay, eta[..., 0], inv_eta[..., 0], "radiance")[1]

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        _check_mode(mode)
        (wo,) = _dirs(("wo", wo))
        u_lobe = as_float_array(u_lobe, "u_lobe")
        u2 = _u2(u2)
        _, (wo, u_lobe, u2, ax, ay, eta, inv_eta) = self._bcast_all((wo, 1), (u_lobe, 0), (u2, 1))
        eta_h, inv_eta_h = eta[..., 0], inv_eta[..., 0]
        o = ox, oy, oz = _xyz(wo)
        m = mx, my, mz = _sample_m(self.distribution, o, ax, ay, u2[..., 0], u2[..., 1])
        dot_o = ox * mx + oy * my + oz * mz
        # Fresnel and Snell's law at the microfacet with the hero's eta; the interface flips
        # when wo is on the back of the microfacet (etap = 1 / eta there).
        R, c, _, inv_etap, cos_t, tir = _fr_dielectric_snell(dot_o, eta_h, inv_eta_h)
        reflect = u_lobe < R
        # Reflection about wm (thesis eq. 3.8).
        c2 = 2.0 * dot_o
        # Refraction through wm (thesis eq. 3.12), with the normal nm = +-wm facing wo:
        # wt = -wo / eta' + (cos_i / eta' - cos_t) nm.
        b = jnp.where(dot_o < 0, cos_t - c * inv_etap, c * inv_etap - cos_t)
        a = jnp.where(reflect, c2, b)
        ov = jnp.where(reflect, 1.0, inv_etap)
        i = a * mx - ov * ox, a * my - ov * oy, a * mz - ov * oz
        iz = i[2]
        same = oz * iz > 0
        ok = jnp.where(reflect, same, ~tir & ~same & (iz != 0))
        f_h, pdf = self._eval(o, i, ax, ay, eta_h, inv_eta_h, mode, m=m, mask=ok)
        if self.dispersion:
            f = self._spectral_f(o, i, ax, ay, eta, inv_eta, mode)
            term = ~reflect & _dispersive(eta)
            f = jnp.where(term[..., None], _hero_only(f), f)
        else:
            f = jnp.broadcast_to(f_h[..., None], eta.shape)
            term = jnp.zeros(ok.shape, bool)
        ok = pdf > 0
        # f_h and the pdf are zero where the sample failed; the per-wavelength f is not.
        f = jnp.where(ok[..., None], f, 0.0) if self.dispersion else f
        etap_s = jnp.where(oz > 0, eta_h, inv_eta_h)
        s = BSDFSample(
            f=f,
            wi=_stack3(*i),
            pdf=pdf,
            is_delta=jnp.zeros(ok.shape, bool),
            is_transmission=~reflect,
            eta=jnp.where(reflect, 1.0, etap_s),
            terminate_secondary=term,
        )
        return _failed_or(ok, s, masked=True)


# --------------------------------------------------------------------------------------------
# Two-sided wrapper


def _flip_z(w: Array) -> Array:
    return jnp.concatenate([w[..., :2], -w[..., 2:]], axis=-1)


class TwoSidedBxDF(AbstractBxDF):
    r"""Different BxDFs on the two sides of a surface (Mitsuba's `twosided`).

    For `wo` on the front (+z) side the `front` BxDF is used as is. For `wo` on the back side,
    `wo` and `wi` are mirrored through the surface ($z \to -z$), `back` is evaluated in that
    mirrored frame (so each BxDF sees its own front side), and a sampled `wi` is mirrored back.
    Both BxDFs are evaluated and the result selected per element (no branching under `jit`).
    Meant for reflective BxDFs; a transmissive BxDF would couple the two sides.

    **Fields:**

    - `front`: BxDF of the side the normal points to.
    - `back`: BxDF of the other side; `None` (default) reuses `front`.

    Values and pdfs are those of the wrapped BxDFs [sr^-1].

    ??? cite "References"
        `Jakob2022` (Mitsuba 3 `twosided` plugin).
    """

    front: AbstractBxDF
    back: AbstractBxDF | None

    def __init__(self, front: AbstractBxDF, back: AbstractBxDF | None = None):
        if not isinstance(front, AbstractBxDF) or not (
            back is None or isinstance(back, AbstractBxDF)
        ):
            raise TypeError("`front` and `back` must be BxDFs (subclasses of AbstractBxDF).")
        self.front = front
        self.back = back

    def _back(self) -> AbstractBxDF:
        return self.front if self.back is None else self.back

    def f(self, wo, wi, *, mode: str = "radiance") -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        ff = self.front.f(wo, wi, mode=mode)
        fb = self._back().f(_flip_z(wo), _flip_z(wi), mode=mode)
        ff, fb = jnp.broadcast_arrays(ff, fb)
        back = wo[..., 2] < 0
        back = jnp.reshape(back, back.shape + (1,) * (ff.ndim - back.ndim))
        return jnp.where(back, fb, ff)

    def pdf(self, wo, wi) -> Array:
        wo, wi = _dirs(("wo", wo), ("wi", wi))
        pf = self.front.pdf(wo, wi)
        pb = self._back().pdf(_flip_z(wo), _flip_z(wi))
        pf, pb = jnp.broadcast_arrays(pf, pb)
        back = jnp.broadcast_to(wo[..., 2] < 0, pf.shape)
        return jnp.where(back, pb, pf)

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        (wo,) = _dirs(("wo", wo))
        sf = self.front.sample_f(wo, u_lobe, u2, mode=mode)
        sb = self._back().sample_f(_flip_z(wo), u_lobe, u2, mode=mode)
        sb = eqx.tree_at(lambda s: s.wi, sb, _flip_z(sb.wi))
        back = wo[..., 2] < 0

        def pick(a, b):
            a, b = jnp.broadcast_arrays(a, b)
            m = jnp.reshape(back, back.shape + (1,) * (a.ndim - back.ndim))
            m = jnp.broadcast_to(jnp.reshape(m, (1,) * (a.ndim - m.ndim) + m.shape), a.shape)
            return jnp.where(m, b, a)

        return jax.tree_util.tree_map(pick, sf, sb)
