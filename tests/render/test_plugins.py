"""The renderer's plugin design: registries, material sets, strategies passed as objects."""

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.render as rr
from radiometria.render import _registry
from radiometria.scattering import DiffuseBxDF

from ._synthetic import furnace_camera, lit_box_scene

ABSTRACT = {
    "MATERIALS": rr.AbstractMaterial,
    "LIGHTS": rr.AbstractLight,
    "INTEGRATORS": rr.AbstractIntegrator,
    "SAMPLERS": rr.AbstractSampler,
    "TEXTURES": rr.AbstractTexture,
    "ACCELERATORS": rr.AbstractAccelerator,
}


@pytest.mark.parametrize("registry", sorted(ABSTRACT))
def test_registry_maps_names_to_plugin_classes(registry):
    table = getattr(_registry, registry)
    assert table
    for name, cls in table.items():
        assert issubclass(cls, ABSTRACT[registry]), (name, cls)
        if hasattr(cls, "NAME"):  # Mitsuba's other sampler names map to one of ours
            assert cls.NAME == _registry.SAMPLER_ALIASES.get(name, name)


def _wavelengths(n):
    return jnp.linspace(400.0, 700.0, 4 * n, dtype=jnp.float32).reshape(n, 4)


def _uniform(seed, shape):
    return jax.random.uniform(jax.random.key(seed), shape, jnp.float32)


def _directions(n, seed):
    u = 2.0 * _uniform(seed, (2, n, 3)) - 1.0
    w = u / jnp.linalg.norm(u, axis=-1, keepdims=True)
    return w[0].at[:, 2].set(jnp.abs(w[0][:, 2])), w[1]


@pytest.mark.parametrize("n", [40, 300])
def test_material_set_gives_each_path_its_own_bxdf(n):
    """A scene of several kinds gives each path exactly its own plugin's value, density and
    sample, asked one query at a time or all three at once (`f_pdf_sample`). With 40 paths
    every kind is evaluated on every path and picked per path; with 300 each kind's BxDF is
    built and evaluated only on its own paths, gathered into blocks and scattered back
    (`_materials._set._on_paths`), which must change no path's result and mix no paths up."""
    props = [
        ("diffuse", {"reflectance": 0.3}),
        ("roughconductor", {"material": "Au", "alpha": 0.3, "specular_reflectance": 0.5}),
        ("dielectric", {"int_ior": 1.7, "specular_transmittance": 0.8}),
        ("diffuse", {"reflectance": rr.LinearRGB([0.2, 0.5, 0.7])}),
        ("roughdiffuse", {"reflectance": 0.6, "alpha": 0.4}),
        ("roughplastic", {"diffuse_reflectance": rr.LinearRGB([0.1, 0.3, 0.7]), "alpha": 0.2}),
    ]
    plugins = [_registry.MATERIALS[t].from_properties(p) for t, p in props]
    mset = rr.MaterialSet.from_materials(plugins)
    assert len(mset.plugins) == 5 and not mset.identity_rows
    # Kinds in an irregular order, so that a block's paths are not a contiguous run.
    material = jnp.asarray((np.arange(n) * 7 + np.arange(n) // 5) % len(props), jnp.int32)
    wl = _wavelengths(n)
    wo, wi = _directions(n, 0)
    u = _uniform(1, (n, 3))

    @eqx.filter_jit
    def queries(materials, rows):
        # One compiled program per material set (op by op, the blocks' many small
        # operations took a minute to dispatch and compile one at a time).
        bxdf = materials.bxdf(rows, wl)
        return (
            bxdf.f(wo, wi),
            bxdf.pdf(wo, wi),
            bxdf.sample_f(wo, u[:, 0], u[:, 1:]),
            bxdf.f_pdf_sample(wo, wi, u[:, 0], u[:, 1:]),
        )

    f_mixed, pdf_mixed, sample, (f_all, pdf_all, sample_all) = queries(mset, material)

    def same(got, want, rows):
        got, want = np.asarray(got)[rows], np.asarray(want)[rows]
        if got.dtype == bool:
            np.testing.assert_array_equal(got, want)
        else:
            np.testing.assert_allclose(got, want, rtol=2e-6, atol=1e-7)

    for m, plugin in enumerate(plugins):
        f_own, pdf_own, expect, _ = queries(plugin, jnp.zeros(n, jnp.int32))
        rows = np.flatnonzero(np.asarray(material) == m)
        same(f_mixed, f_own, rows)
        same(pdf_mixed, pdf_own, rows)
        same(f_all, f_own, rows)
        same(pdf_all, pdf_own, rows)
        for field in ("f", "wi", "pdf", "is_delta", "is_transmission", "eta"):
            same(getattr(sample, field), getattr(expect, field), rows)
            same(getattr(sample_all, field), getattr(expect, field), rows)
    transmissive = [False, False, True, False, False, False]
    assert np.asarray(mset.transmissive).tolist() == transmissive


def test_specular_reflectance_scales_reflection_only():
    """Mitsuba's `specular_reflectance` / `specular_transmittance` factors: f is scaled on
    the reflected or transmitted side; sampling and densities are the base BxDF's."""
    wl = _wavelengths(64)
    wo, _ = _directions(64, 2)
    u = _uniform(3, (64, 3))
    plain = rr.Dielectric.from_properties({"int_ior": 1.5}).bxdf(jnp.zeros(64, jnp.int32), wl)
    scaled = rr.Dielectric.from_properties(
        {"int_ior": 1.5, "specular_reflectance": 0.25, "specular_transmittance": 0.5}
    ).bxdf(jnp.zeros(64, jnp.int32), wl)
    a = plain.sample_f(wo, u[:, 0], u[:, 1:])
    b = scaled.sample_f(wo, u[:, 0], u[:, 1:])
    np.testing.assert_array_equal(a.pdf, b.pdf)
    factor = np.where(np.asarray(a.is_transmission)[:, None], 0.5, 0.25)
    np.testing.assert_allclose(np.asarray(b.f), np.asarray(a.f) * factor, rtol=1e-6)


@pytest.mark.parametrize("name", sorted(_registry.MATERIALS))
def test_material_rejects_unknown_parameters_naming_them(name):
    with pytest.raises(ValueError, match=r"scene\.xml: material 'm'.*'shininess'.*supported"):
        _registry.MATERIALS[name].from_properties(
            {"shininess": 3.0}, where="scene.xml: material 'm'"
        )


def test_oren_nayar_renders_from_mitsuba_xml(tmp_path):
    """`OrenNayar` (thesis 3.1), unreachable before the plugin design, renders from a scene
    file; with alpha = 0 it is Lambertian, so its image equals the `diffuse` one."""
    template = "\n".join(
        [
            '<scene version="3.0.0">',
            '  <sensor type="perspective"><float name="fov" value="60"/>',
            '    <transform name="to_world">',
            '      <lookat origin="0, 0, 1.5" target="0, 0, 0" up="0, 1, 0"/>',
            "    </transform>",
            '    <film type="hdrfilm"><integer name="width" value="8"/>',
            '      <integer name="height" value="8"/></film>',
            "  </sensor>",
            '  <integrator type="path"><integer name="max_depth" value="3"/></integrator>',
            '  <shape type="rectangle"><bsdf type="{bsdf}">',
            '    <rgb name="reflectance" value="0.6, 0.5, 0.4"/>{extra}</bsdf></shape>',
            '  <shape type="rectangle">',
            '    <transform name="to_world"><rotate x="1" angle="180"/><translate z="2"/>',
            "    </transform>",
            '    <emitter type="area"><rgb name="radiance" value="2, 2, 2"/></emitter>',
            "  </shape>",
            "</scene>",
        ]
    )
    images = {}
    for key, bsdf, extra in (
        ("smooth", "diffuse", ""),
        ("flat", "roughdiffuse", '<float name="alpha" value="0"/>'),
        ("rough", "roughdiffuse", '<float name="alpha" value="0.8"/>'),
    ):
        path = tmp_path / f"{key}.xml"
        path.write_text(template.format(bsdf=bsdf, extra=extra))
        images[key] = np.asarray(rr.render(path, spp=4, progress=False))
    assert np.all(np.isfinite(images["rough"])) and images["rough"].mean() > 0
    np.testing.assert_allclose(images["flat"], images["smooth"], rtol=1e-5, atol=1e-7)
    assert not np.allclose(images["rough"], images["smooth"], rtol=1e-3)


def test_direct_integrator_is_the_two_segment_path_estimator():
    scene, cam = lit_box_scene(), furnace_camera(8, 8)
    kw = dict(camera=cam, spp=2, seed=4, progress=False)
    direct = np.asarray(rr.render(scene, integrator=rr.Direct(), **kw))
    two = np.asarray(rr.render(scene, integrator=rr.Path(max_depth=2, rr_depth=2), **kw))
    np.testing.assert_array_equal(direct, two)
    deeper = np.asarray(rr.render(scene, integrator=rr.Path(max_depth=5), **kw))
    assert deeper.mean() > direct.mean()  # indirect light adds energy


class _Antithetic(rr.AbstractSampler):
    """A user-defined sampler: independent variates mirrored on odd passes (1 - u)."""

    NAME: ClassVar[str] = "antithetic"

    def sample(self, seed, pixel, pass_index, first_dim, n_dims, dtype=jnp.float32):
        u = rr.Independent().sample(seed, pixel, pass_index // 2, first_dim, n_dims, dtype)
        odd = (pass_index % 2 == 1)[..., None]
        return jnp.where(odd, jnp.minimum(1.0 - u, jnp.nextafter(1.0, 0.0).astype(dtype)), u)


def test_a_user_defined_sampler_plugs_into_render():
    """Any `AbstractSampler` subclass drives the driver; with antithetic variates the image
    still estimates the same radiance as the independent sampler (both at 64 spp)."""
    scene, cam = lit_box_scene(), furnace_camera(4, 4)
    kw = dict(camera=cam, spp=64, seed=1, progress=False, integrator=rr.Path(max_depth=3))
    mine = np.asarray(rr.render(scene, sampler=_Antithetic(), **kw))
    ref = np.asarray(rr.render(scene, sampler=rr.Independent(), **kw))
    assert np.all(np.isfinite(mine))
    np.testing.assert_allclose(mine.mean(), ref.mean(), rtol=0.05)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"integrator": "path"}, r"`integrator` must be a AbstractIntegrator.*Path\(\)"),
        ({"sampler": "sobol"}, r"`sampler` must be a AbstractSampler.*OwenSobol\(\)"),
        ({"sampler": "halton"}, r"`sampler`.*'halton'.*Known names"),
    ],
)
def test_render_takes_objects_not_strings(kwargs, match):
    with pytest.raises(TypeError, match=match):
        rr.render(lit_box_scene(), camera=furnace_camera(2, 2), spp=1, progress=False, **kwargs)


def test_path_rejects_bad_depths():
    with pytest.raises(ValueError, match="max_depth"):
        rr.Path(max_depth=0)
    with pytest.raises(ValueError, match="rr_depth"):
        rr.Path(rr_depth=True)


def test_compile_scene_names_material_and_parameter():
    desc = rr.load_scene("cornell-box")
    bad = dataclasses.replace(desc.materials[0], params={"roughness": 0.2})
    desc = dataclasses.replace(desc, materials=(bad, *desc.materials[1:]))
    with pytest.raises(ValueError, match=r"cornell-box: material .*'roughness'"):
        rr.compile_scene(desc, width=4, height=4)


def test_scene_integrator_follows_the_file():
    desc = rr.load_scene("cornell-box")
    assert rr.scene_integrator(desc) == rr.Path(max_depth=8, rr_depth=5)
    direct = dataclasses.replace(desc, integrator="direct")
    assert isinstance(rr.scene_integrator(direct), rr.Direct)


def test_plugins_are_pytrees_that_jit_and_differentiate():
    """A material plugin is an equinox Module: jit sees its arrays, grad flows to them."""
    plugin = rr.Diffuse.from_properties({"reflectance": 0.4})
    wl = _wavelengths(8)
    wo, wi = _directions(8, 5)

    def mean_f(p):
        return jnp.mean(p.bxdf(jnp.zeros(8, jnp.int32), wl).f(wo, wi))

    grads = eqx.filter_grad(mean_f)(plugin)
    g = np.asarray(grads.reflectance.table.values)
    # f = R / pi on the upper hemisphere: d mean(f) / dR sums to (#upper / n) / pi over the grid
    upper = np.mean(np.asarray(wi[:, 2]) > 0)
    np.testing.assert_allclose(g.sum(), upper / np.pi, rtol=1e-5)
    assert float(eqx.filter_jit(mean_f)(plugin)) == pytest.approx(float(mean_f(plugin)))
    assert isinstance(plugin.bxdf(jnp.zeros(8, jnp.int32), wl), DiffuseBxDF)
