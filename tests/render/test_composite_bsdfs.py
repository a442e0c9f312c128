"""Composite BSDFs (issue 12): `blendbsdf` and `mask`, plugins built from nested materials.

The plugins' BxDFs at a hit (uv-dependent weights and opacities included) are compared with
Mitsuba 3's own `blendbsdf` and `mask` (`eval`, `pdf`, `scalar_rgb` with grey spectra), and a
scene using both with the per-pixel z-test against Mitsuba 3 `scalar_spectral`, with a
negative control that must fail.

The scene uses Mitsuba's `direct` integrator: Mitsuba 3.9's `path` integrator renders a mask
lit by an area light with the opacity applied twice (a mask of opacity 0.3 facing an area
light: `direct` gives 0.3 of the opaque surface's radiance, `path` with `max_depth` 2 gives
0.09), which no unbiased estimator of the mask's BSDF can match.
"""

import jax.numpy as jnp
import numpy as np
import pytest
from PIL import Image

from radiometria.render import SceneError, load_scene
from radiometria.render._materials import (
    BlendBSDF,
    Diffuse,
    Mask,
    MaterialSet,
    RoughConductor,
    RoughDielectric,
)
from radiometria.render._textures import TextureSpec

from ._mitsuba import floor_and_light_xml, perspective_xml

mi = pytest.importorskip("mitsuba")
dr = pytest.importorskip("drjit")

WL = 550.0


def _dirs(n, seed, lower=False):
    v = np.random.default_rng(seed).normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = np.abs(v[:, 2]) * (-1 if lower else 1)
    return v.astype(np.float32).astype(np.float64)


def _mitsuba_eval_pdf(params, wo, wi, uv):
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict(params)
    ctx, ev, pd = mi.BSDFContext(), [], []
    for a, b, c in zip(wo, wi, uv, strict=True):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(*map(float, a))
        si.uv = mi.Point2f(*map(float, c))
        si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
        w = mi.Vector3f(*map(float, b))
        ev.append(float(bsdf.eval(ctx, si, w)[0]))
        pd.append(float(bsdf.pdf(ctx, si, w)))
    return np.array(ev), np.array(pd)


def _ours(plugin, wo, wi, uv):
    """Our plugin's f cos and pdf (the plugins render in float32)."""
    mats = MaterialSet.from_materials([plugin])
    n = wo.shape[0]
    wl = jnp.full((n, 4), WL, jnp.float32)
    b = mats.bxdf(jnp.zeros(n, jnp.int32), wl, jnp.asarray(uv, jnp.float32))
    wo32, wi32 = jnp.asarray(wo, jnp.float32), jnp.asarray(wi, jnp.float32)
    f = np.asarray(b.f(wo32, wi32), np.float64)[:, 0] * np.abs(wi[:, 2])
    return f, np.asarray(b.pdf(wo32, wi32), np.float64)


CHECKER = TextureSpec("checkerboard", colors=(0.2, 0.9))
MI_CHECKER = {"type": "checkerboard", "color0": 0.2, "color1": 0.9}


@pytest.mark.parametrize("weight", [0.3, "checkerboard"])
def test_blendbsdf_plugin_matches_mitsuba_eval_and_pdf(weight):
    """Two Lambertian children (rough microfacet children differ from Mitsuba's by its
    separable masking term, independently of the blend)."""
    wo, wi = _dirs(64, 0), _dirs(64, 1)
    uv = np.random.default_rng(2).uniform(0, 1, (64, 2))
    ours = BlendBSDF.from_properties({
        "weight": CHECKER if weight == "checkerboard" else weight,
        "bsdf_0": Diffuse.from_properties({"reflectance": 0.4}),
        "bsdf_1": Diffuse.from_properties({"reflectance": 0.9}),
    })  # fmt: skip
    params = {
        "type": "blendbsdf", "weight": MI_CHECKER if weight == "checkerboard" else weight,
        "a": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.4] * 3}},
        "b": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.9] * 3}},
    }  # fmt: skip
    ev, pd = _mitsuba_eval_pdf(params, wo, wi, uv)
    f, pdf = _ours(ours, wo, wi, uv)
    np.testing.assert_allclose(f, ev, rtol=1e-4, atol=1e-7)
    np.testing.assert_allclose(pdf, pd, rtol=1e-4, atol=1e-7)


@pytest.mark.parametrize("lower", [False, True])
def test_mask_plugin_matches_mitsuba_eval_and_pdf_on_both_sides(lower):
    wo, wi = _dirs(64, 3, lower), _dirs(64, 4, lower)
    uv = np.random.default_rng(5).uniform(0, 1, (64, 2))
    ours = Mask.from_properties(
        {"opacity": CHECKER, "bsdf_0": Diffuse.from_properties({"reflectance": 0.7})}
    )
    nested = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.7] * 3}}
    params = {"type": "mask", "opacity": MI_CHECKER, "a": nested}
    ev, pd = _mitsuba_eval_pdf(params, wo, wi, uv)
    f, pdf = _ours(ours, wo, wi, uv)
    assert (ev > 0).any() != lower  # from behind a one-sided nested BSDF is black
    np.testing.assert_allclose(f, ev, rtol=1e-4, atol=1e-7)
    np.testing.assert_allclose(pdf, pd, rtol=1e-4, atol=1e-7)


def test_composites_of_one_kind_join_their_nested_materials():
    """Two blends with different nested kinds in one set give each its own BxDF."""
    d = Diffuse.from_properties({"reflectance": 0.4})
    c = RoughConductor.from_properties({"alpha": 0.3, "distribution": "ggx"})
    g = RoughDielectric.from_properties({"alpha": 0.2, "distribution": "ggx"})
    a = BlendBSDF.from_properties({"weight": 0.25, "bsdf_0": d, "bsdf_1": c})
    b = BlendBSDF.from_properties({"weight": 0.6, "bsdf_0": g, "bsdf_1": d})
    both = MaterialSet.from_materials([d, a, b])
    assert len(both.plugins) == 2 and np.asarray(both.transmissive).tolist() == [0, 0, 1]
    wo, wi = _dirs(16, 6), _dirs(16, 7)
    uv = np.zeros((16, 2))
    wo, wi = jnp.asarray(wo, jnp.float32), jnp.asarray(wi, jnp.float32)
    for index, alone in ((1, a), (2, b)):
        mats = MaterialSet.from_materials([alone])
        wl = jnp.full((16, 4), WL, jnp.float32)
        joint = both.bxdf(jnp.full(16, index, jnp.int32), wl, jnp.asarray(uv, jnp.float32))
        single = mats.bxdf(jnp.zeros(16, jnp.int32), wl, jnp.asarray(uv, jnp.float32))
        np.testing.assert_allclose(joint.f(wo, wi), single.f(wo, wi), rtol=1e-6)
        np.testing.assert_allclose(joint.pdf(wo, wi), single.pdf(wo, wi), rtol=1e-6)


# -- scenes ------------------------------------------------------------------------------------

SIZE = 16
COMPOSITES = """<texture type="checkerboard" id="chk"><float name="color0" value="0.15"/>
    <float name="color1" value="0.85"/>
    <transform name="to_uv"><scale x="2" y="2"/></transform></texture>
  <bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.7, 0.2, 0.1"/></bsdf>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.9"/><rotate y="1" angle="30"/>
      <translate x="-0.9"/></transform>
    <bsdf type="blendbsdf"><ref name="weight" id="chk"/><ref id="red"/>
      <bsdf type="roughconductor"><float name="alpha" value="0.2"/>
        <string name="material" value="Au"/></bsdf></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.9"/><rotate y="1" angle="-30"/>
      <translate x="0.9"/></transform>
    <bsdf type="mask"><texture type="bitmap" name="opacity">
        <string name="filename" value="opacity.png"/>
        <string name="filter_type" value="nearest"/></texture>
      <bsdf type="twosided"><bsdf type="diffuse">
        <rgb name="reflectance" value="0.1, 0.3, 0.8"/></bsdf></bsdf></bsdf>
  </shape>"""


def _scene(tmp_path, swap: bool = False):
    grey = np.array([[0, 255, 64, 191], [128, 32, 224, 96]], np.uint8)
    Image.fromarray(grey).save(tmp_path / "opacity.png")  # one channel, as Mitsuba needs
    body = COMPOSITES
    if swap:  # the blend's weights w -> 1 - w
        body = body.replace('"0.15"', '"x"').replace('"0.85"', '"0.15"').replace('"x"', '"0.85"')
    path = tmp_path / f"scene{int(swap)}.xml"
    path.write_text(
        f"""<scene version="3.0.0">
  <integrator type="direct"/>
  {perspective_xml("0, 1, 4", 45, SIZE)}
  {floor_and_light_xml(4, 6)}
  <emitter type="constant"><rgb name="radiance" value="0.4"/></emitter>
  {body}
</scene>"""
    )
    return path


@pytest.mark.slow
def test_blend_and_mask_scene_passes_the_z_test_against_mitsuba(tmp_path):
    from ._mitsuba import z_test_against_mitsuba

    res = z_test_against_mitsuba(_scene(tmp_path), spp=64, ref_spp=1024)
    assert res.passed, res.message


@pytest.mark.slow
def test_a_wrong_blend_weight_fails_the_z_test(tmp_path):
    """Negative control: our blend's weights w -> 1 - w (Mitsuba's scene unchanged)."""
    from radiometria.montecarlo import pixel_z_test
    from radiometria.render import render

    from ._mitsuba import mitsuba_moments

    mean, var = mitsuba_moments(_scene(tmp_path), 1024, seed=1)
    wrong = _scene(tmp_path, swap=True)
    ours = np.asarray(render(wrong, spp=64, return_xyz=True, progress=False), np.float64)
    res = pixel_z_test(ours, mean, var, 64, 1024)
    assert not res.passed, res.message


@pytest.mark.parametrize(
    ("bsdf", "message"),
    [
        ('<bsdf type="blendbsdf"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>',
         "needs a 'weight'"),
        ('<bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="diffuse"/></bsdf>',
         "needs 2 nested"),
        ('<bsdf type="blendbsdf"><float name="weight" value="1.5"/><bsdf type="diffuse"/>'
         '<bsdf type="diffuse"/></bsdf>', r"must lie in \[0.0, 1.0\], got 1.5"),
        ('<bsdf type="twosided"><bsdf type="mask"><bsdf type="diffuse"/></bsdf></bsdf>',
         "cannot be two-sided"),
        ('<bsdf type="twosided"><bsdf type="blendbsdf"><float name="weight" value="0.5"/>'
         '<bsdf type="diffuse"/><bsdf type="dielectric"/></bsdf></bsdf>', "transmitting child"),
        ('<bsdf type="mask"><float name="alpha" value="0.5"/><bsdf type="diffuse"/></bsdf>',
         "unsupported parameter 'alpha'"),
    ],
)  # fmt: skip
def test_bad_composites_name_file_line_and_problem(tmp_path, bsdf, message):
    path = tmp_path / "bad.xml"
    path.write_text(
        f'<scene version="3.0.0">\n<shape type="rectangle">\n{bsdf}\n</shape>\n</scene>'
    )
    with pytest.raises(SceneError, match=message) as info:
        load_scene(path)
    assert str(info.value).startswith(f"{path}:3"), str(info.value)


# -- textured roughness and specular reflectance (rough conductors) ---------------------------

TEXTURED_METAL = """<shape type="rectangle">
    <transform name="to_world"><scale value="1.4"/><rotate x="1" angle="-60"/>
      <translate y="-0.3"/></transform>
    <bsdf type="roughconductor"><string name="material" value="Au"/>
      <texture type="checkerboard" name="alpha"><float name="color0" value="{a0}"/>
        <float name="color1" value="{a1}"/>
        <transform name="to_uv"><scale x="3" y="3"/></transform></texture>
      <texture type="bitmap" name="specular_reflectance">
        <string name="filename" value="opacity.png"/>
        <string name="filter_type" value="nearest"/></texture></bsdf>
  </shape>"""


def _metal_scene(tmp_path, a0=0.05, a1=0.4):
    grey = np.array([[0, 255, 64, 191], [128, 32, 224, 96]], np.uint8)
    Image.fromarray(grey).save(tmp_path / "opacity.png")
    path = tmp_path / f"metal{a0}.xml"
    path.write_text(
        f"""<scene version="3.0.0">
  <integrator type="direct"/>
  {perspective_xml("0, 1, 4", 45, SIZE)}
  {floor_and_light_xml(4, 6)}
  {TEXTURED_METAL.format(a0=a0, a1=a1)}
</scene>"""
    )
    return path


@pytest.mark.slow
def test_textured_roughness_and_reflectance_pass_the_z_test_against_mitsuba(tmp_path):
    from ._mitsuba import z_test_against_mitsuba

    res = z_test_against_mitsuba(_metal_scene(tmp_path), spp=64, ref_spp=1024)
    assert res.passed, res.message


@pytest.mark.slow
def test_swapped_roughness_texture_fails_the_z_test(tmp_path):
    """Negative control: our checkerboard's two roughness values swapped."""
    from radiometria.montecarlo import pixel_z_test
    from radiometria.render import render

    from ._mitsuba import mitsuba_moments

    mean, var = mitsuba_moments(_metal_scene(tmp_path), 1024, seed=1)
    wrong = _metal_scene(tmp_path, a0=0.4, a1=0.05)
    ours = np.asarray(render(wrong, spp=64, return_xyz=True, progress=False), np.float64)
    res = pixel_z_test(ours, mean, var, 64, 1024)
    assert not res.passed, res.message
