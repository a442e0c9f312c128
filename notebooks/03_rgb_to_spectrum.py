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
# # 3. From RGB to spectra
#
# Thesis section 2.2.3. A spectral renderer needs spectra, but scenes are authored in RGB.
# Jakob & Hanika (2019) map each RGB colour to a smooth sigmoid-polynomial spectrum
# S(lambda) = s(c0 lambda^2 + c1 lambda + c2), s(x) = 1/2 + x / (2 sqrt(1 + x^2)),
# whose three coefficients are fitted by Gauss-Newton in CIELAB (eq. 2.27) and stored in a table.

# %%
import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp
import matplotlib.pyplot as plt

import radiometria as rm

# %% [markdown]
# The packaged sRGB table (resolution 64) loads at once; a lookup is a trilinear interpolation,
# vectorised and differentiable.

# %%
lut = rm.upsampling.get_lut("sRGB")
rgb = jnp.array([[0.9, 0.4, 0.1], [0.1, 0.4, 0.9], [0.2, 0.7, 0.3]])
coeffs = lut.coefficients(rgb)
print(coeffs)
wavelengths = jnp.linspace(360.0, 830.0, 471)
spectra = rm.upsampling.SigmoidPolynomialSpectrum(coeffs)(wavelengths[None, :])
for colour, s in zip(rgb, spectra, strict=True):
    plt.plot(wavelengths, s, color=tuple(float(c) for c in colour))
plt.xlabel("wavelength [nm]")
plt.ylabel("reflectance")
# %% [markdown]
# A direct fit (optimistix Gauss-Newton with the exact Jacobian from JAX) agrees with the table.

# %%
fit = rm.upsampling.fit_rgb(rgb[0], "sRGB")
print("direct fit:", fit.coeffs, " table:", coeffs[0])

# %% [markdown]
# The gradient of a spectral value with respect to the RGB input flows through the table.

# %%
grad = jax.grad(lambda c: rm.upsampling.RGBAlbedoSpectrum(lut, c)(550.0).sum())(rgb[0])
print("d S(550 nm) / d rgb =", grad)
