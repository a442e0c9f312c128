# %% [markdown]
# # Monte Carlo and quasi-Monte Carlo integration (thesis ch. 5-7)
#
# The same integrand, integrated with plain Monte Carlo and with Owen-scrambled Sobol points:
# the root-mean-square error falls like n^-1/2 for the first and close to n^-3/2 for the second
# on a smooth integrand. Then the irradiance of a uniform sky on a Lambertian point (pi L, thesis
# eq. 1.13) by cosine-weighted importance sampling, which has zero variance.
# `python examples/ch5_quasi_monte_carlo.py [OUT_DIR]`.

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
key = jax.random.key(0)

# %% [markdown]
# A Genz "product peak" test function in 4 dimensions, with its closed-form integral.

# %%
d = 4
f, exact = rm.montecarlo.genz("product_peak", a=jnp.full(d, 2.0), w=jnp.full(d, 0.5))
ns = [2**k for k in range(6, 10 if SMOKE else 14)]
fig, ax = plt.subplots(figsize=(5, 4))
for method in ("mc", "sobol"):
    study = rm.montecarlo.convergence_study(
        f, exact, ns, method=method, dim=d, key=key, n_replicates=8 if SMOKE else 32
    )
    print(f"{method:6s} RMSE slope {float(study.slope):+.2f}")
    ax.loglog(ns, study.rmse, "o-", label=f"{method} (slope {float(study.slope):.2f})")
ax.set_xlabel("n")
ax.set_ylabel("RMSE")
ax.legend()
fig.savefig(OUT / "ch5_convergence.png", dpi=100)

# %% [markdown]
# Irradiance from a uniform sky of radiance L = 1: E = pi L (thesis eq. 1.13). Uniform
# hemisphere sampling has variance; cosine-weighted sampling is exact for every sample.

# %%
n = 1_000 if SMOKE else 100_000
cos_theta = lambda w: w[..., 2]  # noqa: E731
uniform = rm.montecarlo.integrate(cos_theta, "hemisphere", n, method="mc", key=key)
cosine = rm.montecarlo.importance_sampling(
    cos_theta,
    rm.montecarlo.sample_cosine_hemisphere,
    lambda w: rm.montecarlo.cosine_hemisphere_pdf(w[..., 2]),
    n,
    u_dim=2,
    key=key,
)
print(f"uniform: {float(uniform.mean):.5f} +- {float(uniform.standard_error):.5f}")
print(f"cosine : {float(cosine.mean):.5f} +- {float(cosine.standard_error):.5f}")
print(f"exact  : {jnp.pi:.5f}")
