# %% [markdown]
# # Photometry and colorimetry (thesis sections 2.1-2.2)
#
# Luminance of a blackbody (eq. 2.1-2.5), its XYZ and chromaticity (eq. 2.12-2.20), its
# correlated colour temperature, and a colour difference (CIEDE2000).
# `python examples/ch2_colorimetry.py [OUT_DIR]`.

# %%
import os
import sys
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp

import radiometria as rm

SMOKE = os.environ.get("RADIOMETRIA_SMOKE") == "1"
OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "out/examples")
OUT.mkdir(parents=True, exist_ok=True)

# %%
wavelengths = jnp.arange(360.0, 831.0, 5.0 if SMOKE else 1.0)  # [nm]
for T in (2856.0, 5000.0, 6504.0):
    L = rm.radiometry.planck(wavelengths, T)  # [W sr^-1 m^-2 nm^-1]
    Lv = rm.photometry.luminance(L, wavelengths)  # [cd m^-2]
    XYZ = rm.colorimetry.sd_to_XYZ(L, wavelengths)  # Y is luminance [cd m^-2]
    xy = rm.colorimetry.XYZ_to_xy(XYZ)
    cct = rm.colorimetry.xy_to_CCT(xy)
    print(
        f"T = {T:6.0f} K  Lv = {float(Lv):.4e} cd/m^2  Y = {float(XYZ[1]):.4e}  "
        f"xy = ({float(xy[0]):.4f}, {float(xy[1]):.4f})  CCT = {float(cct[0]):.1f} K"
    )

# %% [markdown]
# The D65 illuminant's chromaticity from its 1 nm spectrum (thesis table 2.1), and the
# reflective tristimulus values of a grey under it (Y = 0.5 for a 50 % reflector).

# %%
d65 = rm.colorimetry.get_illuminant("D65")
white = rm.colorimetry.sd_to_XYZ(
    jnp.ones_like(d65.values), d65.wavelengths_nm, illuminant=d65.values
)
grey = rm.colorimetry.sd_to_XYZ(
    0.5 * jnp.ones_like(d65.values), d65.wavelengths_nm, illuminant=d65.values
)
print("D65 xy:", rm.colorimetry.XYZ_to_xy(white), " grey Y:", float(grey[1]))

# %%
Lab_1 = rm.colorimetry.XYZ_to_Lab(rm.colorimetry.sRGB_to_XYZ(jnp.array([0.8, 0.2, 0.1])), white)
Lab_2 = rm.colorimetry.XYZ_to_Lab(rm.colorimetry.sRGB_to_XYZ(jnp.array([0.8, 0.25, 0.1])), white)
print("CIEDE2000 between two oranges:", float(rm.colorimetry.delta_E_CIE2000(Lab_1, Lab_2)))
