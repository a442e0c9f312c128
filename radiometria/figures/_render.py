"""Figures for `radiometria.render` (thesis ch. 8-9)."""

import numpy as np

from ..colorimetry import srgb_eotf_inverse
from ..render import Independent, OwenSobol, render
from ._registry import figure, save


def _display(rgb_linear: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """Linear sRGB -> sRGB-encoded values in [0, 1] for `imshow` (no tone mapping)."""
    return np.clip(np.asarray(srgb_eotf_inverse(np.clip(rgb_linear * exposure, 0.0, 1.0))), 0, 1)


def cornell_box_data(
    *, smoke: bool = False, size: int | None = None, spp: int | None = None
) -> dict:
    """What fig. 9 (Cornell box) plots: `render` of both Cornell box scenes.

    `size` (32 px in smoke mode, else 256) and `spp` (4 or 64) may be overridden; `box` and
    `measured` (size, size, 3) are the linear-sRGB renders of `"cornell-box"` and
    `"cornell-box-measured"` (default sampler and seed) [relative radiance]; `exposure` =
    0.18 / the mean Rec. 709 luminance of `measured`, the scale its panel is shown at.
    """
    size = size if size is not None else (32 if smoke else 256)
    spp = spp if spp is not None else (4 if smoke else 64)
    box = np.asarray(render("cornell-box", spp=spp, width=size, height=size, progress=False))
    measured = np.asarray(
        render("cornell-box-measured", spp=spp, width=size, height=size, progress=False)
    )
    y = measured @ np.array([0.2126, 0.7152, 0.0722])
    return {
        "size": size,
        "spp": spp,
        "box": box,
        "measured": measured,
        "exposure": 0.18 / max(float(y.mean()), 1e-12),
    }


@figure("fig_9_cornell_box")
def fig_9_cornell_box(out_dir, *, smoke: bool = False):
    """The Cornell box rendered spectrally: Mitsuba's RGB scene and the measured one.

    Left: `cornell-box` (Mitsuba 3's `cornell_box()`): linear-sRGB reflectances upsampled to
    spectra (Jakob & Hanika 2019), the RGB light as an illuminant spectrum (x D65), path
    tracing with NEE + MIS, 4 hero wavelengths per path, `max_depth` 8, Gaussian film. Right:
    `cornell-box-measured`: the measured reflectance and light spectra, no RGB anywhere; its
    light has the data's relative scale, so that image is exposed to a mean of 0.18. The data
    are `cornell_box_data()`.
    """
    import matplotlib.pyplot as plt

    data = cornell_box_data(smoke=smoke)
    size, spp, box, measured = data["size"], data["spp"], data["box"], data["measured"]
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 5.4), layout="constrained")
    panels = [
        (box, 1.0, "cornell-box (RGB scene, upsampled)"),
        (measured, data["exposure"], "cornell-box-measured (spectral data)"),
    ]
    for ax, (img, exposure, title) in zip(axes, panels, strict=True):
        ax.imshow(_display(img, exposure), interpolation="nearest")
        ax.set_title(title, fontsize=10)
        ax.set_axis_off()
    fig.suptitle(
        f"Spectral path tracing (hero wavelengths, NEE + MIS), {size}x{size} px, {spp} spp"
    )
    return save(fig, out_dir, "fig_9_cornell_box")


def render_convergence_data(*, smoke: bool = False, seeds=None) -> dict:
    """What fig. 9 (render convergence) plots: relative MSE of Cornell box renders against spp.

    `size` (8 px in smoke mode, else 32), `counts` = 1, 2, 4, ... `max_spp` (8 or 64),
    `reference`: an `OwenSobol` render with 16 x `max_spp` samples per pixel, seed 99;
    `seeds` ((0,) or (0, 1) unless given); and `errors`, `{"independent": (len(counts),),
    "sobol": ...}`: the relative MSE, mean over pixels and channels of
    $(x - x_\\mathrm{ref})^2 / (x_\\mathrm{ref}^2 + 10^{-2})$, averaged over the seeds.
    """
    size, max_spp = (8, 8) if smoke else (32, 64)
    counts = [2**i for i in range(int(np.log2(max_spp)) + 1)]
    n_pix = size * size
    kw = {"width": size, "height": size, "progress": False, "batch": n_pix}
    reference = np.asarray(
        render("cornell-box", spp=16 * max_spp, sampler=OwenSobol(), seed=99, **kw)
    )

    def rel_mse(img):
        return float(np.mean((img - reference) ** 2 / (reference**2 + 1e-2)))

    if seeds is None:
        seeds = (0,) if smoke else (0, 1)
    errors = {}
    for name, sampler in (("independent", Independent()), ("sobol", OwenSobol())):

        def error(n, sampler=sampler):
            imgs = [render("cornell-box", spp=n, sampler=sampler, seed=s, **kw) for s in seeds]
            return np.mean([rel_mse(np.asarray(img)) for img in imgs])

        errors[name] = np.array([error(n) for n in counts])
    return {
        "size": size,
        "counts": counts,
        "reference": reference,
        "seeds": tuple(seeds),
        "errors": errors,
    }


@figure("fig_9_render_convergence")
def fig_9_render_convergence(out_dir, *, smoke: bool = False):
    """Relative MSE of the Cornell box against the number of samples per pixel.

    Independent samples converge as $1/N$ (slope -1 in MSE); the padded Owen-scrambled Sobol
    sampler stratifies the pixel area, the wavelengths and every 2D light and BSDF sample, and
    reaches a given error with fewer samples (thesis ch. 5-7). Reference: a Sobol render with
    16 times the largest sample count (different seed). The data are
    `render_convergence_data()`.
    """
    import matplotlib.pyplot as plt

    data = render_convergence_data(smoke=smoke)
    size, counts = data["size"], data["counts"]
    fig, ax = plt.subplots(figsize=(6.0, 4.5), layout="constrained")
    for name, color in (("independent", "tab:blue"), ("sobol", "tab:orange")):
        err = list(data["errors"][name])
        ax.loglog(counts, err, "o-", color=color, label=name)
    ax.loglog(counts, err[0] * counts[0] / np.asarray(counts, float), "k--", lw=0.8,
              label="slope -1")  # fmt: skip
    ax.set_xlabel("samples per pixel")
    ax.set_ylabel("relative MSE")
    ax.set_title(f"Cornell box, {size}x{size} px: convergence of the pixel estimates")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    return save(fig, out_dir, "fig_9_render_convergence")
