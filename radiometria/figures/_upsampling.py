"""Figures for `radiometria.upsampling` (thesis section 2.2.3): RGB to spectrum."""

import jax
import numpy as np

from ..colorimetry import get_cmfs, get_colourspace
from ..constants import VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM
from ..upsampling import (
    RGBAlbedoSpectrum,
    forward_model,
    get_lut,
    roundtrip_delta_E,
    sigmoid_jakob2019,
    sigmoid_polynomial_jakob2019,
)
from ._registry import figure, save

# Thesis figure 2.4: c0 = -0.000073447, c1 = 0.035354, c2 = -2.607 (nm coefficients).
THESIS_COEFFS = (-0.000073447, 0.035354, -2.607)


def sigmoid_figure_data() -> dict:
    """What fig. 2.4 plots, from `sigmoid_jakob2019` and `sigmoid_polynomial_jakob2019`.

    - `x` (401,) on [-10, 10] and `s` (401,) = $s(x)$ of eq. 2.26 [dimensionless];
    - `wavelengths_nm` (471,), 360-830 nm [nm], `coeffs` = `THESIS_COEFFS` ($c_0, c_1, c_2$ in
        nm units), `poly` = $c_0\\lambda^2 + c_1\\lambda + c_2$ and `S` = $s(\\mathrm{poly})$
        (eq. 2.25) [dimensionless].
    """
    x = np.linspace(-10.0, 10.0, 401)
    wl = np.linspace(VISIBLE_WAVELENGTH_MIN_NM, VISIBLE_WAVELENGTH_MAX_NM, 471)
    c = np.asarray(THESIS_COEFFS)
    return {
        "x": x,
        "s": np.asarray(sigmoid_jakob2019(x)),
        "wavelengths_nm": wl,
        "coeffs": c,
        "poly": (c[0] * wl + c[1]) * wl + c[2],
        "S": np.asarray(sigmoid_polynomial_jakob2019(c, wl)),
    }


@figure("fig_2_4_sigmoid")
def fig_2_4_sigmoid(out_dir, *, smoke: bool = False):
    """The sigmoid s(x) (eq. 2.26) and S(lambda) with the thesis's coefficients (fig. 2.4).

    The data are `sigmoid_figure_data()`.
    """
    import matplotlib.pyplot as plt

    data = sigmoid_figure_data()
    x, wl, c, poly, S = (data[k] for k in ("x", "wavelengths_nm", "coeffs", "poly", "S"))
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(10.0, 3.8))
    ax0.plot(x, data["s"], color="k")
    ax0.axhline(0.0, color="0.6", lw=0.6)
    ax0.axhline(1.0, color="0.6", lw=0.6)
    ax0.set_title(r"$s(x) = \frac{1}{2} + \frac{x}{2\sqrt{1+x^2}}$  (eq. 2.26)")
    ax0.set_xlabel("x")
    ax0.set_ylabel("s(x)")
    ax1.plot(wl, S, color="tab:green", label=r"$S(\lambda) = s(c_0\lambda^2 + c_1\lambda + c_2)$")
    ax1.set_ylim(-0.02, 1.02)
    ax1.set_xlabel("wavelength [nm]")
    ax1.set_ylabel(r"$S(\lambda)$")
    ax1.set_title(
        rf"$c_0 = {c[0]:.6g},\ c_1 = {c[1]:.6g},\ c_2 = {c[2]:.4g}$ (eq. 2.25, fig. 2.4)",
        fontsize=9,
    )
    twin = ax1.twinx()
    twin.plot(wl, poly, color="0.5", ls="--", lw=0.9, label=r"$c_0\lambda^2 + c_1\lambda + c_2$")
    twin.set_ylabel("polynomial", color="0.4")
    lines = ax1.get_lines() + twin.get_lines()
    ax1.legend(lines, [ln.get_label() for ln in lines], loc="upper right", fontsize=8)
    for ax in (ax0, ax1):
        ax.grid(True, alpha=0.3)
    return save(fig, out_dir, "fig_2_4_sigmoid")


def _chromaticity_grid(n: int, primaries: np.ndarray) -> np.ndarray:
    """xy points on a regular grid inside the triangle of `primaries` (3, 2)."""
    from matplotlib.path import Path as MplPath

    x, y = np.meshgrid(np.linspace(0.0, 0.8, n), np.linspace(0.0, 0.9, n))
    pts = np.stack([x.ravel(), y.ravel()], axis=-1)
    inside = MplPath(primaries).contains_points(pts)
    return pts[inside]


def roundtrip_error_data(*, smoke: bool = False) -> dict:
    """What the round-trip error figure plots, from the packaged sRGB table (`get_lut`).

    - `xy` (m, 2): a regular grid of chromaticities inside the sRGB triangle (40 x 40 in
        smoke mode, else 160 x 160, on [0, 0.8] x [0, 0.9]);
    - `rgb` (m, 3): their linear sRGB with the largest component 1 [dimensionless];
    - `results`: `[(brightness, delta_E), ...]` for brightness 1 and 0.02, `delta_E` (m,) the
        CIEDE2000 of `roundtrip_delta_E(lut, rgb * brightness)` under x64;
    - `locus` (421, 2): the spectral locus, 360-780 nm; `primaries` (3, 2): sRGB's xy.
    """
    cs = get_colourspace("sRGB")
    lut = get_lut("sRGB")
    primaries = np.asarray(cs.primaries)
    xy = _chromaticity_grid(40 if smoke else 160, primaries)
    XYZ = np.stack([xy[:, 0] / xy[:, 1], np.ones(len(xy)), (1 - xy.sum(1)) / xy[:, 1]], axis=-1)
    rgb = XYZ @ np.asarray(cs.matrix_XYZ_to_RGB).T
    rgb = np.clip(rgb / rgb.max(axis=1, keepdims=True), 0.0, 1.0)
    v = np.asarray(get_cmfs().values)[:421]
    with jax.enable_x64(True):
        results = [(b, roundtrip_delta_E(lut, rgb * b)[0]) for b in (1.0, 0.02)]
    return {
        "xy": xy,
        "rgb": rgb,
        "results": results,
        "locus": v[:, :2] / v.sum(axis=1, keepdims=True),
        "primaries": primaries,
    }


@figure("fig_2_roundtrip_error")
def fig_2_roundtrip_error(out_dir, *, smoke: bool = False):
    """Round-trip CIEDE2000 of the packaged sRGB table over the xy chromaticity diagram.

    For each chromaticity inside the sRGB triangle the colour is taken at two brightnesses
    (linear RGB with its largest component 1, and 0.02) and sent through the table:
    RGB -> coefficients -> spectrum -> XYZ under D65 -> CIEDE2000 against the input. The data
    are `roundtrip_error_data()`.
    """
    import matplotlib.pyplot as plt

    data = roundtrip_error_data(smoke=smoke)
    xy, locus, results = data["xy"], data["locus"], data["results"]
    fig, axes = plt.subplots(1, 2, figsize=(10.5, 4.6), sharey=True)
    vmax = max(float(d.max()) for _, d in results)
    for ax, (b, de) in zip(axes, results, strict=True):
        ax.plot(locus[:, 0], locus[:, 1], color="k", lw=0.8)
        ax.plot([locus[0, 0], locus[-1, 0]], [locus[0, 1], locus[-1, 1]], color="k", lw=0.8)
        tri = np.vstack([data["primaries"], data["primaries"][:1]])
        ax.plot(tri[:, 0], tri[:, 1], color="0.4", lw=0.8)
        sc = ax.scatter(
            xy[:, 0], xy[:, 1], c=de, s=6 if smoke else 2, cmap="viridis", vmin=0, vmax=vmax
        )
        ax.set_title(f"max(R,G,B) = {b:g}: mean {de.mean():.3f}, max {de.max():.3f}", fontsize=10)
        ax.set_xlabel("x")
        ax.set_aspect("equal")
        ax.set_xlim(0.0, 0.8)
        ax.set_ylim(0.0, 0.9)
    axes[0].set_ylabel("y")
    fig.colorbar(sc, ax=axes, label=r"round-trip $\Delta E_{00}$", shrink=0.85)
    fig.suptitle("sRGB -> sigmoid spectrum (res-64 table) -> sRGB, D65, CIE 1931 2°, 1 nm")
    return save(fig, out_dir, "fig_2_roundtrip_error")


def colorchecker_spectra(step_nm: float = 1.0) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """ColorChecker N Ohta reflectances (colour-science) on 360-830 nm: (wl, (24, n), names).

    colour-science tabulates them at 380-780 nm, 5 nm; they are interpolated linearly and
    extended with their end values (CIE 015 practice).
    """
    import colour

    data = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    wl = np.arange(VISIBLE_WAVELENGTH_MIN_NM, VISIBLE_WAVELENGTH_MAX_NM + step_nm / 2, step_nm)
    names = list(data.keys())
    values = np.stack([np.interp(wl, data[k].wavelengths, data[k].values) for k in names])
    return wl, values, names


def colorchecker_figure_data() -> dict:
    """What the ColorChecker figure plots: measured and upsampled spectra of the 24 patches.

    - `wavelengths_nm` (471,), `measured` (24, 471), `names` (24): `colorchecker_spectra()`;
    - `rgb` (24, 3): linear sRGB of each measured reflectance under D65 (the forward model of
        the fit, `forward_model("sRGB")`), clipped to [0, 1];
    - `upsampled` (24, 471): `RGBAlbedoSpectrum(get_lut("sRGB"), rgb)` on the same grid;
    - `delta_E` (24,): the round-trip CIEDE2000 of `rgb` (`roundtrip_delta_E`), under x64;
    - `encoded` (24, 3): the gamma-encoded sRGB of `rgb`, the patches' colours.
    """
    model = forward_model("sRGB")
    wl, values, names = colorchecker_spectra()
    rgb = np.clip(values @ model.weights_XYZ @ model.matrix_XYZ_to_RGB.T, 0.0, 1.0)
    lut = get_lut("sRGB")
    with jax.enable_x64(True):
        up = np.asarray(RGBAlbedoSpectrum(lut, rgb)(wl))
        de, _ = roundtrip_delta_E(lut, rgb)
    encoded = np.clip(np.asarray(get_colourspace("sRGB").cctf_encoding(rgb)), 0.0, 1.0)
    return {
        "wavelengths_nm": wl,
        "measured": values,
        "names": names,
        "rgb": rgb,
        "upsampled": up,
        "delta_E": de,
        "encoded": encoded,
    }


@figure("fig_2_colorchecker")
def fig_2_colorchecker(out_dir, *, smoke: bool = False):
    """The 24 ColorChecker patches: measured reflectance vs the upsampled sigmoid spectrum.

    Each measured spectrum (N. Ohta's data, via colour-science) is converted to linear sRGB
    under D65 (the forward model of the fit), then looked up in the packaged table; the panel
    shows both spectra on the patch's colour and the round-trip CIEDE2000. The data are
    `colorchecker_figure_data()`.
    """
    import matplotlib.pyplot as plt

    data = colorchecker_figure_data()
    wl, values, names = data["wavelengths_nm"], data["measured"], data["names"]
    up, de, encoded = data["upsampled"], data["delta_E"], data["encoded"]
    fig, axes = plt.subplots(4, 6, figsize=(13.0, 8.0), sharex=True, sharey=True)
    for k, ax in enumerate(axes.ravel()):
        ax.set_facecolor(encoded[k])
        ax.plot(wl, values[k], color="k", lw=1.2, label="measured")
        ax.plot(wl, up[k], color="w", lw=1.2, ls="--", label="upsampled")
        ax.set_title(f"{names[k]}\n$\\Delta E_{{00}}$ = {de[k]:.3f}", fontsize=8)
        ax.set_ylim(0.0, 1.0)
        ax.set_xlim(380.0, 780.0)
    for ax in axes[-1]:
        ax.set_xlabel("nm", fontsize=8)
    axes[0, 0].legend(fontsize=7, loc="upper left", framealpha=0.6)
    fig.suptitle(
        "ColorChecker (N. Ohta): measured reflectance (solid) and sigmoid upsampling of its "
        "sRGB colour (dashed)"
    )
    fig.tight_layout()
    return save(fig, out_dir, "fig_2_colorchecker")
