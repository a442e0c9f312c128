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
# # 4. Monte Carlo and quasi-Monte Carlo
#
# Thesis chapters 5-7. Randomness is always explicit: a `jax.random` key or an array `u` of
# uniform variates, so the same code runs with random or quasi-random points.

# %%
import os

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp
import matplotlib.pyplot as plt

import radiometria as rm

SMOKE = os.environ.get("RADIOMETRIA_SMOKE") == "1"
key = jax.random.key(0)

# %% [markdown]
# Point sets: independent, Sobol, and Owen-scrambled Sobol (256 points in 2D).

# %%
n = 256
sets = {
    "independent": rm.montecarlo.independent(n, 2, key=key),
    "Sobol": rm.montecarlo.sobol(n, 2),
    "Owen-scrambled Sobol": rm.montecarlo.sobol(n, 2, scramble="owen", key=key),
}
fig, axes = plt.subplots(1, 3, figsize=(12, 4))
for ax, (name, pts) in zip(axes, sets.items(), strict=True):
    ax.scatter(pts[:, 0], pts[:, 1], s=4)
    ax.set_title(name)
    ax.set_aspect("equal")

# %% [markdown]
# Warps map uniform variates to distributions with a known pdf; every warp has an inverse.

# %%
u = rm.montecarlo.sobol(n, 2, scramble="owen", key=key)
w = rm.montecarlo.sample_cosine_hemisphere(u)
print(
    "max |invert(sample(u)) - u| =",
    float(jnp.max(jnp.abs(rm.montecarlo.invert_cosine_hemisphere_sample(w) - u))),
)

# %% [markdown]
# Integrate the irradiance of a uniform sky (E = pi, thesis eq. 1.13) with several methods;
# randomised QMC reports an error estimate from independent replicates.

# %%
f = lambda w: w[..., 2]  # noqa: E731
for method in ("mc", "stratified", "sobol"):
    est = rm.montecarlo.integrate(f, "hemisphere", 64 if SMOKE else 1024, method=method, key=key)
    print(f"{method:10s} {float(est.mean):.6f} +- {float(est.standard_error):.2e}")
