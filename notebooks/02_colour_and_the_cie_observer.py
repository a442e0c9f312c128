# ---
# jupyter:
#   jupytext:
#     formats: ipynb,py:percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 2. Colour and the CIE observer
#
# Thesis section 2.2: tristimulus values from spectra (eq. 2.12-2.19), chromaticity, colour
# spaces and colour differences. Names follow colour-science (`sd_to_XYZ`, `XYZ_to_xy`).

# %%
import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp
import matplotlib.pyplot as plt

import radiometria as rm

# %% [markdown]
# The CIE 1931 2 degree colour-matching functions, packaged with their provenance.

# %%
cmfs = rm.colorimetry.get_cmfs("CIE 1931 2 Degree Standard Observer")
plt.plot(cmfs.wavelengths_nm, cmfs.values)
plt.xlabel("wavelength [nm]")
plt.legend(["$\\bar x$", "$\\bar y$", "$\\bar z$"])
# %% [markdown]
# Reflective colour: a reflectance under an illuminant, normalised so that the perfect
# reflector has Y = 1. The xy chromaticity of D65 from its spectrum is close to
# (0.3127, 0.3290).

# %%
d65 = rm.colorimetry.get_illuminant("D65")
white = rm.colorimetry.sd_to_XYZ(jnp.ones_like(d65.values), d65.wavelengths_nm, d65.values)
print("D65 white XYZ:", white, "xy:", rm.colorimetry.XYZ_to_xy(white))
print("CCT and Duv of D65:", rm.colorimetry.xy_to_CCT(rm.colorimetry.XYZ_to_xy(white)))

# %% [markdown]
# Colour spaces are pytrees whose matrices are derived from primaries and white point.

# %%
srgb = rm.colorimetry.RGB_COLOURSPACES["sRGB"]
print(srgb.matrix_RGB_to_XYZ)
p3 = rm.colorimetry.RGB_to_RGB(jnp.array([1.0, 0.0, 0.0]), "sRGB", "Display P3")
print("sRGB red in Display P3:", p3)

# %% [markdown]
# CIEDE2000 between two colours, and its gradient (differentiable colour difference).

# %%
Lab_1 = jnp.array([50.0, 2.6772, -79.7751])
Lab_2 = jnp.array([50.0, 0.0, -82.7485])
print(rm.colorimetry.delta_E_CIE2000(Lab_1, Lab_2))  # 2.0425 in Sharma et al. (2005)
print(jax.grad(rm.colorimetry.delta_E_CIE2000)(Lab_1, Lab_2))
