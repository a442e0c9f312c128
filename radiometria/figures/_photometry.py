"""Figures for `radiometria.photometry` (thesis section 2.1)."""

import numpy as np

from ..constants import K_M, K_M_SCOTOPIC, VISIBLE_WAVELENGTH_MAX_NM, VISIBLE_WAVELENGTH_MIN_NM
from ..photometry import luminous_efficiency_table
from ._registry import figure, save


@figure("fig_2_luminous_efficiency")
def fig_2_luminous_efficiency(out_dir, *, smoke: bool = False):
    """CIE photopic V(lambda) and scotopic V'(lambda), and the spectral luminous efficacy K V."""
    import matplotlib.pyplot as plt

    fig, (ax, ax_k) = plt.subplots(1, 2, figsize=(10.0, 3.8), layout="constrained")
    curves = [
        ("photopic", r"photopic $V(\lambda)$ (CIE 1924)", "$K_m$", K_M, "tab:green"),
        ("scotopic", r"scotopic $V'(\lambda)$ (CIE 1951)", "$K'_m$", K_M_SCOTOPIC, "tab:blue"),
    ]
    for vision, label, symbol, efficacy, colour in curves:
        wavelengths_nm, values = (np.asarray(a) for a in luminous_efficiency_table(vision))
        # The tables are rounded, so V' equals 1 on 506-508 nm: mark the plateau's centre.
        peak = wavelengths_nm[values == values.max()].mean()
        ax.plot(wavelengths_nm, values, color=colour, label=f"{label}, peak {peak:.0f} nm")
        ax.axvline(peak, color=colour, lw=0.6, ls=":")
        ax_k.plot(
            wavelengths_nm, efficacy * values, color=colour, label=f"{symbol} = {efficacy:g} lm/W"
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
