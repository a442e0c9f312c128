# %% [markdown]
# # Blackbody radiation (thesis section 1.5)
#
# Planck's law (thesis eq. 1.24) in W sr^-1 m^-2 nm^-1, Stefan-Boltzmann from integrating it
# (eq. 1.22-1.23), and Wien's displacement law. Run as a script:
# `python examples/ch1_blackbody.py [OUT_DIR]`; `RADIOMETRIA_SMOKE=1` shrinks the grids.

# %%
import os
import sys
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)  # physics checks to 1e-9 need double precision

import jax.numpy as jnp
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import radiometria as rm

SMOKE = os.environ.get("RADIOMETRIA_SMOKE") == "1"
OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "out/examples")
OUT.mkdir(parents=True, exist_ok=True)

# %% [markdown]
# Stefan-Boltzmann: integrate pi L over wavelength on a log grid and compare with sigma T^4.

# %%
n = 4_000 if SMOKE else 200_000
wavelengths = jnp.geomspace(10.0, 1e6, n)  # [nm]
for T in (300.0, 1000.0, 5772.0):
    exitance = jnp.pi * rm.radiometry.integrate_spectrum(
        rm.radiometry.planck(wavelengths, T), wavelengths
    )
    sigma_T4 = rm.radiometry.stefan_boltzmann_exitance(T)
    print(f"T = {T:7.1f} K  integral = {float(exitance):.6e}  sigma T^4 = {float(sigma_T4):.6e}")

# %% [markdown]
# Wien's law: the peak found by the gradient of Planck's law vanishing.

# %%
T = 5772.0
peak = rm.radiometry.planck_peak_wavelength(T)
slope = jax.grad(rm.radiometry.planck)(peak, T)
print(f"Wien peak at {float(peak):.3f} nm; dL/dlambda there = {float(slope):.2e}")

# %%
visible = jnp.linspace(200.0, 2000.0, 200 if SMOKE else 1000)
fig, ax = plt.subplots(figsize=(6, 4))
for T in (3000.0, 4000.0, 5000.0, 6000.0):
    ax.plot(visible, rm.radiometry.planck(visible, T), label=f"{T:.0f} K")
ax.set_xlabel("wavelength [nm]")
ax.set_ylabel("spectral radiance [W sr$^{-1}$ m$^{-2}$ nm$^{-1}$]")
ax.legend()
fig.savefig(OUT / "ch1_blackbody.png", dpi=100)
print("wrote", OUT / "ch1_blackbody.png")
