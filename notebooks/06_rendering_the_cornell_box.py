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
# # 6. Rendering the Cornell box
#
# Thesis chapters 8-9, with the camera and film of section 2.3. A scene goes through three
# stages: a `SceneDescription` (what the scene file says, NumPy and plain Python), a compiled
# `RenderScene` (device arrays for the integrators) with its camera and reconstruction filter,
# and an image from `radiometria.render.render`. Rendering is spectral: each camera path
# carries four hero wavelengths, and the film turns them into CIE XYZ, then linear sRGB.
# The renderer works in float32, so this notebook leaves JAX's default precision alone.

# %%
import os

import jax
import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np

import radiometria as rm

SMOKE = os.environ.get("RADIOMETRIA_SMOKE") == "1"
SIZE, SPP = (32, 4) if SMOKE else (128, 64)


def show(ax, rgb_linear, title, exposure=1.0):
    """Linear sRGB -> sRGB-encoded values in [0, 1] for `imshow` (clipped, no tone mapping)."""
    encoded = rm.colorimetry.srgb_eotf_inverse(jnp.clip(exposure * rgb_linear, 0.0, 1.0))
    ax.imshow(np.clip(np.asarray(encoded), 0.0, 1.0), interpolation="nearest")
    ax.set_title(title, fontsize=10)
    ax.set_axis_off()


# %% [markdown]
# ## The scene description
#
# `load_scene("cornell-box")` is Mitsuba 3's `cornell_box()` expanded into world-space
# triangles: every shape is merged into one triangle array, with a material and an emitter
# index per triangle.

# %%
description = rm.render.load_scene("cornell-box")
print(f"{description.n_triangles} triangles in {description.unit}")
for i, name in enumerate(description.shape_names):
    faces = np.flatnonzero(description.face_shape == i)
    material = description.materials[description.face_material[faces[0]]].name
    print(f"  {name:10s} {faces.size:2d} triangles, material {material}")
for m in description.materials:
    print(f"material {m.name!r}: {m.type}, {m.params}")
light = description.emitters[0]
print(f"emitter {light.name!r}: radiance {light.radiance}, area {light.total_area:.4f}")
print("camera:", description.camera.origin, "looking along", description.camera.direction)
print(f"film: {description.film}, max_depth {description.max_depth}")

# %% [markdown]
# The scene is authored in RGB (`LinearRGB` values); the renderer needs spectra.
# `tabulate_spectrum` tabulates each parameter on the renderer's 1 nm grid, the RGB spectrum
# class choosing what a triple means: reflectances as bounded sigmoid-polynomial spectra
# (`RGBAlbedoSpectrum`, Jakob & Hanika 2019, thesis 2.2.3), the light's RGB radiance as an
# illuminant spectrum (`RGBIlluminantSpectrum`: a smooth spectrum times D65), exactly as
# `compile_scene` does.

# %%
grid = rm.render.wavelength_grid_nm()
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 3.5), layout="constrained")
colours = {"white": "0.6", "green": "tab:green", "red": "tab:red"}
for m in description.materials:
    reflectance = rm.render.tabulate_spectrum(
        m.params["reflectance"], rm.upsampling.RGBAlbedoSpectrum
    )
    ax1.plot(grid, reflectance, color=colours.get(m.name, "k"), label=m.name)
ax1.set(xlabel="wavelength [nm]", ylabel="reflectance", title="materials")
ax1.legend()
radiance = rm.render.tabulate_spectrum(light.radiance, rm.upsampling.RGBIlluminantSpectrum)
ax2.plot(grid, radiance, color="orange")
ax2.set(xlabel="wavelength [nm]", ylabel="radiance [relative]", title="light")

# %% [markdown]
# ## Compiling it
#
# `compile_scene` returns the `RenderScene` (triangles as structure-of-arrays, the material
# plugins with their spectra as `SpectrumTable` rows, the area light with its discrete
# distribution for sampling, an accelerator), a `PinholeCamera` and the film's reconstruction
# filter. With 36 triangles, brute-force intersection is faster than a BVH, so the accelerator
# is a `BruteForceAccelerator` around a plain `TriangleMesh`.

# %%
scene, camera, rfilter = rm.render.compile_scene(description, width=SIZE, height=SIZE)
print("accelerator:", type(scene.accelerator).__name__)
print("triangle corners p0:", scene.p0.shape, scene.p0.dtype)
(diffuse,) = scene.materials.plugins  # the three Lambertian materials, one plugin
print(
    f"materials: {type(diffuse).__name__}, reflectance table",
    diffuse.reflectance.table.values.shape,
)
print("emissive triangles:", scene.light.light_face, "selection cdf:", scene.light.light_cdf)
print(f"camera {camera.width} x {camera.height} px, fov_x {float(camera.fov_x_deg):.2f} deg")
print(f"filter {type(rfilter).__name__}, radius {float(rfilter.radius)} px")
light_vertices = description.vertices[np.unique(description.faces[light.triangles])]
print("the light's corners in raster space [px]:\n", np.asarray(camera.project(light_vertices)))

# %% [markdown]
# ## Rendering
#
# `render` takes the scene name, a description or a compiled scene with its camera. It traces
# the paths in batches, so memory does not grow with the sample count, and compiles one step
# per configuration (the first call takes seconds). The integrator is an object: by default
# the scene file's (`Path(max_depth=8, rr_depth=5)` here); `max_depth` counts path segments as
# Mitsuba does, and `Direct()` is direct illumination (two segments).

# %%
rgb = rm.render.render(description, spp=SPP, width=SIZE, height=SIZE, progress=False)
direct = rm.render.render(
    description, spp=SPP, width=SIZE, height=SIZE, integrator=rm.render.Direct(), progress=False
)
print("mean linear sRGB, path  :", np.asarray(rgb.mean(axis=(0, 1))))
print("mean linear sRGB, direct:", np.asarray(direct.mean(axis=(0, 1))))
fig, axes = plt.subplots(1, 2, figsize=(9, 4.6), layout="constrained")
show(axes[0], rgb, f"path tracing, {SPP} spp")
show(axes[1], direct, f"direct illumination, {SPP} spp")

# %% [markdown]
# ## Convergence
#
# The relative mean squared error of small renders against a reference with 16 times the
# largest sample count. Independent samples converge as $1/N$; the padded Owen-scrambled Sobol
# sampler stratifies the pixel area, the wavelength and every 2D light and BSDF sample, and
# gets a lower error at equal spp (thesis ch. 5-7). `batch` is set to one pass over the image,
# so every sample count reuses one compiled step.

# %%
small, max_spp = (8, 8) if SMOKE else (32, 64)
counts = [2**i for i in range(int(np.log2(max_spp)) + 1)]
kw = {"width": small, "height": small, "progress": False, "batch": small * small}
reference = np.asarray(
    rm.render.render(description, spp=16 * max_spp, sampler=rm.render.OwenSobol(), seed=99, **kw)
)


def relative_mse(img):
    return float(np.mean((np.asarray(img) - reference) ** 2 / (reference**2 + 1e-2)))


fig, ax = plt.subplots(figsize=(5.5, 4))
samplers = {"independent": rm.render.Independent(), "sobol": rm.render.OwenSobol()}
for sampler, plugin in samplers.items():
    errors = [
        relative_mse(rm.render.render(description, spp=n, sampler=plugin, seed=1, **kw))
        for n in counts
    ]
    slope = np.polyfit(np.log(counts), np.log(errors), 1)[0]
    print(f"{sampler:11s} MSE slope {slope:+.2f}")
    ax.loglog(counts, errors, "o-", label=f"{sampler} (slope {slope:.2f})")
ax.loglog(counts, errors[0] * counts[0] / np.asarray(counts, float), "k--", label="1/N")
ax.set(xlabel="samples per pixel", ylabel="relative MSE")
ax.legend()

# %% [markdown]
# ## The spectral side: hero wavelengths
#
# One uniform variate gives a path its four wavelengths (Wilkie et al. 2014): $u$ and its three
# shifts by 1/4 are pushed through the inverse CDF of a density close to the luminous
# efficiency curve, so the four are stratified and each one is marginally distributed with
# that density.

# %%
u = jnp.array([0.02, 0.1, 0.17])
wavelength_nm, pdf = rm.render.sample_hero_wavelengths(u)
for ui, lam in zip(u, wavelength_nm, strict=True):
    print(f"u = {float(ui):.2f}: wavelengths {np.round(np.asarray(lam), 1)} nm")
many, _ = rm.render.sample_hero_wavelengths(jax.random.uniform(jax.random.key(0), (20_000,)))
plt.figure(figsize=(5.5, 3.5))
plt.hist(np.asarray(many).ravel(), bins=94, range=(360, 830), density=True, alpha=0.6)
plt.plot(grid, rm.montecarlo.visible_wavelengths_pdf(grid), "k", label="p(lambda)")
plt.xlabel("wavelength [nm]")
plt.legend()

# %% [markdown]
# The film turns the four radiance samples of a path into one XYZ estimate,
# $\frac14\sum_i L(\lambda_i)\,\bar{\mathbf{x}}(\lambda_i)/p(\lambda_i)/\int\bar y$
# (`radiometria.camera.film_samples_to_XYZ`): a constant spectrum $L = 1$ gives $Y = 1$ in
# expectation, and close to 1 for every path, because $p$ follows $\bar y$ closely.
# `return_xyz=True` returns the XYZ image itself.

# %%
film = rm.camera.Film(1, 1)
for lam, p in zip(wavelength_nm, pdf, strict=True):
    y = rm.camera.film_samples_to_XYZ(film, jnp.ones(4), lam, p)[1]
    print(f"Y of L = 1 at {np.round(np.asarray(lam))} nm: {float(y):.3f}")
xyz = rm.render.render(
    description, spp=SPP, width=SIZE, height=SIZE, return_xyz=True, progress=False
)
print("image chromaticity xy:", np.asarray(rm.colorimetry.XYZ_to_xy(xyz.mean(axis=(0, 1)))))

# %% [markdown]
# `cornell-box-measured` has no RGB anywhere: the Cornell Program of Computer Graphics'
# measured reflectance and light spectra (lengths in mm). Its light has the data's relative
# scale, so the image is exposed to a mean luminance of 0.18.

# %%
measured = rm.render.render(
    "cornell-box-measured", spp=SPP, width=SIZE, height=SIZE, progress=False
)
luminance = float(jnp.mean(measured @ jnp.array([0.2126, 0.7152, 0.0722])))
fig, axes = plt.subplots(1, 2, figsize=(9, 4.6), layout="constrained")
show(axes[0], rgb, "cornell-box (RGB, upsampled)")
show(axes[1], measured, "cornell-box-measured", exposure=0.18 / luminance)

# %% [markdown]
# ## Devices and sharding
#
# Every step of `render` shards its pixels over a 1-D mesh of the local devices
# (`jax.shard_map`), with no communication until the samples are added into the film; the
# image depends only on the seed and the batch, not on the device count. A CPU is one XLA
# device unless `XLA_FLAGS=--xla_force_host_platform_device_count=<cores>` is set before JAX
# is imported; on several hosts, call `jax.distributed.initialize(...)` everywhere and run the
# same `render` call (see the module docstring of `radiometria.render`). `devices=` picks the
# devices explicitly.

# %%
devices = jax.local_devices()
print(f"{len(devices)} local device(s):", devices)
again = rm.render.render(
    description, spp=SPP, width=SIZE, height=SIZE, devices=devices[:1], progress=False
)
print("same image on the first device alone:", bool(jnp.allclose(again, rgb, rtol=1e-5, atol=1e-6)))
