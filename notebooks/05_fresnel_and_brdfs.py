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
# # 5. Fresnel equations and BRDFs
#
# Thesis chapter 3. Directions live in the local shading frame with the normal on +z, and the
# BxDF excludes the cosine factor (thesis eq. 3.4).

# %%
import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp
import matplotlib.pyplot as plt

import radiometria as rm

# %% [markdown]
# Glass: s and p reflectance against the angle of incidence, with Brewster's angle.

# %%
theta = jnp.linspace(0.0, jnp.pi / 2, 200)
r_s, r_p = rm.scattering.fresnel_dielectric_polarized(jnp.cos(theta), 1.5)
plt.plot(jnp.degrees(theta), r_s, label="$R_s$")
plt.plot(jnp.degrees(theta), r_p, label="$R_p$")
plt.plot(jnp.degrees(theta), rm.scattering.fresnel_dielectric(jnp.cos(theta), 1.5), label="R")
plt.axvline(jnp.degrees(jnp.arctan(1.5)), color="k", ls=":")
plt.xlabel("angle of incidence [deg]")
plt.legend()

# %% [markdown]
# A rough conductor: evaluate, sample and check that the sample weights average to the
# directional albedo; the gradient of the albedo with respect to roughness flows through
# sampling.


# %%
def albedo(alpha, n=4096):
    bxdf = rm.scattering.RoughConductorBxDF(alpha_x=alpha, eta=jnp.ones(1), k=jnp.full(1, 1e4))
    u = jax.random.uniform(jax.random.key(0), (n, 3))
    wo = jnp.broadcast_to(jnp.array([0.0, 0.0, 1.0]), (n, 3))
    s = bxdf.sample_f(wo, u[:, 0], u[:, 1:])
    w = jnp.where(s.pdf > 0, s.f[:, 0] * jnp.abs(s.wi[:, 2]) / jnp.maximum(s.pdf, 1e-300), 0.0)
    return jnp.mean(w)


print("albedo at alpha 0.5:", float(albedo(0.5)))
print("d albedo / d alpha:", float(jax.grad(albedo)(0.5)))
