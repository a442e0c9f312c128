"""Figures for `radiometria.scattering` (thesis chapter 3)."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..colorimetry import XYZ_to_sRGB, get_illuminant, sd_to_XYZ
from ..constants import VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM
from ..scattering import (
    ConductorBxDF,
    DielectricBxDF,
    DiffuseBxDF,
    DiffuseTransmissionBxDF,
    OrenNayarBxDF,
    RetroreflectiveBxDF,
    RoughConductorBxDF,
    RoughDielectricBxDF,
    conductor_ior,
    fresnel_conductor,
    fresnel_dielectric,
    fresnel_dielectric_polarized,
    reflect,
    refract,
)
from ._registry import figure, save


def fresnel_dielectric_data(*, smoke: bool = False) -> dict:
    """What the dielectric Fresnel figure plots, from `fresnel_dielectric_polarized` and
    `fresnel_dielectric` for glass, $\\eta = 1.5$.

    `theta` (n,) on $[0, \\pi/2]$ [rad] (n = 181 in smoke mode, else 901), `eta` = 1.5, and
    for `"outside"` (air to glass, $\\cos\\theta_i > 0$) and `"inside"` (glass to air, the
    same angles with $\\cos\\theta_i < 0$) a dict with `R_s`, `R_p` (s and p reflectances)
    and `F` (unpolarised) (n,) [dimensionless], `brewster` = $\\arctan\\eta_t/\\eta_i$ [deg]
    and, inside, `critical` = $\\arcsin(1/\\eta)$ [deg].
    """
    n = 181 if smoke else 901
    eta = 1.5
    theta = np.linspace(0.0, np.pi / 2, n)
    out = {"theta": theta, "eta": eta}
    for side in ("outside", "inside"):
        cos = np.cos(theta) if side == "outside" else -np.cos(theta)
        R_s, R_p = (np.asarray(x) for x in fresnel_dielectric_polarized(cos, eta))
        rel = eta if side == "outside" else 1.0 / eta
        out[side] = {
            "R_s": R_s,
            "R_p": R_p,
            "F": np.asarray(fresnel_dielectric(cos, eta)),
            "brewster": float(np.degrees(np.arctan(rel))),
        }
    out["inside"]["critical"] = float(np.degrees(np.arcsin(1.0 / eta)))
    return out


@figure("fig_3_fresnel_dielectric")
def fig_3_fresnel_dielectric(out_dir, *, smoke: bool = False):
    """Fresnel reflectance of glass (eta = 1.5) vs angle: s, p, unpolarised; Brewster's angle.

    Thesis eq. 3.13-3.18 with kappa = 0; the right panel is the same interface seen from inside
    the glass (eta = 1/1.5), with total internal reflection beyond the critical angle. The
    data are `fresnel_dielectric_data()`.
    """
    import matplotlib.pyplot as plt

    data = fresnel_dielectric_data(smoke=smoke)
    theta = data["theta"]
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0), sharey=True)
    for ax, side in zip(axes, ("outside", "inside"), strict=True):
        R_s, R_p, F = (data[side][k] for k in ("R_s", "R_p", "F"))
        deg = np.degrees(theta)
        ax.plot(deg, R_s, label=r"$\bar\rho_\perp$ (s)", color="tab:blue")
        ax.plot(deg, R_p, label=r"$\bar\rho_\parallel$ (p)", color="tab:red")
        ax.plot(deg, F, label=r"$F_r$ (unpolarised)", color="k", lw=2)
        theta_b = data[side]["brewster"]
        ax.axvline(theta_b, color="0.5", ls="--", lw=1)
        ax.annotate(
            f"Brewster {theta_b:.1f}°",
            (theta_b, 0.55),
            rotation=90,
            ha="right",
            va="center",
            fontsize=8,
        )
        if side == "inside":
            theta_c = data["inside"]["critical"]
            ax.axvline(theta_c, color="0.3", ls=":", lw=1)
            ax.annotate(
                f"critical angle {theta_c:.1f}°: total internal reflection",
                (theta_c + 2.0, 0.6),
                rotation=0,
                ha="left",
                va="center",
                fontsize=8,
            )
            ax.set_title(r"from inside the glass, $\eta_i = 1.5 \to \eta_t = 1$")
        else:
            ax.set_title(r"air to glass, $\eta_t/\eta_i = 1.5$")
        ax.set_xlabel(r"angle of incidence $\theta_i$ [deg]")
        ax.set_xlim(0, 90)
        ax.set_ylim(0, 1.02)
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("reflectance")
    axes[0].legend(fontsize=8, loc="upper left")
    fig.suptitle("Fresnel equations for a dielectric (thesis eq. 3.13-3.18)")
    return save(fig, out_dir, "fig_3_fresnel_dielectric")


def _srgb_of_reflectance(wl: np.ndarray, reflectance: np.ndarray) -> np.ndarray:
    """Gamma-encoded sRGB of a reflectance spectrum under D65 (colorimetry, thesis 2.2.2)."""
    d65 = get_illuminant("D65")
    s = np.interp(wl, np.asarray(d65.wavelengths_nm), np.asarray(d65.values))
    xyz = sd_to_XYZ(np.asarray(reflectance, float), np.asarray(wl, float), illuminant=s)
    return np.clip(np.asarray(XYZ_to_sRGB(xyz)), 0.0, 1.0)


_METALS = [("Au", "gold", "goldenrod"), ("Ag", "silver", "0.5"), ("Cu", "copper", "chocolate")]
_METALS.append(("Al", "aluminium", "steelblue"))


def fresnel_conductors_data(*, smoke: bool = False) -> dict:
    """What the metals figure plots, from `conductor_ior` and `fresnel_conductor`.

    `wavelengths_nm` (n,), 360-830 nm (n = 95 in smoke mode, else 471) [nm]; `theta` (m,) on
    $[0, \\pi/2]$ (m = 91 or 361) [rad]; and `metals`, `{symbol: dict}` for Au, Ag, Cu and Al
    with `name`, `eta`, `k` (n,), the tabulated optical constants [dimensionless], `R` (n,),
    the normal-incidence reflectance, `rgb` (3,), its gamma-encoded sRGB colour under D65,
    clipped to [0, 1], `eta_550`, `k_550` and `F_550` (m,), the reflectance against the
    angle of incidence at 550 nm.
    """
    wl = np.linspace(VISIBLE_WAVELENGTH_MIN_NM, VISIBLE_WAVELENGTH_MAX_NM, 95 if smoke else 471)
    theta = np.linspace(0, np.pi / 2, 91 if smoke else 361)
    metals = {}
    for sym, name, _ in _METALS:
        eta, k = (np.asarray(x) for x in conductor_ior(sym, wl))
        R = np.asarray(fresnel_conductor(1.0, eta, k))
        e550, k550 = (np.asarray(x) for x in conductor_ior(sym, 550.0))
        metals[sym] = {
            "name": name,
            "eta": eta,
            "k": k,
            "R": R,
            "rgb": _srgb_of_reflectance(wl, R),
            "eta_550": float(e550),
            "k_550": float(k550),
            "F_550": np.asarray(fresnel_conductor(np.cos(theta), e550, k550)),
        }
    return {"wavelengths_nm": wl, "theta": theta, "metals": metals}


@figure("fig_3_fresnel_conductors")
def fig_3_fresnel_conductors(out_dir, *, smoke: bool = False):
    """Gold, silver, copper (and aluminium): spectral eta, k, normal-incidence reflectance, colour.

    Tabulated optical constants (`radiometria.scattering.conductor_ior`), thesis eq. 3.13-3.18;
    the swatches are the sRGB colour of the normal-incidence reflectance under D65. The data
    are `fresnel_conductors_data()`.
    """
    import matplotlib.pyplot as plt

    data = fresnel_conductors_data(smoke=smoke)
    wl, theta = data["wavelengths_nm"], data["theta"]
    fig, axes = plt.subplots(1, 3, figsize=(13.0, 4.0))
    for idx, (sym, name, colour) in enumerate(_METALS):
        m = data["metals"][sym]
        axes[0].plot(wl, m["eta"], color=colour, label=rf"{name} $\eta$")
        axes[0].plot(wl, m["k"], color=colour, ls="--", label=rf"{name} $k$")
        axes[1].plot(wl, m["R"], color=colour, lw=2, label=name)
        axes[2].plot(np.degrees(theta), m["F_550"], color=colour, label=f"{name} (550 nm)")
        axes[1].add_patch(
            plt.Rectangle((640.0, 0.05 + 0.1 * idx), 35, 0.08, color=m["rgb"], ec="k")
        )
        axes[1].annotate(name, (680.0, 0.09 + 0.1 * idx), fontsize=7, va="center")
    axes[0].set_xlabel("wavelength [nm]")
    axes[0].set_ylabel(r"optical constants $\eta$, $k$")
    axes[0].set_title("Complex index of refraction")
    axes[0].legend(fontsize=6, ncol=2)
    axes[1].set_xlabel("wavelength [nm]")
    axes[1].set_ylabel("reflectance at normal incidence")
    axes[1].set_ylim(0, 1.02)
    axes[1].set_title("Spectral reflectance and colour (D65)")
    axes[1].legend(fontsize=7, loc="lower left")
    axes[1].annotate("sRGB colour (D65)", (640.0, 0.46), fontsize=7)
    axes[2].set_xlabel(r"angle of incidence $\theta_i$ [deg]")
    axes[2].set_ylabel(r"$F_r$")
    axes[2].set_ylim(0, 1.02)
    axes[2].set_title("Angular dependence at 550 nm")
    axes[2].legend(fontsize=7)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    fig.suptitle("Fresnel reflectance of metals (thesis eq. 3.13-3.18)")
    return save(fig, out_dir, "fig_3_fresnel_conductors")


_LOBE_ALPHAS = (0.05, 0.1, 0.2, 0.4, 0.7)


def brdf_lobes_data(*, smoke: bool = False) -> dict:
    """What the BRDF lobes figure plots: $f(\\omega_o, \\omega_i)\\cos\\theta_o$ in the plane of
    incidence for light from $\\omega_i$, $45°$ off the normal.

    `theta_i` [rad]; `wi` (3,) = $(-\\sin\\theta_i, 0, \\cos\\theta_i)$; `t` (n,) on
    $[-\\pi/2, \\pi/2]$, the signed polar angle of $\\omega_o = (\\sin t, 0, \\cos t)$ [rad]
    (n = 361 in smoke mode, else 1441); `ggx`, `{alpha: (n,)}` for `RoughConductorBxDF(alpha,
    1, 1e4)` (GGX, unit Fresnel term) [sr^-1], plotted divided by their maxima; `diffuse`,
    `[(label, colour, (n,))]` for `DiffuseBxDF(1)` and `OrenNayarBxDF(1, sigma)`, sigma 0.5
    and 1 rad [sr^-1].
    """
    theta_i = np.radians(45.0)
    wi = np.array([-np.sin(theta_i), 0.0, np.cos(theta_i)])
    t = np.linspace(-np.pi / 2, np.pi / 2, 361 if smoke else 1441)
    wo = jnp.asarray(np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], -1))
    ggx = {}
    for a in _LOBE_ALPHAS:
        b = RoughConductorBxDF(a, 1.0, 1e4)
        ggx[a] = np.asarray(b.f(wo, jnp.asarray(wi)))[:, 0] * np.cos(t)
    diffuse = []
    for b, label, c in [
        (DiffuseBxDF(1.0), "Lambert", "k"),
        (OrenNayarBxDF(1.0, 0.5), r"Oren-Nayar $\sigma$ = 0.5", "tab:red"),
        (OrenNayarBxDF(1.0, 1.0), r"Oren-Nayar $\sigma$ = 1", "tab:orange"),
    ]:
        diffuse.append((label, c, np.asarray(b.f(wo, jnp.asarray(wi)))[:, 0] * np.cos(t)))
    return {"theta_i": theta_i, "wi": wi, "t": t, "ggx": ggx, "diffuse": diffuse}


@figure("fig_3_brdf_lobes")
def fig_3_brdf_lobes(out_dir, *, smoke: bool = False):
    """Polar plots of f cos(theta_o) in the plane of incidence for GGX conductors and Lambert.

    Incidence at 45 degrees; rough conductor (`RoughConductorBxDF`, unit Fresnel term) for
    several roughnesses, the Lambertian lobe for reference (thesis fig. 3.1 categories). The
    data are `brdf_lobes_data()`.
    """
    import matplotlib.pyplot as plt

    data = brdf_lobes_data(smoke=smoke)
    theta_i, t = data["theta_i"], data["t"]
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.6), subplot_kw={"projection": "polar"})
    cmap = plt.cm.viridis
    alphas = list(data["ggx"])
    for j, a in enumerate(alphas):
        v = data["ggx"][a]
        axes[0].plot(t, v / v.max(), color=cmap(j / (len(alphas) - 1)), label=rf"$\alpha$ = {a}")
    axes[0].set_title(r"GGX conductor, $f\cos\theta_o$ (normalised)", fontsize=10)
    for label, c, v in data["diffuse"]:
        axes[1].plot(t, v, color=c, label=label)
    axes[1].set_title(r"diffuse lobes, $f\cos\theta_o$ [sr$^{-1}$]", fontsize=10)
    for ax in axes:
        ax.set_thetamin(-90)
        ax.set_thetamax(90)
        ax.set_theta_zero_location("N")
        ax.annotate(
            "",
            xy=(0, 0),
            xytext=(-theta_i, ax.get_rmax()),
            arrowprops={"arrowstyle": "->", "color": "0.4"},
        )
        ax.legend(fontsize=7, loc="lower left", bbox_to_anchor=(-0.1, -0.15))
    fig.suptitle(r"BRDF lobes in the plane of incidence, $\theta_i = 45°$ (thesis eq. 3.4)")
    return save(fig, out_dir, "fig_3_brdf_lobes")


def albedo_roughness_data(*, smoke: bool = False) -> dict:
    """What the albedo-roughness figure plots: Monte Carlo directional albedos (eq. 3.5).

    `alphas` (a,), GGX roughness on [0.05, 1] (a = 8 in smoke mode, else 20); `mus` (3,),
    the cosines of the outgoing direction $\\omega_o = (\\sqrt{1 - \\mu^2}, 0, \\mu)$; `n`,
    the sample count (4096 or 131072, the same uniforms, key 3, for every point); and
    `conductor`, `dielectric` (3, a, 2): the mean of `sample_f(...).weight()` and its
    standard error, for `RoughConductorBxDF(alpha, 1, 1e4)` (unit Fresnel term) and
    `RoughDielectricBxDF(alpha, 1.5)` (reflection plus transmission, importance transport)
    [dimensionless].
    """
    n = 4_096 if smoke else 131_072
    alphas = np.linspace(0.05, 1.0, 8 if smoke else 20)
    mus = np.array([1.0, 0.5, 0.2])
    key = jax.random.key(3)
    u = jax.random.uniform(key, (n, 3))

    @jax.jit
    def albedo_conductor(alpha, wo):
        s = RoughConductorBxDF(alpha, 1.0, 1e4).sample_f(wo, u[:, 0], u[:, 1:])
        w = s.weight()[:, 0]
        return jnp.mean(w), jnp.std(w) / np.sqrt(n)

    @jax.jit
    def albedo_dielectric(alpha, wo):
        s = RoughDielectricBxDF(alpha, 1.5).sample_f(wo, u[:, 0], u[:, 1:], mode="importance")
        w = s.weight()[:, 0]
        return jnp.mean(w), jnp.std(w) / np.sqrt(n)

    out = {"alphas": alphas, "mus": mus, "n": n}
    for name, fn in (("conductor", albedo_conductor), ("dielectric", albedo_dielectric)):
        res = []
        for mu in mus:
            wo = jnp.broadcast_to(jnp.array([np.sqrt(1 - mu * mu), 0.0, mu]), (n, 3))
            res.append([[float(x) for x in fn(jnp.asarray(a), wo)] for a in alphas])
        out[name] = np.array(res)
    return out


@figure("fig_3_albedo_roughness")
def fig_3_albedo_roughness(out_dir, *, smoke: bool = False):
    """Directional albedo of single-scattering GGX microfacets vs roughness: the energy loss.

    White furnace: a conductor with unit Fresnel term (k -> infinity) and a dielectric
    (eta = 1.5, reflection + transmission, importance transport); Monte Carlo estimates of
    thesis eq. 3.5 with their 2-sigma error bars (`hemispherical_directional_reflectance`).
    The data are `albedo_roughness_data()`.
    """
    import matplotlib.pyplot as plt

    data = albedo_roughness_data(smoke=smoke)
    alphas = data["alphas"]
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0), sharey=True)
    colours = ["tab:blue", "tab:green", "tab:red"]
    for i, (mu, c) in enumerate(zip(data["mus"], colours, strict=True)):
        for ax, name in zip(axes, ("conductor", "dielectric"), strict=True):
            res = data[name][i]
            ax.errorbar(
                alphas,
                res[:, 0],
                yerr=2 * res[:, 1],
                color=c,
                marker="o",
                ms=3,
                capsize=2,
                label=rf"$\cos\theta_o$ = {mu}",
            )
    axes[0].set_title("rough conductor, $F = 1$")
    axes[1].set_title(r"rough dielectric, $\eta = 1.5$ ($R + T$)")
    for ax in axes:
        ax.axhline(1.0, color="k", lw=0.8)
        ax.set_xlabel(r"GGX roughness $\alpha$")
        ax.grid(True, alpha=0.3)
        ax.set_ylim(0.0, 1.05)
        ax.legend(fontsize=8, loc="lower left")
    axes[0].set_ylabel(r"directional albedo $\rho(\omega_o)$ (eq. 3.5)")
    fig.suptitle("Energy loss of single-scattering microfacet models (white furnace)")
    return save(fig, out_dir, "fig_3_albedo_roughness")


# --------------------------------------------------------------------------------------------
# Reflection and transmission types (thesis fig. 3.1)

_THETA_LIGHT_DEG = 45.0  # fig. 3.1: light arrives 45 degrees off the normal [deg]


def _plane_directions(t: np.ndarray) -> np.ndarray:
    """Unit vectors $(\\sin t, 0, \\cos t)$ of the plane of incidence, $t$ from the normal."""
    return np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)


@eqx.filter_jit
def _f_importance(bxdf, wo, wi):
    return bxdf.f(wo, wi, mode="importance")


def reflection_types_data(*, n_angles: int = 721, n_samples: int = 65_536) -> list[dict]:
    """What fig. 3.1 plots: one dict per panel, the lobes computed with the library's BxDFs.

    The light arrives from $\\omega_l$, $45°$ off the normal in the $xz$ plane. Each dict has
    `title`, `bxdf`, `light` ($\\omega_l$, (3,)), and either

    - `kind="lobe"`: `t` (n_angles,), the polar angle from the normal over the whole circle
        [rad], and `lobe`, the scattered flux per unit solid angle
        $f(\\omega_l, \\omega)\\,|\\cos\\theta|$ at $\\omega = (\\sin t, 0, \\cos t)$ ($f$ in
        importance mode: $f(\\omega, \\omega_l)$, light from $\\omega_l$ into $\\omega$)
        [sr^-1]; or
    - `kind="delta"`: `directions` (k, 3), the specular directions from `sample_f`, and
        `fractions` (k,), the flux fraction each carries (pdf times weight: $F_r$, $1 - F_r$).

    and `albedo_r`, `albedo_t`: the reflected and transmitted fractions of the incident flux
    (Monte Carlo means of `sample_f` weights, `n_samples` samples, key 0), with their
    standard errors `se_r`, `se_t` [dimensionless].
    """
    theta_l = np.radians(_THETA_LIGHT_DEG)
    light = np.array([-np.sin(theta_l), 0.0, np.cos(theta_l)])
    eta_au, k_au = (np.asarray(x) for x in conductor_ior("Au", 550.0))
    panels = [
        ("diffuse reflection (Lambert, R = 0.8)", DiffuseBxDF(0.8), "lobe"),
        (r"glossy reflection (GGX, $\alpha$ = 0.25)", RoughConductorBxDF(0.25, 1.0, 1e4), "lobe"),
        ("perfectly specular reflection (gold)", ConductorBxDF(eta_au, k_au), "delta"),
        ("retroreflection (R = 0.8, n = 12)", RetroreflectiveBxDF(0.8, 12.0), "lobe"),
        ("diffuse transmission (R = 0.1, T = 0.7)", DiffuseTransmissionBxDF(0.1, 0.7), "lobe"),
        (r"specular transmission (glass, $\eta$ = 1.5)", DielectricBxDF(1.5), "delta"),
    ]
    t = np.linspace(-np.pi, np.pi, n_angles)
    u = jax.random.uniform(jax.random.key(0), (n_samples, 3))

    @eqx.filter_jit
    def scatter(bxdf, light):  # MC weights and transmission flags of sample_f from light
        wl = jnp.broadcast_to(light, (n_samples, 3))
        s = bxdf.sample_f(wl, u[:, 0], u[:, 1:], mode="importance")
        return s.weight()[:, 0], s.is_transmission

    out = []
    for title, bxdf, kind in panels:
        w, trans = (np.asarray(x) for x in scatter(bxdf, jnp.asarray(light)))
        d = {"title": title, "bxdf": bxdf, "kind": kind, "light": light}
        for side, mask in (("r", ~trans), ("t", trans)):
            wm = np.where(mask, w, 0.0)
            d[f"albedo_{side}"] = float(wm.mean())
            d[f"se_{side}"] = float(wm.std() / np.sqrt(n_samples))
        if kind == "lobe":
            wt = _plane_directions(t)
            f = np.asarray(_f_importance(bxdf, jnp.asarray(light), jnp.asarray(wt)))
            d.update(t=t, lobe=f[:, 0] * np.abs(wt[:, 2]))
        else:
            # u_lobe = 0 picks reflection, u_lobe -> 1 transmission (when there is one).
            lobes = bxdf.sample_f(
                jnp.asarray(np.broadcast_to(light, (2, 3))),
                jnp.asarray([0.0, 1.0 - 1e-7]),
                jnp.full((2, 2), 0.5),
                mode="importance",
            )
            frac = np.asarray(lobes.pdf) * np.asarray(lobes.weight())[:, 0]
            dirs = np.asarray(lobes.wi)
            keep = [0] + ([1] if bool(np.asarray(lobes.is_transmission)[1]) else [])
            d.update(directions=dirs[keep], fractions=frac[keep])
        out.append(d)
    return out


@figure("fig_3_1_reflection_types")
def fig_3_1_reflection_types(out_dir, *, smoke: bool = False):
    """Types of reflection and transmission, drawn from the library's BxDFs.

    Polar plots in the plane of incidence of the flux scattered per unit solid angle,
    $f(\\omega, \\omega_l)|\\cos\\theta|$, for light arriving $45°$ off the normal (grey arrow):
    diffuse (`DiffuseBxDF`), glossy (`RoughConductorBxDF`, GGX, unit Fresnel term), perfectly
    specular (`ConductorBxDF`, gold at 550 nm), retroreflective (`RetroreflectiveBxDF`),
    diffuse transmission (`DiffuseTransmissionBxDF`, a Lambertian BRDF and BTDF) and specular
    transmission (`DielectricBxDF`, glass). The specular lobes are Dirac deltas, drawn as
    arrows whose length is the flux fraction they carry ($F_r$ and $1 - F_r$). Each panel
    states the reflected and transmitted fractions $\\rho$, $\\tau$ (Monte Carlo estimates from
    `sample_f`). Above the horizontal line is the reflection hemisphere, below transmission.
    The data are `reflection_types_data()`.

    !!! note "Thesis"
        Fig. 3.1, section 3.1 (diffuse, glossy specular, perfectly specular reflection,
        retroreflective material; transmission), eq. 3.4.
    """
    import matplotlib.pyplot as plt

    panels = reflection_types_data(
        n_angles=361 if smoke else 1441, n_samples=4_096 if smoke else 262_144
    )
    fig, axes = plt.subplots(
        2, 3, figsize=(12.0, 8.4), subplot_kw={"projection": "polar"}, layout="constrained"
    )
    for ax, p in zip(axes.ravel(), panels, strict=True):
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)  # t > 0 towards +x, on the right
        if p["kind"] == "lobe":
            r_max = 1.15 * float(p["lobe"].max())
            ax.fill(p["t"], p["lobe"], color="tab:blue", alpha=0.25)
            ax.plot(p["t"], p["lobe"], color="tab:blue", lw=1.4)
            ax.set_rlabel_position(100)
        else:
            r_max = 1.15
            for w, frac in zip(p["directions"], p["fractions"], strict=True):
                t = np.arctan2(w[0], w[2])
                ax.annotate(
                    "",
                    xy=(t, frac),
                    xytext=(0, 0),
                    arrowprops={"arrowstyle": "-|>", "color": "tab:blue", "lw": 2.2},
                )
                ax.annotate(
                    f"{frac:.2f}",
                    (t, frac),
                    textcoords="offset points",
                    xytext=(4, 4),
                    fontsize=8,
                    color="tab:blue",
                )
            ax.set_yticklabels([])
        t_l = np.arctan2(p["light"][0], p["light"][2])
        ax.annotate(
            "",
            xy=(0, 0),
            xytext=(t_l, r_max),
            arrowprops={"arrowstyle": "-|>", "color": "0.45", "lw": 1.4},
        )
        ax.plot([np.pi / 2, -np.pi / 2], [r_max, r_max], color="k", lw=1.6)  # the surface
        ax.plot([np.pi / 2, -np.pi / 2], [0, 0], color="k", lw=1.6)
        ax.set_rmax(r_max)
        ax.set_xticks(np.radians(np.arange(0, 360, 45)))
        ax.tick_params(labelsize=7)
        text = rf"$\rho$ = {p['albedo_r']:.3f}"
        if p["albedo_t"] > 0:
            text += rf", $\tau$ = {p['albedo_t']:.3f}"
        ax.set_title(f"{p['title']}\n{text}", fontsize=9)
    fig.suptitle(
        r"Reflection and transmission types, $f(\omega,\omega_l)\,|\cos\theta|$ [sr$^{-1}$], "
        r"light at $\theta_l$ = 45° (thesis fig. 3.1)"
    )
    return save(fig, out_dir, "fig_3_1_reflection_types")


# --------------------------------------------------------------------------------------------
# Specular reflection and refraction geometry (thesis fig. 3.2)

_REFRACTION_CASES = [  # (eta_i, eta_t, theta_i [deg]): air to glass; glass to air, below and
    (1.0, 1.5, 50.0),  # above the critical angle (41.8 deg)
    (1.5, 1.0, 30.0),
    (1.5, 1.0, 55.0),
]


def reflection_refraction_data(*, n_angles: int = 181) -> dict:
    """What fig. 3.2 plots, from `reflect`, `refract` and `fresnel_dielectric`.

    The interface is the plane $z = 0$ with normal $\\hat n = +z$ pointing into the medium
    of incidence $\\eta_i$; every direction points away from the interface (thesis
    convention). Keys:

    - `cases`: one dict per diagram with `eta_i`, `eta_t` [dimensionless], `theta_i` [rad],
        `wi` (3,) (towards the light), `wr` = `reflect(wi, n)`, `wt`, `valid` =
        `refract(wi, n, eta_t / eta_i)`, `theta_r`, `theta_t` [rad] measured from the
        library's directions ($\\theta_r$ from $+\\hat n$, $\\theta_t$ from $-\\hat n$; NaN
        under total internal reflection), and `R` = `fresnel_dielectric(cos theta_i,
        eta_t / eta_i)` (reflected fraction; $1 - R$ is transmitted);
    - `theta_i` (n_angles,) on $[0, \\pi/2)$ [rad] and, for `"air_glass"` ($\\eta_t/\\eta_i =
        1.5$) and `"glass_air"` ($1/1.5$), dicts with `theta_r`, `theta_t` (NaN where
        `valid` is False) and `valid`: the angle curves.
    """
    normal = np.array([0.0, 0.0, 1.0])

    def geometry(theta_i, eta):
        wi = np.stack([-np.sin(theta_i), np.zeros_like(theta_i), np.cos(theta_i)], axis=-1)
        wr = np.asarray(reflect(wi, normal))
        wt, valid = (np.asarray(x) for x in refract(wi, normal, eta))
        theta_r = np.arccos(np.clip(wr @ normal, -1.0, 1.0))
        theta_t = np.where(valid, np.arccos(np.clip(-(wt @ normal), -1.0, 1.0)), np.nan)
        return wi, wr, wt, valid, theta_r, theta_t

    cases = []
    for eta_i, eta_t, deg in _REFRACTION_CASES:
        theta_i = np.radians(deg)
        wi, wr, wt, valid, theta_r, theta_t = geometry(np.array(theta_i), eta_t / eta_i)
        R = float(np.asarray(fresnel_dielectric(np.cos(theta_i), eta_t / eta_i)))
        cases.append(
            {
                "eta_i": eta_i,
                "eta_t": eta_t,
                "theta_i": theta_i,
                "wi": wi,
                "wr": wr,
                "wt": wt,
                "valid": bool(valid),
                "theta_r": float(theta_r),
                "theta_t": float(theta_t),
                "R": R,
            }
        )
    theta = np.linspace(0.0, np.pi / 2, n_angles, endpoint=False)
    curves = {}
    for name, eta in (("air_glass", 1.5), ("glass_air", 1.0 / 1.5)):
        _, _, _, valid, theta_r, theta_t = geometry(theta, eta)
        curves[name] = {"theta_r": theta_r, "theta_t": theta_t, "valid": valid}
    return {"cases": cases, "theta_i": theta, **curves}


def _angle_arc(ax, start_deg: float, end_deg: float, radius: float, label: str, colour: str):
    """An arc between two polar angles of the diagram (degrees from +x), with its label."""
    from matplotlib.patches import Arc

    lo, hi = sorted((start_deg, end_deg))
    ax.add_patch(Arc((0, 0), 2 * radius, 2 * radius, theta1=lo, theta2=hi, color=colour, lw=1))
    mid = np.radians(0.5 * (lo + hi))
    ax.annotate(
        label,
        (1.3 * radius * np.cos(mid), 1.3 * radius * np.sin(mid)),
        color=colour,
        ha="center",
        va="center",
        fontsize=9,
    )


@figure("fig_3_2_reflection_refraction")
def fig_3_2_reflection_refraction(out_dir, *, smoke: bool = False):
    """Geometry of specular reflection and refraction at a smooth interface.

    Three diagrams in the plane of incidence: light from air onto glass, and from glass into
    air below and beyond the critical angle $\\theta_c = \\arcsin(\\eta_t/\\eta_i)$ (total
    internal reflection). The reflected and refracted rays are `reflect` and `refract` of
    the incident direction; the angles $\\theta_i$, $\\theta_r = \\theta_i$ (law of reflection)
    and $\\theta_t$ with $\\eta_i\\sin\\theta_i = \\eta_t\\sin\\theta_t$ (Snell's law) are measured
    on those vectors, and each ray's opacity is its flux fraction $R$, $1 - R$ from
    `fresnel_dielectric`. Right: $\\theta_r$ and $\\theta_t$ against $\\theta_i$ for both
    directions of travel. The data are `reflection_refraction_data()`.

    !!! note "Thesis"
        Fig. 3.2, eq. 3.7-3.12, section 3.1.1.
    """
    import matplotlib.pyplot as plt

    data = reflection_refraction_data(n_angles=91 if smoke else 451)
    fig, axes = plt.subplots(1, 4, figsize=(17.0, 4.4), layout="constrained")
    for ax, c in zip(axes[:3], data["cases"], strict=True):
        glass_top = c["eta_i"] > c["eta_t"]
        ax.add_patch(
            plt.Rectangle(
                (-1.3, -1.3),
                2.6,
                1.3,
                color="lightsteelblue" if not glass_top else "white",
                zorder=0,
            )
        )
        ax.add_patch(
            plt.Rectangle(
                (-1.3, 0.0), 2.6, 1.3, color="lightsteelblue" if glass_top else "white", zorder=0
            )
        )
        ax.axhline(0.0, color="k", lw=1.2)
        ax.plot([0, 0], [-1.2, 1.2], color="0.4", ls="--", lw=0.8)
        ax.annotate(r"$\hat n$", (0.03, 1.12), fontsize=10)
        xz = lambda w: (w[0], w[2])  # noqa: E731 -- the diagram shows the xz plane
        ax.annotate(
            "",
            xy=(0, 0),
            xytext=xz(c["wi"]),
            arrowprops={"arrowstyle": "-|>", "color": "k", "lw": 1.8},
        )
        ax.annotate(
            "",
            xy=xz(c["wr"]),
            xytext=(0, 0),
            arrowprops={
                "arrowstyle": "-|>",
                "color": "tab:blue",
                "lw": 1.8,
                "alpha": max(c["R"], 0.15),
            },
        )
        deg = lambda w: np.degrees(np.arctan2(w[2], w[0]))  # noqa: E731
        _angle_arc(ax, 90.0, deg(c["wi"]), 0.35, r"$\theta_i$", "k")
        _angle_arc(ax, 90.0, deg(c["wr"]), 0.45, r"$\theta_r$", "tab:blue")
        text = (
            rf"$\eta_i$ = {c['eta_i']:g}, $\eta_t$ = {c['eta_t']:g}"
            "\n"
            rf"$\theta_i$ = {np.degrees(c['theta_i']):.1f}°, "
            rf"$\theta_r$ = {np.degrees(c['theta_r']):.1f}°"
        )
        if c["valid"]:
            ax.annotate(
                "",
                xy=xz(c["wt"]),
                xytext=(0, 0),
                arrowprops={
                    "arrowstyle": "-|>",
                    "color": "tab:red",
                    "lw": 1.8,
                    "alpha": max(1.0 - c["R"], 0.15),
                },
            )
            _angle_arc(ax, -90.0, deg(c["wt"]), 0.4, r"$\theta_t$", "tab:red")
            text += rf", $\theta_t$ = {np.degrees(c['theta_t']):.1f}°"
            text += "\n" + rf"$R$ = {c['R']:.3f}, $T$ = {1 - c['R']:.3f}"
            title = "refraction" + (" into glass" if not glass_top else " into air")
        else:
            text += "\n" + r"total internal reflection, $R$ = 1"
            title = r"beyond the critical angle $\theta_c$"
        ax.text(-1.25, -1.25, text, fontsize=8, va="bottom")
        ax.set_xlim(-1.3, 1.3)
        ax.set_ylim(-1.3, 1.3)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(title, fontsize=10)
    ax = axes[3]
    deg_i = np.degrees(data["theta_i"])
    ax.plot(
        deg_i,
        np.degrees(data["air_glass"]["theta_r"]),
        color="tab:blue",
        label=r"$\theta_r$ (both)",
    )
    ax.plot(
        deg_i,
        np.degrees(data["air_glass"]["theta_t"]),
        color="tab:red",
        label=r"$\theta_t$, air $\to$ glass",
    )
    ax.plot(
        deg_i,
        np.degrees(data["glass_air"]["theta_t"]),
        color="tab:red",
        ls="--",
        label=r"$\theta_t$, glass $\to$ air",
    )
    theta_c = np.degrees(np.arcsin(1.0 / 1.5))
    ax.axvline(theta_c, color="0.4", ls=":", lw=1)
    ax.annotate(rf"$\theta_c$ = {theta_c:.1f}°", (theta_c + 1, 5), fontsize=8)
    ax.set_xlim(0, 90)
    ax.set_ylim(0, 90)
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.set_xlabel(r"$\theta_i$ [deg]")
    ax.set_ylabel("angle [deg]")
    ax.set_title(r"law of reflection and Snell's law, $\eta$ = 1.5", fontsize=10)
    ax.legend(fontsize=8, loc="upper left")
    fig.suptitle("Specular reflection and refraction (thesis fig. 3.2, eq. 3.7-3.12)")
    return save(fig, out_dir, "fig_3_2_reflection_refraction")
