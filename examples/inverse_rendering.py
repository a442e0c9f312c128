# %% [markdown]
# # Inverse rendering: a wall's albedo and a light's temperature by gradient descent
#
# The spectral path tracer is a JAX function, so `jax.grad` differentiates a rendered image
# with respect to the scene's spectra. Here the Cornell box, its light made a blackbody, is
# rendered with the true red-wall albedo (a linear sRGB colour, turned into a reflectance
# spectrum by the sigmoid-polynomial table of thesis section 2.2.3) and the true light
# temperature (Planck's law, eq. 1.24). Both are then recovered from that image alone,
# starting from a blue-grey wall and a 6500 K light, by Adam on an image loss whose gradient
# flows through the path tracer (next-event estimation, MIS, Russian roulette, hero
# wavelengths; thesis ch. 5-8), the film (eq. 2.12-2.14), the RGB-to-spectrum lookup
# (eq. 2.25-2.27) and Planck's law. Run as `python examples/inverse_rendering.py [OUT_DIR]`;
# `RADIOMETRIA_SMOKE=1` shrinks the image, the sample counts and the number of steps.
#
# **How the gradient is computed.** `path_radiance` traces each path segment with stream
# compaction: a loop over the chunks of live paths whose trip count is a traced value. JAX
# differentiates such a loop in forward mode (`jax.jvp`, `jax.jacfwd`) but not in reverse
# mode. `path_radiance(..., compact=False)` traces every path in every segment instead (a
# loop of static length that gives the same estimate), which `jax.grad` differentiates; the
# optimisation below uses it. For four parameters forward mode would serve as well: outside
# smoke mode the script checks that `jax.jacfwd` through the compacted loop gives the same
# gradient. Russian roulette's survival probability is detached from the gradient (as in
# Mitsuba 3), so the gradient of a path that survives it is an unbiased estimate of the
# gradient of the expected radiance.
#
# **Noise.** Each step renders the image with the same random numbers (common random
# numbers: one fixed seed), so the loss is a deterministic, piecewise smooth function of the
# parameters and the descent converges without the jitter of fresh noise at every step. The
# target is a separate, less noisy render with other seeds (the "photograph"), so the fit
# cannot reach zero loss by matching the target's noise. The loss is the relative squared
# error of 8 x 8 pixel block means, $(I - T)^2 / (|T| + 0.01)^2$ per block and channel:
# relative, because the red wall's green and blue albedos (about 0.04) change dim pixel
# values that an absolute error would hardly see under the noise; block means, because the
# squared error of noisy values is minimised by a darker albedo than the true one (the noise
# variance grows with the albedo: with 4 x 4 blocks the red albedo came out 9 % low), and
# averaging 64 pixels divides that bias by 64. What error remains is the Monte Carlo noise
# of the renders: the fit ends with a loss below that of the true values.

# %%
import os
import sys
import time
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import radiometria as rm

SMOKE = os.environ.get("RADIOMETRIA_SMOKE") == "1"
OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "out/examples")
OUT.mkdir(parents=True, exist_ok=True)

SIZE = 16 if SMOKE else 64  # image width = height [px]
SPP = 2 if SMOKE else 4  # samples per pixel of each optimisation step
TARGET_SEEDS = 2 if SMOKE else 16  # the target averages this many renders of SPP samples
STEPS = 100 if SMOKE else 150  # Adam steps
BLOCK = 8  # the loss compares BLOCK x BLOCK pixel means

# %% [markdown]
# ## The scene and a differentiable render
#
# `compile_scene` gives the renderer's arrays (a `RenderScene`, an equinox pytree) and the
# camera. The render below is the driver's estimator reduced to what a gradient needs: `SPP`
# samples uniform in each pixel (a box filter), four hero wavelengths per path,
# `path_radiance` and the film's spectral-to-XYZ estimate, averaged per pixel and converted to
# linear sRGB. The scene is an argument, so the parameters reach the image through the
# scene's spectral tables.

# %%
description = rm.render.load_scene("cornell-box")
base_scene, camera, _ = rm.render.compile_scene(description, width=SIZE, height=SIZE)
RED = [m.name for m in description.materials].index("red")
INTEGRATOR = rm.render.scene_integrator(description)  # the scene file's `Path` integrator
MAX_DEPTH, RR_DEPTH = INTEGRATOR.max_depth, INTEGRATOR.rr_depth  # 8 segments, roulette from 5
GRID = jnp.asarray(rm.render.wavelength_grid_nm(), jnp.float32)  # the renderer's 1 nm grid
LUT = rm.upsampling.get_lut("sRGB")
CMFS = rm.camera.Film(1, 1, dtype=jnp.float32)  # only its colour-matching functions are used


def camera_samples(seed):
    """Rays, hero wavelengths and bounce variates of SPP paths per pixel, fixed by `seed`."""
    n = SIZE * SIZE * SPP
    dims = 3 + rm.render.sample_dimensions(MAX_DEPTH)
    u = jax.random.uniform(jax.random.key(seed), (n, dims), jnp.float32)
    pixel = jnp.repeat(jnp.arange(SIZE * SIZE), SPP)
    raster = jnp.stack([pixel % SIZE, pixel // SIZE], axis=-1).astype(jnp.float32) + u[:, :2]
    origins, directions = camera.generate_ray(raster)
    wavelength_nm, pdf = rm.render.sample_hero_wavelengths(u[:, 2])
    return origins, directions, wavelength_nm, pdf, u[:, 3:]


def render(scene, samples, *, compact=True):
    """Linear sRGB image (SIZE, SIZE, 3) of `scene` from `camera_samples` (box filter)."""
    origins, directions, wavelength_nm, pdf, u = samples
    radiance = rm.render.path_radiance(
        scene,
        origins,
        directions,
        wavelength_nm,
        u,
        max_depth=MAX_DEPTH,
        rr_depth=RR_DEPTH,
        compact=compact,
    )
    xyz = rm.camera.film_samples_to_XYZ(CMFS, radiance, wavelength_nm, pdf)
    xyz = xyz.reshape(SIZE, SIZE, SPP, 3).mean(axis=2)
    return rm.colorimetry.XYZ_to_RGB(xyz, "sRGB")


# %% [markdown]
# ## The scene's parameters
#
# - The red wall's linear sRGB albedo, kept in (0, 1) as the logistic sigmoid of an
#   unconstrained vector `albedo_logit`, and upsampled to a reflectance spectrum on the
#   renderer's grid by `RGBAlbedoSpectrum` (differentiable in the colour), as `compile_scene`
#   does for the scene file's colour.
# - The light, a blackbody $L(\lambda) = s(T)\,B(\lambda, T)$ whose scale $s(T)$ keeps the
#   luminance factor $Y = \int L\bar y\,d\lambda / \int\bar y\,d\lambda$ of the scene's own
#   light: the temperature changes only the light's colour, which the image shows as the
#   colour cast on the white walls. The fit runs on $\log(T / 1000\,\mathrm{K})$.

# %%
RGB_TRUE = np.asarray(description.materials[RED].params["reflectance"].rgb, np.float32)
T_TRUE, T_START = 3200.0, 6500.0  # [K]
cmfs = rm.colorimetry.get_cmfs()
YBAR = jnp.asarray(np.interp(GRID, cmfs.wavelengths_nm, cmfs.values[:, 1]), jnp.float32)
LIGHT_Y = float(jnp.sum(base_scene.light.radiance.table.values[0] * YBAR) / jnp.sum(YBAR))


def reflectance_table(scene):
    """The scene's reflectance rows: its materials are all Lambertian, one `Diffuse` plugin
    whose rows are in material order."""
    (diffuse,) = scene.materials.plugins
    return diffuse.reflectance.table


def scene_at(params):
    """The Cornell box with the red wall's albedo and the light's temperature of `params`."""
    rgb = jax.nn.sigmoid(params["albedo_logit"])
    reflectance = rm.upsampling.RGBAlbedoSpectrum(LUT, rgb)(GRID)  # [1]
    planck = rm.radiometry.planck(GRID, 1000.0 * jnp.exp(params["log_temperature"]))
    radiance = planck * (LIGHT_Y * jnp.sum(YBAR) / jnp.sum(planck * YBAR))  # [W m^-2 sr^-1 nm^-1]
    return eqx.tree_at(
        lambda s: (reflectance_table(s).values, s.light.radiance.table.values),
        base_scene,
        (
            reflectance_table(base_scene).values.at[RED].set(reflectance),
            radiance[None, :],
        ),
    )


def parameters(rgb, temperature):
    rgb = jnp.asarray(rgb, jnp.float32)
    return {
        "albedo_logit": jnp.log(rgb) - jnp.log1p(-rgb),
        "log_temperature": jnp.log(jnp.float32(temperature) / 1000.0),
    }


truth = parameters(RGB_TRUE, T_TRUE)
start = parameters([0.4, 0.5, 0.6], T_START)
# The upsampling is `compile_scene`'s: the scene's own red-wall spectrum comes back.
row_error = jnp.max(
    jnp.abs(reflectance_table(scene_at(truth)).values - reflectance_table(base_scene).values)
)
print(
    f"red-wall spectrum, differentiable upsampling vs compile_scene: max |diff| = {row_error:.1e}"
)

# %% [markdown]
# ## The target and the loss

# %%
render_jit = jax.jit(render)
t0 = time.perf_counter()
target = sum(render_jit(scene_at(truth), camera_samples(100 + s)) for s in range(TARGET_SEEDS))
target = target / TARGET_SEEDS
samples = camera_samples(0)  # common random numbers: the same paths at every step


def blocks(image):
    return image.reshape(SIZE // BLOCK, BLOCK, SIZE // BLOCK, BLOCK, 3).mean(axis=(1, 3))


def loss(params, *, compact=False):
    image = render(scene_at(params), samples, compact=compact)
    reference = blocks(target)
    return jnp.mean(((blocks(image) - reference) / (jnp.abs(reference) + 0.01)) ** 2)


loss_and_grad = jax.jit(jax.value_and_grad(loss))  # reverse mode, through compact=False
value, gradient = loss_and_grad(start)
print(f"target and first gradient: {time.perf_counter() - t0:.1f} s; loss at the start {value:.3e}")
print(f"  jax.grad   {jax.tree.map(lambda g: np.round(np.asarray(g), 6), gradient)}")
if not SMOKE:  # forward mode through the compacted loop: the same numbers (one more compile)
    forward = jax.jit(jax.jacfwd(lambda p: loss(p, compact=True)))(start)
    print(f"  jax.jacfwd {jax.tree.map(lambda g: np.round(np.asarray(g), 6), forward)}")

# %% [markdown]
# ## Adam
#
# Plain Adam (Kingma & Ba 2015; optax's `adam` does the same), one learning rate per parameter:
# 0.1 for the albedo logits, 0.03 for the log temperature, and short memories for both
# moments ($\beta_1 = 0.5$, $\beta_2 = 0.9$ instead of 0.9 and 0.999). The red albedo and the
# temperature trade off against each other (a bluer light on a redder wall), and their large
# early gradients dominate; with the default memories their momentum overshoots along that
# valley and the weak green and blue gradients, which take over once it is crossed, get small
# steps for hundreds of iterations.

# %%
LEARNING_RATE = {"albedo_logit": 0.1, "log_temperature": 0.03}


def adam(params, steps, beta1=0.5, beta2=0.9, eps=1e-8):
    m = jax.tree.map(jnp.zeros_like, params)
    v = jax.tree.map(jnp.zeros_like, params)
    history, losses = [params], []
    for t in range(1, steps + 1):
        value, g = loss_and_grad(params)
        m = jax.tree.map(lambda m, g: beta1 * m + (1 - beta1) * g, m, g)
        v = jax.tree.map(lambda v, g: beta2 * v + (1 - beta2) * g * g, v, g)
        params = {
            k: params[k]
            - LEARNING_RATE[k] * (m[k] / (1 - beta1**t)) / (jnp.sqrt(v[k] / (1 - beta2**t)) + eps)
            for k in params
        }
        history.append(params)
        losses.append(float(value))
    return history, np.asarray(losses)


t0 = time.perf_counter()
history, losses = adam(start, STEPS)
seconds = time.perf_counter() - t0
rgb_history = np.asarray([jax.nn.sigmoid(p["albedo_logit"]) for p in history])
t_history = 1000.0 * np.exp(np.asarray([p["log_temperature"] for p in history]))
print(f"{STEPS} Adam steps ({SIZE}x{SIZE} px, {SPP} spp) in {seconds:.1f} s")
print(f"  red-wall albedo: true {np.round(RGB_TRUE, 4)}, recovered {np.round(rgb_history[-1], 4)}")
print(f"  light temperature: true {T_TRUE:.0f} K, recovered {t_history[-1]:.0f} K")
print(
    f"  loss {losses[0]:.3e} -> {losses[-1]:.3e}; at the true values {loss_and_grad(truth)[0]:.3e}"
)

# %% [markdown]
# ## Convergence


# %%
def show(ax, image, title):
    ax.imshow(np.asarray(rm.colorimetry.srgb_eotf_inverse(jnp.clip(image, 0.0, 1.0))))
    ax.set_title(title, fontsize=9)
    ax.axis("off")


fig, axes = plt.subplots(2, 3, figsize=(12, 7.5))
axes[0, 0].semilogy(losses)
axes[0, 0].set_ylabel("loss (relative squared error of block means)")
for i, (c, name) in enumerate(zip("rgb", "RGB", strict=True)):
    axes[0, 1].plot(rgb_history[:, i], color=c, label=name)
    axes[0, 1].axhline(RGB_TRUE[i], color=c, ls="--", lw=0.8)
axes[0, 1].set_ylabel("red-wall albedo (linear sRGB)")
axes[0, 1].legend(title="dashed: true")
axes[0, 2].plot(t_history)
axes[0, 2].axhline(T_TRUE, color="k", ls="--", lw=0.8)
axes[0, 2].set_ylabel("light temperature [K]")
for ax in axes[0]:
    ax.set_xlabel("Adam step")
show(axes[1, 0], target, f"target: albedo {np.round(RGB_TRUE, 2)}, {T_TRUE:.0f} K")
show(
    axes[1, 1],
    render_jit(scene_at(start), samples),
    f"start: albedo (0.4, 0.5, 0.6), {T_START:.0f} K",
)
show(axes[1, 2], render_jit(scene_at(history[-1]), samples), "recovered")
fig.tight_layout()
fig.savefig(OUT / "inverse_rendering.png", dpi=100)
print("wrote", OUT / "inverse_rendering.png")
