# %% [markdown]
# # Spectral rendering of the Cornell box (thesis ch. 8-9)
#
# The built-in `cornell-box` scene (Mitsuba 3's `cornell_box()`: RGB reflectances upsampled to
# spectra, an RGB light as an illuminant spectrum) rendered with `radiometria.render.render`.
# Two integrators, direct illumination (`Direct()`: two path segments) and path tracing
# (`Path()`: NEE + MIS + Russian roulette, the scene's depths), each with independent samples
# (`Independent()`) and with padded Owen-scrambled Sobol points (`OwenSobol()`). The
# difference between the two integrators is the indirect light (colour bleeding); the
# difference between the two samplers is the noise at equal sample count, measured against a
# reference render with 4x the samples.
# `python examples/ch9_render.py [OUT_DIR]` writes PNG and OpenEXR images and a comparison
# figure.

# %%
import os
import sys
import time
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import radiometria as rm

SMOKE = os.environ.get("RADIOMETRIA_SMOKE") == "1"
OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "out/examples")
OUT.mkdir(parents=True, exist_ok=True)
SIZE, SPP = (32, 4) if SMOKE else (128, 64)

# %% [markdown]
# The scene as loaded from its description, then compiled to device arrays (`RenderScene`),
# a pinhole camera and the film's reconstruction filter (a Gaussian, thesis eq. 2.34).

# %%
description = rm.render.load_scene("cornell-box")
print(
    f"{description.n_triangles} triangles, {len(description.materials)} materials, "
    f"{len(description.emitters)} emitter, max_depth {description.max_depth}"
)
scene, camera, rfilter = rm.render.compile_scene(description, width=SIZE, height=SIZE)
print(f"camera: {camera.width} x {camera.height} px, fov_x {float(camera.fov_x_deg):.2f} deg")
print(f"filter: {type(rfilter).__name__}, radius {float(rfilter.radius)} px")

# %% [markdown]
# Four renders: {direct, path} x {independent, Sobol}, same seed and sample count. The first
# render of each combination compiles the step (seconds); the sample count is not part of the
# compiled program, so the reference reuses the path/Sobol program.

# %%
INTEGRATORS = {"direct": rm.render.Direct(), "path": rm.render.scene_integrator(description)}
SAMPLERS = {"independent": rm.render.Independent(), "sobol": rm.render.OwenSobol()}
images = {}
for integrator in INTEGRATORS:
    for sampler in SAMPLERS:
        start = time.perf_counter()
        rgb = rm.render.render(
            description,
            spp=SPP,
            width=SIZE,
            height=SIZE,
            integrator=INTEGRATORS[integrator],
            sampler=SAMPLERS[sampler],
            seed=0,
            progress=False,
        )
        images[integrator, sampler] = rgb = np.asarray(rgb)
        mean = rgb.mean(axis=(0, 1))
        print(
            f"{integrator:6s} {sampler:11s} mean linear sRGB "
            f"({mean[0]:.4f}, {mean[1]:.4f}, {mean[2]:.4f})  {time.perf_counter() - start:5.1f} s"
        )

reference = np.asarray(
    rm.render.render(
        description,
        spp=4 * SPP,
        width=SIZE,
        height=SIZE,
        sampler=SAMPLERS["sobol"],
        seed=99,
        progress=False,
    )
)

# %% [markdown]
# Indirect light is what path tracing adds to direct illumination. Noise: relative RMSE of each
# path-traced image against the reference (the Sobol points stratify the pixel area, the
# wavelengths and every 2D light and BSDF sample, so they are less noisy at equal spp).

# %%
direct, path = images["direct", "sobol"], images["path", "sobol"]
indirect = 1.0 - direct.mean(axis=(0, 1)) / path.mean(axis=(0, 1))
print("indirect share of the image mean (R, G, B):", np.round(indirect, 3))


def relative_rmse(img: np.ndarray) -> float:
    """Root-mean-square error relative to the reference (1e-2 keeps dark pixels bounded)."""
    return float(np.sqrt(np.mean((img - reference) ** 2 / (reference**2 + 1e-2))))


for sampler in ("independent", "sobol"):
    error = relative_rmse(images["path", sampler])
    print(f"path {sampler:11s} relative RMSE vs reference: {error:.4f}")

# %% [markdown]
# Images: linear sRGB in float32 OpenEXR (the radiometric result) and 8-bit sRGB PNG (for
# viewing). The EXR is read back to check the round trip.

# %%
for (integrator, sampler), rgb in images.items():
    stem = f"ch9_cornell_box_{integrator}_{sampler}"
    rm.camera.write_exr(OUT / f"{stem}.exr", rgb, {"spp": SPP, "integrator": integrator})
    rm.camera.write_png(OUT / f"{stem}.png", rgb)
back, header = rm.camera.read_exr(OUT / "ch9_cornell_box_path_sobol.exr")
print("EXR round trip exact:", bool(np.array_equal(back, path)), "| spp in header:", header["spp"])

fig, axes = plt.subplots(2, 2, figsize=(8, 8), layout="constrained")
for ax, ((integrator, sampler), rgb) in zip(axes.ravel(), images.items(), strict=True):
    shown = rm.colorimetry.srgb_eotf_inverse(np.clip(rgb, 0.0, 1.0))
    ax.imshow(np.clip(np.asarray(shown), 0.0, 1.0), interpolation="nearest")
    ax.set_title(f"{integrator}, {sampler}", fontsize=10)
    ax.set_axis_off()
fig.suptitle(f"Cornell box, {SIZE} x {SIZE} px, {SPP} spp, 4 hero wavelengths per path")
fig.savefig(OUT / "ch9_cornell_box.png", dpi=100)
