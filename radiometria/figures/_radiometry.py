"""Figures for `radiometria.radiometry` (thesis chapter 1)."""

import numpy as np

from ..radiometry import planck, planck_peak_wavelength
from ._registry import figure, save

_PLANCK_TEMPERATURES = (3000.0, 4000.0, 5000.0, 5778.0, 6000.0)  # [K]; 5778 K is the Sun


def planck_figure_data(*, smoke: bool = False) -> dict:
    """What the Planck figure plots, computed with `planck` and `planck_peak_wavelength`.

    - `wavelengths_nm` (n,): 100 nm to 100 µm, log-spaced (n = 200 in smoke mode, else 1000);
    - `temperatures` (5,) [K] and `radiance` (5, n), `planck(wavelengths_nm, T)` for each
        [W sr^-1 m^-2 nm^-1];
    - `locus_temperatures` (100,), 2000-8000 K, with `locus_peak_nm` = $b/T$ [nm] and
        `locus_radiance`, the radiance at that peak: Wien's displacement locus;
    - `peaks_nm` (5,) and `peaks_radiance` (5,): the peak of each plotted curve.
    """
    n = 200 if smoke else 1000
    wavelengths_nm = np.geomspace(100.0, 1e5, n)
    temperatures = np.asarray(_PLANCK_TEMPERATURES)
    radiance = np.stack([np.asarray(planck(wavelengths_nm, t)) for t in temperatures])
    locus_t = np.geomspace(2000.0, 8000.0, 100)
    locus_peak_nm = np.asarray(planck_peak_wavelength(locus_t))
    peaks_nm = np.asarray(planck_peak_wavelength(temperatures))
    return {
        "wavelengths_nm": wavelengths_nm,
        "temperatures": temperatures,
        "radiance": radiance,
        "locus_temperatures": locus_t,
        "locus_peak_nm": locus_peak_nm,
        "locus_radiance": np.asarray(planck(locus_peak_nm, locus_t)),
        "peaks_nm": peaks_nm,
        "peaks_radiance": np.asarray(planck(peaks_nm, temperatures)),
    }


@figure("fig_1_planck")
def fig_1_planck(out_dir, *, smoke: bool = False):
    """Planck's law (thesis eq. 1.24) for 3000-6000 K, log-log, with Wien's displacement locus.

    The data are `planck_figure_data()`.
    """
    import matplotlib.pyplot as plt

    data = planck_figure_data(smoke=smoke)
    wavelengths_nm, temperatures = data["wavelengths_nm"], data["temperatures"]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    ax.axvspan(380.0, 780.0, color="0.92", zorder=0, label="visible (380-780 nm)")
    colours = plt.cm.inferno(np.linspace(0.25, 0.8, len(temperatures)))
    for temperature, radiance, colour in zip(temperatures, data["radiance"], colours, strict=True):
        label = f"{temperature:.0f} K" + (" (Sun)" if temperature == 5778.0 else "")
        ax.loglog(wavelengths_nm, radiance, color=colour, label=label)
    # Wien's locus: the peak (lambda_max(T), L(lambda_max(T), T)) traced over temperature.
    ax.loglog(
        data["locus_peak_nm"],
        data["locus_radiance"],
        "k--",
        lw=1,
        label=r"Wien: $\lambda_{max} = b/T$",
    )
    ax.plot(data["peaks_nm"], data["peaks_radiance"], "ko", ms=3)
    ax.set_xlim(wavelengths_nm[0], wavelengths_nm[-1])
    ax.set_ylim(1e-2, 2e5)
    ax.set_xlabel("wavelength [nm]")
    ax.set_ylabel(r"spectral radiance $L_{bb,\lambda}$ [W sr$^{-1}$ m$^{-2}$ nm$^{-1}$]")
    ax.set_title("Blackbody spectral radiance (Planck's law)")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    return save(fig, out_dir, "fig_1_planck")
