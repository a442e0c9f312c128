"""Figures for `radiometria.scattering` (thesis chapter 3)."""

import jax
import jax.numpy as jnp
import numpy as np

from ..colorimetry import XYZ_to_sRGB, get_illuminant, sd_to_XYZ
from ..constants import VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM
from ..scattering import (
    DiffuseBxDF,
    OrenNayarBxDF,
    RoughConductorBxDF,
    RoughDielectricBxDF,
    conductor_ior,
    fresnel_conductor,
    fresnel_dielectric,
    fresnel_dielectric_polarized,
)
from ._registry import figure, save


@figure("fig_3_fresnel_dielectric")
def fig_3_fresnel_dielectric(out_dir, *, smoke: bool = False):
    """Fresnel reflectance of glass (eta = 1.5) vs angle: s, p, unpolarised; Brewster's angle.

    Thesis eq. 3.13-3.18 with kappa = 0; the right panel is the same interface seen from inside
    the glass (eta = 1/1.5), with total internal reflection beyond the critical angle.
    """
    import matplotlib.pyplot as plt

    n = 181 if smoke else 901
    eta = 1.5
    theta = np.linspace(0.0, np.pi / 2, n)
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0), sharey=True)
    for ax, side in zip(axes, ("outside", "inside"), strict=True):
        cos = np.cos(theta) if side == "outside" else -np.cos(theta)
        R_s, R_p = (np.asarray(x) for x in fresnel_dielectric_polarized(cos, eta))
        F = np.asarray(fresnel_dielectric(cos, eta))
        deg = np.degrees(theta)
        ax.plot(deg, R_s, label=r"$\bar\rho_\perp$ (s)", color="tab:blue")
        ax.plot(deg, R_p, label=r"$\bar\rho_\parallel$ (p)", color="tab:red")
        ax.plot(deg, F, label=r"$F_r$ (unpolarised)", color="k", lw=2)
        rel = eta if side == "outside" else 1.0 / eta
        theta_b = np.degrees(np.arctan(rel))
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
            theta_c = np.degrees(np.arcsin(1.0 / eta))
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


@figure("fig_3_fresnel_conductors")
def fig_3_fresnel_conductors(out_dir, *, smoke: bool = False):
    """Gold, silver, copper (and aluminium): spectral eta, k, normal-incidence reflectance, colour.

    Tabulated optical constants (`radiometria.scattering.conductor_ior`), thesis eq. 3.13-3.18;
    the swatches are the sRGB colour of the normal-incidence reflectance under D65.
    """
    import matplotlib.pyplot as plt

    wl = np.linspace(VISIBLE_WAVELENGTH_MIN_NM, VISIBLE_WAVELENGTH_MAX_NM, 95 if smoke else 471)
    metals = [("Au", "gold", "goldenrod"), ("Ag", "silver", "0.5"), ("Cu", "copper", "chocolate")]
    metals.append(("Al", "aluminium", "steelblue"))
    fig, axes = plt.subplots(1, 3, figsize=(13.0, 4.0))
    theta = np.linspace(0, np.pi / 2, 91 if smoke else 361)
    for sym, name, colour in metals:
        eta, k = (np.asarray(x) for x in conductor_ior(sym, wl))
        axes[0].plot(wl, eta, color=colour, label=rf"{name} $\eta$")
        axes[0].plot(wl, k, color=colour, ls="--", label=rf"{name} $k$")
        R = np.asarray(fresnel_conductor(1.0, eta, k))
        rgb = _srgb_of_reflectance(wl, R)
        axes[1].plot(wl, R, color=colour, lw=2, label=name)
        e550, k550 = (np.asarray(x) for x in conductor_ior(sym, 550.0))
        axes[2].plot(
            np.degrees(theta),
            np.asarray(fresnel_conductor(np.cos(theta), e550, k550)),
            color=colour,
            label=f"{name} (550 nm)",
        )
        idx = [m[0] for m in metals].index(sym)
        axes[1].add_patch(plt.Rectangle((640.0, 0.05 + 0.1 * idx), 35, 0.08, color=rgb, ec="k"))
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


@figure("fig_3_brdf_lobes")
def fig_3_brdf_lobes(out_dir, *, smoke: bool = False):
    """Polar plots of f cos(theta_o) in the plane of incidence for GGX conductors and Lambert.

    Incidence at 45 degrees; rough conductor (`RoughConductorBxDF`, unit Fresnel term) for
    several roughnesses, the Lambertian lobe for reference (thesis fig. 3.1 categories).
    """
    import matplotlib.pyplot as plt

    theta_i = np.radians(45.0)
    wi = jnp.array([-np.sin(theta_i), 0.0, np.cos(theta_i)])
    t = np.linspace(-np.pi / 2, np.pi / 2, 361 if smoke else 1441)
    wo = jnp.asarray(np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], -1))
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.6), subplot_kw={"projection": "polar"})
    cmap = plt.cm.viridis
    alphas = [0.05, 0.1, 0.2, 0.4, 0.7]
    for j, a in enumerate(alphas):
        b = RoughConductorBxDF(a, 1.0, 1e4)
        v = np.asarray(b.f(wo, wi))[:, 0] * np.cos(t)
        axes[0].plot(t, v / v.max(), color=cmap(j / (len(alphas) - 1)), label=rf"$\alpha$ = {a}")
    axes[0].set_title(r"GGX conductor, $f\cos\theta_o$ (normalised)", fontsize=10)
    for b, label, c in [
        (DiffuseBxDF(1.0), "Lambert", "k"),
        (OrenNayarBxDF(1.0, 0.5), r"Oren-Nayar $\sigma$ = 0.5", "tab:red"),
        (OrenNayarBxDF(1.0, 1.0), r"Oren-Nayar $\sigma$ = 1", "tab:orange"),
    ]:
        v = np.asarray(b.f(wo, wi))[:, 0] * np.cos(t)
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


@figure("fig_3_albedo_roughness")
def fig_3_albedo_roughness(out_dir, *, smoke: bool = False):
    """Directional albedo of single-scattering GGX microfacets vs roughness: the energy loss.

    White furnace: a conductor with unit Fresnel term (k -> infinity) and a dielectric
    (eta = 1.5, reflection + transmission, importance transport); Monte Carlo estimates of
    thesis eq. 3.5 with their 2-sigma error bars (`hemispherical_directional_reflectance`).
    """
    import matplotlib.pyplot as plt

    n = 4_096 if smoke else 131_072
    alphas = np.linspace(0.05, 1.0, 8 if smoke else 20)
    mus = [1.0, 0.5, 0.2]
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

    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0), sharey=True)
    colours = ["tab:blue", "tab:green", "tab:red"]
    for mu, c in zip(mus, colours, strict=True):
        wo = jnp.broadcast_to(jnp.array([np.sqrt(1 - mu * mu), 0.0, mu]), (n, 3))
        for ax, fn in zip(axes, (albedo_conductor, albedo_dielectric), strict=True):
            res = np.array([[float(x) for x in fn(jnp.asarray(a), wo)] for a in alphas])
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
