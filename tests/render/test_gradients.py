"""Derivatives of path-traced radiance with respect to the scene's spectra (float64).

The Cornell box in double precision, its red wall's reflectance upsampled from linear sRGB:
for fixed variates (common random numbers) and no Russian roulette, the estimate is a smooth
function of the colour, so `jax.grad` (reverse mode, `compact=False`) and `jax.jacfwd`
(forward mode, compacted loop) must both match central finite differences. With roulette,
the detached survival probability keeps the gradient unbiased.
"""

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria as rm
from radiometria.render import (
    RenderScene,
    SpectrumTable,
    compile_scene,
    load_scene,
    path_radiance,
    sample_dimensions,
    sample_hero_wavelengths,
    tabulate_spectrum,
    wavelength_grid_nm,
)
from radiometria.upsampling import RGBAlbedoSpectrum, RGBIlluminantSpectrum

DEPTH = 4
N_PATHS = 64


@functools.cache
def _setup(n_paths=N_PATHS, depth=DEPTH):
    """The Cornell box as a float64 Lambertian `RenderScene`, and `n_paths` camera paths."""
    desc = load_scene("cornell-box")
    reflectance = np.stack(
        [tabulate_spectrum(m.params["reflectance"], RGBAlbedoSpectrum) for m in desc.materials]
    )
    radiance = np.stack(
        [tabulate_spectrum(e.radiance, RGBIlluminantSpectrum) for e in desc.emitters]
    )
    scene = RenderScene.from_triangles(
        desc.vertices,
        desc.faces,
        desc.face_material,
        SpectrumTable(jnp.asarray(reflectance)),
        desc.face_emitter,
        SpectrumTable(jnp.asarray(radiance)),
        dtype=jnp.float64,
    )
    _, camera, _ = compile_scene(desc, width=8, height=8)
    dims = 3 + sample_dimensions(depth)
    u = jax.random.uniform(jax.random.key(0), (n_paths, dims), jnp.float64)
    origins, directions = camera.generate_ray(u[:, :2] * 8.0)  # anywhere in the 8 x 8 image
    wavelength_nm, _ = sample_hero_wavelengths(u[:, 2])
    red = [m.name for m in desc.materials].index("red")
    rgb = jnp.asarray(desc.materials[red].params["reflectance"].rgb, jnp.float64)
    rays = (origins.astype(jnp.float64), directions.astype(jnp.float64), wavelength_nm)
    return (scene, rays, u[:, 3:]), red, rgb


@functools.partial(jax.jit, static_argnames=("red", "compact", "depth", "rr_depth"))
def _radiance(rgb, data, *, red, compact=True, depth=DEPTH, rr_depth=DEPTH):
    """Radiance of the paths of `data` (`_setup`), summed over their hero wavelengths, with
    the red wall's albedo upsampled from linear sRGB `rgb`; roulette only if rr_depth < depth."""
    scene, (origins, directions, wavelength_nm), u = data
    grid = jnp.asarray(wavelength_grid_nm())
    row = rm.upsampling.RGBAlbedoSpectrum(rm.upsampling.get_lut("sRGB"), rgb)(grid)
    (diffuse,) = scene.materials.plugins  # one Lambertian plugin, rows in material order
    values = diffuse.reflectance.table.values.at[red].set(row)
    scene = eqx.tree_at(lambda s: s.materials.plugins[0].reflectance.table.values, scene, values)
    radiance = path_radiance(
        scene,
        origins,
        directions,
        wavelength_nm,
        u,
        max_depth=depth,
        rr_depth=rr_depth,
        compact=compact,
    )
    return jnp.sum(radiance, axis=-1)


def test_path_radiance_compact_false_matches_compacted():
    data, red, rgb = _setup()
    a = _radiance(rgb, data, red=red, compact=True)
    b = _radiance(rgb, data, red=red, compact=False)
    assert jnp.sum(a > 0) > N_PATHS // 2
    np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-12)


def test_path_radiance_grad_matches_finite_differences():
    """d(estimate)/d(rgb) of the red wall: reverse and forward mode against central FD."""
    data, red, rgb = _setup()

    def estimate(c, compact=True):
        return jnp.sum(_radiance(c, data, red=red, compact=compact))

    h = 1e-6
    fd = np.array([(estimate(rgb + h * e) - estimate(rgb - h * e)) / (2 * h) for e in np.eye(3)])
    reverse = jax.grad(lambda c: estimate(c, compact=False))(rgb)
    forward = jax.jacfwd(estimate)(rgb)
    assert np.all(np.abs(fd) > 1e-2)  # every channel of the colour reaches the estimate
    np.testing.assert_allclose(np.asarray(reverse), fd, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(forward), fd, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(reverse), np.asarray(forward), rtol=1e-10)


def test_path_radiance_compact_must_be_bool():
    (scene, (origins, directions, wavelength_nm), u), _, _ = _setup()
    with pytest.raises(TypeError, match="compact"):
        path_radiance(scene, origins, directions, wavelength_nm, u, max_depth=DEPTH, compact=1)


@pytest.mark.slow
def test_path_radiance_roulette_gradient_is_unbiased():
    """Roulette's survival probability is detached: with the same variates, the per-path
    gradients with and without roulette have the same mean (both estimate the gradient of the
    expected radiance). Differentiating q too would shift the mean by E[-beta dq / q^2]."""
    n, depth = 4096, 6
    data, red, rgb = _setup(n, depth)

    def per_path(rr_depth):
        return jax.jacfwd(lambda c: _radiance(c, data, red=red, depth=depth, rr_depth=rr_depth))

    d = np.asarray(per_path(2)(rgb) - per_path(depth)(rgb))  # (n, 3)
    assert np.count_nonzero(np.any(d != 0, axis=1)) > n // 10  # roulette acted on many paths
    z = d.mean(axis=0) / (d.std(axis=0, ddof=1) / np.sqrt(n))
    assert np.all(np.abs(z) < 5.0), z


def test_path_radiance_grad_through_a_mixture_of_material_kinds():
    """With two material kinds (the large box a rough conductor), each kind is evaluated on
    its own paths in blocks (`_materials._set._on_paths`, a static loop of conditionals):
    reverse and forward mode still match central finite differences, and the estimate
    equals that of every kind evaluated on every path."""
    from radiometria.render._materials import _set as material_set
    from radiometria.render._materials._rough_conductor import RoughConductor

    (scene, rays, u), red, rgb = _setup()
    desc = load_scene("cornell-box")
    metal = RoughConductor.from_properties({"alpha": 0.3, "material": "Cu"})
    metal = jax.tree.map(
        lambda x: x.astype(jnp.float64) if jnp.issubdtype(x.dtype, jnp.floating) else x, metal
    )
    (diffuse,) = scene.materials.plugins
    box = np.asarray(desc.face_shape) == desc.shape_names.index("large-box")
    face_material = jnp.where(jnp.asarray(box), 3, scene.face_material)
    materials = material_set.MaterialSet.from_materials([diffuse, metal])
    scene = eqx.tree_at(lambda s: (s.materials, s.face_material), scene, (materials, face_material))

    @functools.partial(jax.jit, static_argnames="compact")
    def estimate(c, compact=True):
        grid = jnp.asarray(wavelength_grid_nm())
        row = rm.upsampling.RGBAlbedoSpectrum(rm.upsampling.get_lut("sRGB"), c)(grid)
        values = scene.materials.plugins[0].reflectance.table.values.at[red].set(row)
        s = eqx.tree_at(lambda s: s.materials.plugins[0].reflectance.table.values, scene, values)
        radiance = path_radiance(s, *rays, u, max_depth=DEPTH, rr_depth=DEPTH, compact=compact)
        return jnp.sum(radiance)

    h = 1e-6
    fd = np.array([(estimate(rgb + h * e) - estimate(rgb - h * e)) / (2 * h) for e in np.eye(3)])
    reverse = jax.grad(lambda c: estimate(c, compact=False))(rgb)
    forward = jax.jacfwd(estimate)(rgb)
    assert np.all(np.abs(fd) > 1e-2)
    np.testing.assert_allclose(np.asarray(reverse), fd, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(forward), fd, rtol=1e-6)
    everywhere = material_set._MIN_SPLIT
    try:
        material_set._MIN_SPLIT = 10**9  # every kind on every path, as before the blocks
        plain = jax.jit(estimate.__wrapped__)(rgb)  # traced afresh
    finally:
        material_set._MIN_SPLIT = everywhere
    np.testing.assert_allclose(float(estimate(rgb)), float(plain), rtol=1e-12)
