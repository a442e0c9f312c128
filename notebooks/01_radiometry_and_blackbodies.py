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
# # 1. Radiometry and blackbodies
#
# Thesis chapter 1. Wavelengths are in nanometres and spectral densities per nanometre at
# every boundary of radiometria, so integrating a spectrum over a nanometre grid gives the SI
# quantity directly. We turn on float64 because we compare against constants to 1e-9.

# %%
import os

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp
import matplotlib.pyplot as plt

import radiometria as rm

SMOKE = os.environ.get("RADIOMETRIA_SMOKE") == "1"

# %% [markdown]
# Planck's law (thesis eq. 1.24) returns spectral radiance in W sr^-1 m^-2 nm^-1.

# %%
wavelengths = jnp.linspace(100.0, 3000.0, 300 if SMOKE else 3000)  # [nm]
temperatures = jnp.array([3000.0, 4000.0, 5000.0, 6000.0])  # [K]
L = rm.radiometry.planck(wavelengths[None, :], temperatures[:, None])
for T, row in zip(temperatures, L, strict=True):
    plt.plot(wavelengths, row, label=f"{T:.0f} K")
peaks = rm.radiometry.planck_peak_wavelength(temperatures)
plt.plot(peaks, rm.radiometry.planck(peaks, temperatures), "k--", label="Wien locus")
plt.xlabel("wavelength [nm]")
plt.ylabel("L [W sr$^{-1}$ m$^{-2}$ nm$^{-1}$]")
plt.legend()
# %% [markdown]
# The exitance of a blackbody is pi times its radiance (eq. 1.23); integrated over all
# wavelengths it is sigma T^4 (eq. 1.22).

# %%
grid = jnp.geomspace(10.0, 1e6, 2_000 if SMOKE else 100_000)
M = jnp.pi * rm.radiometry.integrate_spectrum(rm.radiometry.planck(grid, 5772.0), grid)
print(float(M), float(rm.radiometry.stefan_boltzmann_exitance(5772.0)))

# %% [markdown]
# Everything is differentiable: the derivative of radiance with respect to temperature, and
# `vmap` over a batch of temperatures.

# %%
dL_dT = jax.grad(rm.radiometry.planck, argnums=1)(550.0, 5000.0)
print("dL/dT at 550 nm, 5000 K:", float(dL_dT), "W sr^-1 m^-2 nm^-1 K^-1")
print(jax.vmap(rm.radiometry.planck, in_axes=(None, 0))(550.0, temperatures))
