"""Figures for `radiometria.colorimetry` (thesis section 2.2): CMFs and the xy diagram."""

import numpy as np

from ..colorimetry import (
    RGB_COLOURSPACES,
    CCT_to_uv,
    CCT_to_xy,
    UCS_uv_to_xy,
    XYZ_to_sRGB,
    XYZ_to_xy,
    get_cmfs,
    get_illuminant,
    sd_to_XYZ,
    srgb_eotf,
    srgb_eotf_inverse,
    xy_to_XYZ,
)
from ..constants import VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM
from ._registry import figure, save


def cmfs_figure_data() -> dict:
    """What fig. 2.1 plots: `{"rgb": ..., "lms": ..., "xyz": ...}`, each `(wavelengths_nm, values)`.

    - `rgb`: the CIE 1931 RGB colour-matching functions (Wright & Guild, the library's
        table `get_cmfs("Wright & Guild 1931 2 Degree RGB CMFs")`), (n,) [nm] and (n, 3);
    - `lms`: the Stockman & Sharpe (2000) 2° cone fundamentals $\bar l, \bar m, \bar s$
        (energy units, each normalised to a peak of 1), as colour-science tabulates them
        (`colour.MSDS_CMFS["Stockman & Sharpe 2 Degree Cone Fundamentals"]`, from the CVRL
        database, http://www.cvrl.org, 390-830 nm in 1 nm steps) [dimensionless];
    - `xyz`: the CIE 1931 2° standard observer $\bar x, \bar y, \bar z$ (`get_cmfs()`).

    colour-science is a runtime dependency; it is imported here, when the figure is drawn,
    so that importing `radiometria` does not pay for it.
    """
    import colour

    lms = colour.MSDS_CMFS["Stockman & Sharpe 2 Degree Cone Fundamentals"]
    rgb = get_cmfs("Wright & Guild 1931 2 Degree RGB CMFs")
    xyz = get_cmfs("CIE 1931 2 Degree Standard Observer")
    return {
        "rgb": (np.asarray(rgb.wavelengths_nm), np.asarray(rgb.values)),
        "lms": (np.asarray(lms.wavelengths, float), np.asarray(lms.values, float)),
        "xyz": (np.asarray(xyz.wavelengths_nm), np.asarray(xyz.values)),
    }


@figure("fig_2_1_cmfs")
def fig_2_1_cmfs(out_dir, *, smoke: bool = False):
    """Colour-matching functions and cone sensitivities: CIE 1931 RGB, LMS, CIE 1931 XYZ.

    Left: the CIE 1931 RGB colour-matching functions (Wright & Guild) with the primaries'
    wavelengths. Middle: the spectral sensitivities of the three kinds of cones, the
    Stockman & Sharpe (2000) 2° cone fundamentals (colour-science's table). Right: the CIE
    1931 XYZ colour-matching functions, a linear transform of the RGB ones. The data are
    `cmfs_figure_data()`.

    !!! note "Thesis"
        Fig. 2.1, section 2.2.

    ??? cite "References"
        `Stockman2000`.
    """
    import matplotlib.pyplot as plt

    data = cmfs_figure_data()
    fig, (ax0, ax1, ax2) = plt.subplots(1, 3, figsize=(14.5, 3.8), layout="constrained")
    wl, v = data["rgb"]
    for k, (c, lab) in enumerate(zip("rgb", [r"$\bar r$", r"$\bar g$", r"$\bar b$"], strict=True)):
        ax0.plot(wl, v[:, k], color=c, label=lab)
    ax0.axhline(0.0, color="k", lw=0.6)
    for p in (435.8, 546.1, 700.0):  # the CIE 1931 RGB primaries (thesis section 2.2)
        ax0.axvline(p, color="0.6", ls=":", lw=0.8)
    ax0.set_title("CIE 1931 RGB colour-matching functions")
    ax0.set_ylabel("tristimulus value")
    wl, v = data["lms"]
    for k, (c, lab) in enumerate(
        zip(
            ["tab:red", "tab:green", "tab:blue"],
            [r"L ($\bar l$)", r"M ($\bar m$)", r"S ($\bar s$)"],
            strict=True,
        )
    ):
        ax1.plot(wl, v[:, k], color=c, label=lab)
    ax1.set_title("cone fundamentals (Stockman & Sharpe 2°)")
    ax1.set_ylabel("relative sensitivity (energy)")
    wl, v = data["xyz"]
    colours, labels = ["tab:red", "tab:green", "tab:blue"], [r"$\bar x$", r"$\bar y$", r"$\bar z$"]
    for k, (c, lab) in enumerate(zip(colours, labels, strict=True)):
        ax2.plot(wl, v[:, k], color=c, label=lab)
    ax2.set_title("CIE 1931 XYZ colour-matching functions (2°)")
    for ax in (ax0, ax1, ax2):
        ax.set_xlim(VISIBLE_WAVELENGTH_MIN_NM, VISIBLE_WAVELENGTH_MAX_NM)
        ax.set_xlabel("wavelength [nm]")
        ax.legend()
        ax.grid(True, alpha=0.3)
    return save(fig, out_dir, "fig_2_1_cmfs")


def _spectral_locus_xy() -> np.ndarray:
    v = np.asarray(get_cmfs().values)[:421]  # 360-780 nm; beyond, the locus folds back on itself
    return v[:, :2] / v.sum(axis=1, keepdims=True)


def _horseshoe_image(locus: np.ndarray, n: int) -> np.ndarray:
    """RGBA image of the xy diagram filled with (normalised, gamut-clipped) sRGB colours."""
    from matplotlib.path import Path as MplPath

    x = np.linspace(0.0, 0.8, n)
    y = np.linspace(0.0, 0.9, n)
    X, Y = np.meshgrid(x, y)
    xy = np.stack([X.ravel(), Y.ravel()], axis=-1)
    inside = MplPath(np.vstack([locus, locus[:1]])).contains_points(xy)
    xy_in = np.where(inside[:, None], xy, 1.0 / 3.0)  # avoid y = 0 outside the locus
    rgb_lin = np.asarray(XYZ_to_sRGB(np.asarray(xy_to_XYZ(xy_in))))  # encoded; clip below
    # Scale each colour so its largest linear component is 1, then encode again.
    lin = np.asarray(srgb_eotf(rgb_lin))
    lin = np.clip(lin, 0.0, None)
    lin = lin / np.maximum(lin.max(axis=-1, keepdims=True), 1e-12)
    rgb = np.clip(np.asarray(srgb_eotf_inverse(lin)), 0.0, 1.0)
    rgba = np.concatenate([rgb, inside[:, None].astype(float)], axis=-1)
    return rgba.reshape(n, n, 4)


_ISOTEMPERATURE_CCTS = (1500.0, 2000.0, 3000.0, 4000.0, 6500.0, 10000.0)  # [K]
_GAMUTS = ("sRGB", "Display P3", "ITU-R BT.2020")
_TABLE_2_1_ILLUMINANTS = ("A", "D50", "E", "D55", "D65")


def chromaticity_figure_data(*, smoke: bool = False) -> dict:
    """What fig. 2.2 plots, computed with `radiometria.colorimetry`.

    - `locus_wavelengths_nm` (421,), 360-780 nm, and `locus` (421, 2): the spectral locus,
        the xy of the CIE 1931 2° CMFs (`get_cmfs()`);
    - `image` (n, n, 4): the diagram filled with normalised, gamut-clipped sRGB colours, alpha
        1 inside the locus (n = 120 in smoke mode, else 500) on [0, 0.8] x [0, 0.9];
    - `planck_cct` (m,), 1000-100000 K, and `planck_xy` (m, 2) = `CCT_to_xy` (Duv = 0);
    - `isotemperature`: `{cct: (duv, xy)}`, the lines of constant CCT for Duv in
        [-0.02, 0.02] (11 points, `UCS_uv_to_xy(CCT_to_uv(cct, duv))`);
    - `gamuts`: `{name: primaries (3, 2)}` for sRGB, Display P3 and ITU-R BT.2020;
    - `illuminants`: `{name: xy (2,)}` for A, D50, E, D55 and D65 (thesis table 2.1), from
        their tabulated SPDs on 360 nm and up (emissive XYZ, `sd_to_XYZ`, 2° observer).
    """
    locus = _spectral_locus_xy()
    T = np.geomspace(1000.0, 100000.0, 60 if smoke else 300)
    isotemperature = {}
    for t in _ISOTEMPERATURE_CCTS:
        duv = np.linspace(-0.02, 0.02, 11)
        xy = np.asarray(UCS_uv_to_xy(CCT_to_uv(np.full_like(duv, t), duv)))
        isotemperature[t] = (duv, xy)
    illuminants = {}
    for name in _TABLE_2_1_ILLUMINANTS:
        s = get_illuminant(name)
        wl, v = np.asarray(s.wavelengths_nm), np.asarray(s.values)
        keep = wl >= VISIBLE_WAVELENGTH_MIN_NM
        illuminants[name] = np.asarray(XYZ_to_xy(sd_to_XYZ(v[keep], wl[keep])))
    return {
        "locus_wavelengths_nm": np.arange(360.0, 781.0),
        "locus": locus,
        "image": _horseshoe_image(locus, 120 if smoke else 500),
        "planck_cct": T,
        "planck_xy": np.asarray(CCT_to_xy(T)),
        "isotemperature": isotemperature,
        "gamuts": {name: np.asarray(RGB_COLOURSPACES[name].primaries) for name in _GAMUTS},
        "illuminants": illuminants,
    }


@figure("fig_2_2_chromaticity")
def fig_2_2_chromaticity(out_dir, *, smoke: bool = False):
    """CIE 1931 xy chromaticity diagram: spectral locus, Planckian locus with isotemperature
    lines, the sRGB / Display P3 / Rec.2020 gamuts and the illuminants of thesis table 2.1
    (thesis fig. 2.2 and 2.3). The data are `chromaticity_figure_data()`."""
    import matplotlib.pyplot as plt

    data = chromaticity_figure_data(smoke=smoke)
    locus = data["locus"]
    fig, ax = plt.subplots(figsize=(6.6, 7.0))
    img = data["image"]
    ax.imshow(img, origin="lower", extent=(0.0, 0.8, 0.0, 0.9), interpolation="bilinear", zorder=0)
    ax.plot(*np.vstack([locus, locus[:1]]).T, color="k", lw=1.2, zorder=2)
    for wl in (460, 480, 490, 500, 510, 520, 540, 560, 580, 600, 620, 700):
        x, y = locus[wl - 360]
        ax.plot(x, y, "k.", ms=3, zorder=3)
        ax.annotate(
            f"{wl}",
            (x, y),
            textcoords="offset points",
            xytext=(6, 0) if x > 0.2 else (-22, 0),
            fontsize=7,
        )

    # Planckian locus, 1000 K to 100000 K (approaching the infinite-temperature point).
    pl = data["planck_xy"]
    ax.plot(pl[:, 0], pl[:, 1], color="k", lw=1.6, zorder=4, label="Planckian locus")
    # Isotemperature lines: constant CCT, Duv in [-0.02, 0.02] (normals in CIE 1960 uv).
    for t, (_, line) in data["isotemperature"].items():
        ax.plot(line[:, 0], line[:, 1], color="k", lw=0.7, zorder=4)
        ax.annotate(f"{t:.0f} K", line[0], fontsize=6, textcoords="offset points", xytext=(-8, -9))

    styles = {"sRGB": "w-", "Display P3": "w--", "ITU-R BT.2020": "w:"}
    for name, style in styles.items():
        p = data["gamuts"][name]
        tri = np.vstack([p, p[:1]])
        ax.plot(tri[:, 0], tri[:, 1], style, lw=1.4, zorder=5)
        ax.plot(tri[:, 0], tri[:, 1], "k" + style[1:], lw=0.6, zorder=5, label=name)

    # Illuminants of thesis table 2.1, from their tabulated SPDs (emissive XYZ, 2° observer).
    for name, offset in [
        ("A", (5, 4)),
        ("D50", (5, 3)),
        ("E", (4, -11)),
        ("D55", (6, -4)),
        ("D65", (-27, 2)),
    ]:
        xy = data["illuminants"][name]
        ax.plot(*xy, "o", mfc="w", mec="k", ms=4, zorder=6)
        ax.annotate(name, xy, textcoords="offset points", xytext=offset, fontsize=8, zorder=6)

    ax.set_xlim(0.0, 0.8)
    ax.set_ylim(0.0, 0.9)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title("CIE 1931 xy chromaticity diagram")
    ax.grid(True, alpha=0.25)
    ax.legend(loc="upper right", fontsize=8, facecolor="0.85")
    return save(fig, out_dir, "fig_2_2_chromaticity")
