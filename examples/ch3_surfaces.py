# %% [markdown]
# # Surfaces: Fresnel equations and BRDFs (thesis ch. 3)
#
# Fresnel reflectance of glass against angle, with Brewster's angle where r_p vanishes
# (thesis eq. 3.13-3.18), and the directional albedo of a rough GGX conductor estimated by
# Monte Carlo with importance sampling of visible normals: the energy that single-scattering
# microfacet models lose grows with roughness. `python examples/ch3_surfaces.py [OUT_DIR]`.

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
eta = 1.5
brewster = jnp.arctan(eta)  # [rad]
r_s, r_p = rm.scattering.fresnel_dielectric_polarized(jnp.cos(brewster), eta)
print(f"Brewster {jnp.degrees(brewster):.2f} deg: R_s = {float(r_s):.4f}, R_p = {float(r_p):.1e}")
print(f"normal incidence: R = {float(rm.scattering.fresnel_dielectric(1.0, eta)):.4f}")
print(f"closed form ((eta-1)/(eta+1))^2 = {((eta - 1) / (eta + 1)) ** 2:.4f}")

# %% [markdown]
# Directional albedo of a rough "white" conductor (k very large, so the Fresnel term is 1):
# an energy-conserving model would give 1. Mitsuba 3's `roughconductor` gives the same losses.

# %%
n = 4_096 if SMOKE else 262_144
key = jax.random.key(1)
wo = jnp.array([jnp.sin(0.5), 0.0, jnp.cos(0.5)])
for alpha in (0.05, 0.3, 0.6, 1.0):
    bxdf = rm.scattering.RoughConductorBxDF(
        alpha_x=jnp.asarray(alpha), eta=jnp.ones(1), k=jnp.full(1, 1e4)
    )
    u = jax.random.uniform(key, (n, 3))
    s = bxdf.sample_f(jnp.broadcast_to(wo, (n, 3)), u[:, 0], u[:, 1:])
    weight = jnp.where(s.pdf > 0, s.f[:, 0] * jnp.abs(s.wi[:, 2]) / jnp.maximum(s.pdf, 1e-300), 0.0)
    est = rm.montecarlo.estimate_mean(weight)
    print(f"alpha = {alpha:4.2f}: albedo {float(est.mean):.4f} +- {float(est.standard_error):.4f}")
