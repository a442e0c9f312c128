"""Figures for `radiometria.photometry` (thesis section 2.1)."""

import numpy as np

from ..constants import K_M, K_M_SCOTOPIC, VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM
from ..photometry import luminous_efficiency_table
from ._registry import figure, save


def luminous_efficiency_data() -> dict:
    """What the luminous efficiency figure plots: `{"photopic": ..., "scotopic": ...}`.

    Each entry is a dict with `wavelengths_nm` (n,) [nm] and `values` (n,), the packaged CIE
    table (`luminous_efficiency_table`, V(lambda) of CIE 1924 or V'(lambda) of CIE 1951)
    [dimensionless]; `efficacy`, the maximum luminous efficacy $K_m$ or $K'_m$ [lm W^-1];
    `efficacy_curve` = `efficacy * values` [lm W^-1]; and `peak_nm`, the centre of the
    plateau where the (rounded) table equals its maximum [nm].
    """
    out = {}
    for vision, efficacy in (("photopic", K_M), ("scotopic", K_M_SCOTOPIC)):
        wavelengths_nm, values = (np.asarray(a) for a in luminous_efficiency_table(vision))
        # The tables are rounded, so V' equals 1 on 506-508 nm: mark the plateau's centre.
        out[vision] = {
            "wavelengths_nm": wavelengths_nm,
            "values": values,
            "efficacy": efficacy,
            "efficacy_curve": efficacy * values,
            "peak_nm": float(wavelengths_nm[values == values.max()].mean()),
        }
    return out


@figure("fig_2_luminous_efficiency")
def fig_2_luminous_efficiency(out_dir, *, smoke: bool = False):
    """CIE photopic V(lambda) and scotopic V'(lambda), and the spectral luminous efficacy K V.

    The data are `luminous_efficiency_data()`.
    """
    import matplotlib.pyplot as plt

    data = luminous_efficiency_data()
    fig, (ax, ax_k) = plt.subplots(1, 2, figsize=(10.0, 3.8), layout="constrained")
    curves = [
        ("photopic", r"photopic $V(\lambda)$ (CIE 1924)", "$K_m$", "tab:green"),
        ("scotopic", r"scotopic $V'(\lambda)$ (CIE 1951)", "$K'_m$", "tab:blue"),
    ]
    for vision, label, symbol, colour in curves:
        d = data[vision]
        wavelengths_nm, peak = d["wavelengths_nm"], d["peak_nm"]
        ax.plot(wavelengths_nm, d["values"], color=colour, label=f"{label}, peak {peak:.0f} nm")
        ax.axvline(peak, color=colour, lw=0.6, ls=":")
        ax_k.plot(
            wavelengths_nm,
            d["efficacy_curve"],
            color=colour,
            label=f"{symbol} = {d['efficacy']:g} lm/W",
        )
    ax.set_xlabel("wavelength [nm]")
    ax.set_ylabel("spectral luminous efficiency [-]")
    ax.set_title("Luminous efficiency functions")
    ax.legend(fontsize=8)
    ax_k.set_xlabel("wavelength [nm]")
    ax_k.set_ylabel("spectral luminous efficacy [lm W$^{-1}$]")
    ax_k.set_title("Spectral luminous efficacy")
    ax_k.legend(fontsize=8)
    for a in (ax, ax_k):
        a.set_xlim(VISIBLE_WAVELENGTH_MIN_NM, VISIBLE_WAVELENGTH_MAX_NM)
        a.grid(True, alpha=0.3)
    return save(fig, out_dir, "fig_2_luminous_efficiency")
