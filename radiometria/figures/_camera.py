"""Figures for `radiometria.camera` (thesis section 2.3)."""

import jax
import jax.numpy as jnp
import numpy as np

from ..camera import BoxFilter, GaussianFilter, LanczosFilter, MitchellFilter, TentFilter
from ._registry import figure, save


@figure("fig_2_filters")
def fig_2_filters(out_dir, *, smoke: bool = False):
    """Reconstruction filters and their importance-sampled footprints (thesis eq. 2.31-2.35).

    Top row: the normalised 1D profile $f_1(x)$ of each filter and the histogram of sampled
    x-offsets weighted by $w = f/p$, which reconstructs $f_1$ including its negative lobes (the
    estimator of eq. 2.35 is unbiased). Bottom row: the 2D histogram of the sampled offsets,
    i.e. the sampling density $p \\propto |f|$ (the footprint of one pixel's samples).
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import PowerNorm

    filters = [
        ("box", BoxFilter()),
        ("tent", TentFilter()),
        (r"Gaussian ($\sigma$ = 0.5)", GaussianFilter()),
        ("Mitchell-Netravali (B = C = 1/3)", MitchellFilter()),
        (r"Lanczos ($\tau$ = 3)", LanczosFilter()),
    ]
    n = 20_000 if smoke else 1_000_000
    extent = 3.0
    fig, axes = plt.subplots(2, len(filters), figsize=(15.0, 6.0), layout="constrained")
    keys = jax.random.split(jax.random.key(0), len(filters))
    x = np.linspace(-extent, extent, 1201)
    for col, ((title, filt), key) in enumerate(zip(filters, keys, strict=True)):
        offset, weight = filt.sample(jax.random.uniform(key, (n, 2), dtype=jnp.float32))
        offset, weight = np.asarray(offset, np.float64), np.asarray(weight, np.float64)
        profile = np.asarray(filt.evaluate_1d(jnp.asarray(x, jnp.float32)))
        ax = axes[0, col]
        bins = np.linspace(-extent, extent, 121)
        hist, _ = np.histogram(offset[:, 0], bins=bins, weights=weight)
        hist /= n * np.diff(bins)  # the weighted histogram estimates the marginal of f: f_1
        ax.stairs(
            hist,
            bins,
            color="tab:orange",
            fill=True,
            alpha=0.45,
            label="sampled, weighted by $f/p$",
        )
        ax.plot(x, profile, color="k", lw=1.2, label="$f_1(x)$")
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("offset x [px]")
        ax.set_xlim(-extent, extent)
        ax.grid(True, alpha=0.3)
        if col == 0:
            ax.set_ylabel("filter value [px$^{-1}$]")
            ax.legend(fontsize=7, loc="upper left")
        ax2 = axes[1, col]
        h2, xe, ye = np.histogram2d(
            offset[:, 0], offset[:, 1], bins=80, range=[[-extent, extent], [-extent, extent]]
        )
        h2 /= n * np.diff(xe)[0] * np.diff(ye)[0]
        im = ax2.imshow(
            h2.T, origin="lower", extent=(-extent, extent, -extent, extent), cmap="magma",
            interpolation="nearest", norm=PowerNorm(0.5),  # square-root scale shows the lobes
        )  # fmt: skip
        ax2.set_xlabel("offset x [px]")
        if col == 0:
            ax2.set_ylabel("offset y [px]")
        ax2.set_title(f"samples $\\propto |f|$, radius {filt.radius:g} px", fontsize=9)
        fig.colorbar(im, ax=ax2, shrink=0.8, label="density [px$^{-2}$]")
    fig.suptitle("Pixel reconstruction filters and filter importance sampling (eq. 2.35)")
    return save(fig, out_dir, "fig_2_filters")
