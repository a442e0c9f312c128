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
# # 7. Writing your own integrator
#
# Thesis chapter 8. The renderer's integrators are built from public pieces, and a new one
# needs nothing else:
#
# - `radiometria.render.compile_scene` gives a `RenderScene`: triangles as arrays (`p0`, `e1`,
#   `e2`, `normal`) and a material index per triangle; its `materials` (a `MaterialSet` of
#   material plugins, whose spectra are `SpectrumTable` rows); its `light` (an `AreaLight`:
#   the emitter index per triangle, the emitted radiance and the light-sampling distribution
#   `light_face`, `light_cdf`, `light_pdf_area`); and its `accelerator` with the ray queries
#   `intersect_closest` / `intersect_any`;
# - `PinholeCamera.generate_ray` turns raster positions into rays (section 2.3.1);
# - `radiometria.montecarlo` has the warps (cosine hemisphere, triangle, discrete);
# - `radiometria.render.sample_hero_wavelengths` and `radiometria.camera.film_samples_to_XYZ`
#   handle the spectral side.
#
# An integrator written with them is a pure function of arrays, so `jax.jit`, `jax.vmap` and
# `jax.grad` apply to it. Below: ambient occlusion, then spectral direct lighting, checked
# against the library's `Direct` integrator, and its derivatives with respect to the light's
# colour temperature and a wall's albedo. The renderer is float32, and so is everything here.

# %%
import os
import time

import jax
import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np

import radiometria as rm

SMOKE = os.environ.get("RADIOMETRIA_SMOKE") == "1"
SIZE, SPP = (16, 8) if SMOKE else (64, 64)

description = rm.render.load_scene("cornell-box")
scene, camera, _ = rm.render.compile_scene(description, width=SIZE, height=SIZE)
# the top-left corner of every pixel, (SIZE * SIZE, 2) [px]
iy, ix = jnp.meshgrid(jnp.arange(SIZE), jnp.arange(SIZE), indexing="ij")
pixels = jnp.stack([ix, iy], axis=-1).reshape(-1, 2).astype(jnp.float32)

# %% [markdown]
# ## The first hit
#
# The accelerator's `intersect_closest` returns a `Hit` (ray parameter, triangle index,
# barycentrics); the point and the geometric normal come from the scene's triangle arrays.
# The Cornell box's materials scatter on the front side only (the side the normal points to).


# %%
def first_hit(origins, directions):
    """Closest hit of `(n, 3)` rays: (hit anything, front side, triangle, point, normal)."""
    hit = scene.accelerator.intersect_closest(origins, directions, jnp.inf)
    face = jnp.where(hit.valid, hit.prim, 0)
    b1, b2 = hit.b1[:, None], hit.b2[:, None]
    point = scene.p0[face] + b1 * scene.e1[face] + b2 * scene.e2[face]
    normal = scene.normal[face]
    front = jnp.sum(normal * directions, axis=-1) < 0
    return hit.valid, front, face, point, normal


# %% [markdown]
# ## Ambient occlusion
#
# The fraction of the cosine-weighted hemisphere above the first hit that is open up to a
# distance `r`: $A = \frac{1}{\pi}\int_{H^2} V(p, \omega)\cos\theta\,d\omega$. With directions
# drawn from the cosine density $\cos\theta/\pi$ the estimator is the mean visibility. The
# function handles one pixel with its `spp` samples, `u` of shape `(spp, 4)`: two variates for
# the position in the pixel and two for the direction.


# %%
def ambient_occlusion(pixel, u, radius=0.5):
    origins, directions = camera.generate_ray(pixel + u[:, 0:2])
    valid, front, _, point, normal = first_hit(origins, directions)
    normal = jnp.where(front[:, None], normal, -normal)  # towards the camera
    s, t = rm.scattering.coordinate_system(normal)
    local = rm.montecarlo.sample_cosine_hemisphere(u[:, 2:4])
    wi = rm.scattering.to_world((s, t, normal), local)
    occluded = scene.accelerator.intersect_any(point + 1e-4 * normal, wi, radius)
    return jnp.mean(jnp.where(valid & ~occluded, 1.0, 0.0))


# %% [markdown]
# `jax.vmap` maps the one-pixel function over all pixels and `jax.jit` compiles the result
# into one program. The first call compiles, later calls reuse it.

# %%
ao_image = jax.jit(jax.vmap(ambient_occlusion))
u = jax.random.uniform(jax.random.key(0), (SIZE * SIZE, SPP, 4))
for call in ("first call (compiles)", "second call"):
    start = time.perf_counter()
    ao = ao_image(pixels, u).block_until_ready()
    print(f"{call}: {time.perf_counter() - start:.2f} s")
plt.imshow(np.asarray(ao).reshape(SIZE, SIZE), cmap="gray", vmin=0, vmax=1)
plt.title(f"ambient occlusion, r = 0.5, {SPP} spp")
plt.axis("off")

# %% [markdown]
# ## Spectral direct lighting
#
# A one-bounce estimator: the emission seen directly, plus next-event estimation at the first
# hit. A light triangle is chosen with the light's distribution and a point $q$ is drawn
# uniformly on it; `light_pdf_area` is the density of $q$ per unit area (selection
# probability over area), so with the Lambertian BRDF $\rho(\lambda)/\pi$
#
# $$L_r = \frac{\rho(\lambda)}{\pi}\,L_e(\lambda)\,V(p, q)\,
#   \frac{\cos\theta_p \cos\theta_q}{\lVert q - p\rVert^2\, p_A(q)}.$$
#
# Every path carries four hero wavelengths, and the film converts its four radiances into
# XYZ. `params=None` uses the scene's own light; otherwise the light is a blackbody at
# `params["temperature"]` [K], normalised to the scene light's radiance at 560 nm, and the red
# wall's reflectance is scaled by `params["red_albedo"]`.

# %%
film = rm.camera.Film(1, 1)  # only its colour-matching functions are used
RED = [m.name for m in description.materials].index("red")
LIGHT_SPECTRUM = rm.render.tabulate_spectrum(
    description.emitters[0].radiance, rm.upsampling.RGBIlluminantSpectrum
)
LIGHT_AT_560 = float(np.interp(560.0, rm.render.wavelength_grid_nm(), LIGHT_SPECTRUM))
# The Cornell box's materials are all Lambertian: one `Diffuse` plugin, whose reflectance
# texture has one row per material (`row_of` maps a material index to its row).
(DIFFUSE,) = scene.materials.plugins


def light_radiance(params, emitter, wavelength_nm):
    if params is None:
        return scene.light.radiance(emitter, wavelength_nm)
    temperature = params["temperature"]
    planck = rm.radiometry.planck(wavelength_nm, temperature)
    return LIGHT_AT_560 * planck / rm.radiometry.planck(560.0, temperature)


def direct_lighting(params, pixel, u):
    """XYZ of one pixel, `u` (spp, 6): [emitted; reflected], (2, 3)."""
    origins, directions = camera.generate_ray(pixel + u[:, 0:2])
    wavelength_nm, pdf = rm.render.sample_hero_wavelengths(u[:, 2])
    valid, front, face, point, normal = first_hit(origins, directions)
    seen = valid & front
    # emission seen directly
    emitter = scene.light.face_emitter[face]
    le = light_radiance(params, jnp.maximum(emitter, 0), wavelength_nm)
    emitted = jnp.where((seen & (emitter >= 0))[:, None], le, 0.0)
    # next-event estimation: a light triangle, then a uniform point on it
    weights = jnp.diff(scene.light.light_cdf, prepend=0.0)
    choice, _, _ = rm.montecarlo.sample_discrete(u[:, 3], weights)
    light = scene.light.light_face[choice]
    b = rm.montecarlo.sample_uniform_triangle(u[:, 4:6])
    q = scene.p0[light] + b[:, 1:2] * scene.e1[light] + b[:, 2:3] * scene.e2[light]
    dist = jnp.linalg.norm(q - point, axis=-1)
    wi = (q - point) / dist[:, None]
    cos_p = jnp.sum(normal * wi, axis=-1)
    cos_q = -jnp.sum(scene.normal[light] * wi, axis=-1)
    visible = ~scene.accelerator.intersect_any(point + 1e-4 * normal, wi, dist * (1.0 - 1e-3))
    material = scene.face_material[face]
    rho = DIFFUSE.reflectance(scene.materials.row_of[material], wavelength_nm)
    if params is not None:
        rho = rho * jnp.where(material == RED, params["red_albedo"], 1.0)[:, None]
    le_q = light_radiance(params, scene.light.face_emitter[light], wavelength_nm)
    ok = seen & visible & (cos_p > 0) & (cos_q > 0)
    g = jnp.where(ok, cos_p * cos_q / (dist**2 * scene.light.light_pdf_area[light]), 0.0)
    reflected = rho / jnp.pi * le_q * g[:, None]
    xyz = [rm.camera.film_samples_to_XYZ(film, x, wavelength_nm, pdf) for x in (emitted, reflected)]
    return jnp.stack([jnp.mean(x, axis=0) for x in xyz])


direct_image = jax.jit(jax.vmap(direct_lighting, in_axes=(None, 0, 0)))

# %% [markdown]
# A check against the library: `render(..., integrator=Direct())` minus the emission alone
# (`Path(max_depth=1)`, same seed, so the same camera samples) is the reflected direct light,
# which the library estimates with light and BSDF samples combined by MIS. A box filter of
# radius 1/2 px makes its pixels plain averages, like ours. The emitted part is left out of the
# comparison: on the few pixels that see the light it is much noisier than the rest.

# %%
u = jax.random.uniform(jax.random.key(1), (SIZE * SIZE, SPP, 6))
ours = direct_image(None, pixels, u)
kw = {"camera": camera, "rfilter": rm.camera.BoxFilter(0.5), "spp": SPP, "progress": False}
library = rm.render.render(scene, integrator=rm.render.Direct(), return_xyz=True, **kw)
emission = rm.render.render(scene, integrator=rm.render.Path(max_depth=1), return_xyz=True, **kw)
ours_y = float(jnp.mean(ours[:, 1, 1]))
library_y = float(jnp.mean(library[..., 1] - emission[..., 1]))
print(f"mean Y of the reflected direct light: ours {ours_y:.4f}, library {library_y:.4f}")
print(f"relative difference {ours_y / library_y - 1:+.2%}")

# %%
rgb = rm.colorimetry.XYZ_to_RGB(ours.sum(axis=1), "sRGB").reshape(SIZE, SIZE, 3)
plt.imshow(np.clip(np.asarray(rm.colorimetry.srgb_eotf_inverse(jnp.clip(rgb, 0, 1))), 0, 1))
plt.title(f"our direct lighting, {SPP} spp")
plt.axis("off")

# %% [markdown]
# ## Differentiating a pixel
#
# A pixel on the red wall, its luminance-like $Y$ as a function of the parameters, with the
# random numbers held fixed (common random numbers), so the estimate is a smooth function of
# the parameters. `jax.grad` gives both derivatives at once, checked against central finite
# differences.

# %%
params = {"temperature": jnp.float32(3000.0), "red_albedo": jnp.float32(1.0)}
pixel = jnp.floor(camera.project(jnp.array([-0.999, 0.5, 0.0])))
_, _, face, _, _ = first_hit(*camera.generate_ray(pixel[None] + 0.5))
print("pixel", np.asarray(pixel), "sees", description.materials[scene.face_material[face[0]]].name)
u_pixel = jax.random.uniform(jax.random.key(2), (64 if SMOKE else 1024, 6))


def pixel_y(params):
    return direct_lighting(params, pixel, u_pixel).sum(axis=0)[1]


value, grad = jax.jit(jax.value_and_grad(pixel_y))(params)
print(f"Y = {float(value):.5f}")
pixel_y_jit = jax.jit(pixel_y)
for name, step in (("temperature", 10.0), ("red_albedo", 1e-2)):
    up = dict(params, **{name: params[name] + step})
    down = dict(params, **{name: params[name] - step})
    fd = (pixel_y_jit(up) - pixel_y_jit(down)) / (2 * step)
    rel = abs(float(grad[name]) / float(fd) - 1)
    print(f"dY/d{name}: grad {float(grad[name]):+.4e}, central difference {float(fd):+.4e}, "
          f"relative difference {rel:.1e}")  # fmt: skip
    assert rel < 1e-2, name

# %% [markdown]
# Forward mode gives the derivative of the whole image at once: `jax.jvp` of the vmapped
# estimator along the temperature. A hotter light is bluer; in $Y$ a wall gets darker or
# brighter depending on how its reflectance overlaps the shifted spectrum.


# %%
def image_y(temperature):
    p = dict(params, temperature=temperature)
    return direct_image(p, pixels, u).sum(axis=1)[:, 1].reshape(SIZE, SIZE)


y_image, dy_dt = jax.jvp(image_y, (jnp.float32(3000.0),), (jnp.float32(1.0),))
fig, axes = plt.subplots(1, 2, figsize=(9, 4), layout="constrained")
axes[0].imshow(np.asarray(y_image), cmap="gray", vmin=0, vmax=float(jnp.quantile(y_image, 0.95)))
axes[0].set_title("Y, blackbody light at 3000 K")
limit = float(jnp.quantile(jnp.abs(dy_dt), 0.98))
im = axes[1].imshow(np.asarray(dy_dt), cmap="RdBu", vmin=-limit, vmax=limit)
axes[1].set_title("dY / dT [1/K]")
fig.colorbar(im, ax=axes[1])
for ax in axes:
    ax.set_axis_off()
