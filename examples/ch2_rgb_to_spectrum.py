# %% [markdown]
# # RGB to spectrum (thesis section 2.2.3)
#
# A linear sRGB colour becomes a smooth reflectance spectrum S(lambda) = s(c0 lambda^2 +
# c1 lambda + c2) (thesis eq. 2.25-2.26) through the packaged coefficient table (fitted by
# Gauss-Newton in CIELAB, eq. 2.27); integrating that spectrum against the CIE observer under
# D65 gives the colour back. `python examples/ch2_rgb_to_spectrum.py [OUT_DIR]`.

# %%
import os
import sys
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import radiometria as rm

SMOKE = os.environ.get("RADIOMETRIA_SMOKE") == "1"
OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "out/examples")
OUT.mkdir(parents=True, exist_ok=True)

# %%
lut = rm.upsampling.get_lut("sRGB")
colours = jnp.array([[0.8, 0.1, 0.1], [0.1, 0.6, 0.2], [0.2, 0.3, 0.9], [0.5, 0.5, 0.5]])
wavelengths = jnp.arange(360.0, 831.0, 5.0 if SMOKE else 1.0)  # [nm]
reflectance = rm.upsampling.RGBAlbedoSpectrum(lut, colours)(wavelengths[None, :])

# %% [markdown]
# Round trip: spectrum -> XYZ under D65 (reflective, eq. 2.15-2.19) -> linear sRGB.

# %%
d65 = rm.colorimetry.get_illuminant("D65")
refl_d65 = rm.radiometry.resample_spectrum(reflectance, wavelengths, d65.wavelengths_nm)
XYZ = rm.colorimetry.sd_to_XYZ(refl_d65, d65.wavelengths_nm, illuminant=d65.values)
rgb_back = rm.colorimetry.XYZ_to_RGB(XYZ, rm.colorimetry.RGB_COLOURSPACES["sRGB"])
for rgb, back in zip(colours, rgb_back, strict=True):
    print(f"{rgb} -> {jnp.round(back, 4)}")

# %%
fig, ax = plt.subplots(figsize=(6, 4))
for rgb, row in zip(colours, reflectance, strict=True):
    ax.plot(wavelengths, row, color=tuple(float(c) for c in rgb) if rgb[0] != rgb[1] else "grey")
ax.set_xlabel("wavelength [nm]")
ax.set_ylabel("reflectance")
fig.savefig(OUT / "ch2_rgb_to_spectrum.png", dpi=100)
print("wrote", OUT / "ch2_rgb_to_spectrum.png")
