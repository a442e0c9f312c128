"""Figures for `radiometria.radiometry` (thesis chapter 1)."""

import numpy as np

from ..radiometry import planck, planck_peak_wavelength
from ._registry import figure, save


@figure("fig_1_planck")
def fig_1_planck(out_dir, *, smoke: bool = False):
    """Planck's law (thesis eq. 1.24) for 3000-6000 K, log-log, with Wien's displacement locus."""
    import matplotlib.pyplot as plt

    n = 200 if smoke else 1000
    wavelengths_nm = np.geomspace(100.0, 1e5, n)
    temperatures = [3000.0, 4000.0, 5000.0, 5778.0, 6000.0]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    ax.axvspan(380.0, 780.0, color="0.92", zorder=0, label="visible (380-780 nm)")
    colours = plt.cm.inferno(np.linspace(0.25, 0.8, len(temperatures)))
    for temperature, colour in zip(temperatures, colours, strict=True):
        radiance = np.asarray(planck(wavelengths_nm, temperature))
        label = f"{temperature:.0f} K" + (" (Sun)" if temperature == 5778.0 else "")
        ax.loglog(wavelengths_nm, radiance, color=colour, label=label)
    # Wien's locus: the peak (lambda_max(T), L(lambda_max(T), T)) traced over temperature.
    locus_t = np.geomspace(2000.0, 8000.0, 100)
    peak_nm = np.asarray(planck_peak_wavelength(locus_t))
    ax.loglog(
        peak_nm,
        np.asarray(planck(peak_nm, locus_t)),
        "k--",
        lw=1,
        label=r"Wien: $\lambda_{max} = b/T$",
    )
    peaks_nm = np.asarray(planck_peak_wavelength(np.asarray(temperatures)))
    ax.plot(peaks_nm, np.asarray(planck(peaks_nm, np.asarray(temperatures))), "ko", ms=3)
    ax.set_xlim(wavelengths_nm[0], wavelengths_nm[-1])
    ax.set_ylim(1e-2, 2e5)
    ax.set_xlabel("wavelength [nm]")
    ax.set_ylabel(r"spectral radiance $L_{bb,\lambda}$ [W sr$^{-1}$ m$^{-2}$ nm$^{-1}$]")
    ax.set_title("Blackbody spectral radiance (Planck's law)")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    return save(fig, out_dir, "fig_1_planck")
