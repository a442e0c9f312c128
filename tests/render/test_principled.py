"""The `principled` material plugin (issue 12): its BxDF at a hit against Mitsuba 3's own
`principled` in `scalar_spectral` at the same wavelengths (RGB upsampling of the base colour and
the luminance the tints divide by included), and a scene of principled spheres with the
per-pixel z-test against Mitsuba 3, with a negative control that must fail."""

import jax.numpy as jnp
import numpy as np
import pytest

from radiometria.render import SceneError, load_scene
from radiometria.render._materials import MaterialSet, Principled, PrincipledThin
from radiometria.render._spectral import LinearRGB
from radiometria.render._textures import TextureSpec

from ._mitsuba import floor_and_light_xml, perspective_xml

mi = pytest.importorskip("mitsuba")
dr = pytest.importorskip("drjit")

WAVELENGTHS = np.array([[412.0, 489.0, 566.0, 643.0], [455.0, 530.0, 605.0, 690.0]])
PARAMS = {
    "metallic": 0.3, "spec_trans": 0.4, "roughness": 0.5, "spec_tint": 0.5, "sheen": 0.7,
    "sheen_tint": 0.4, "clearcoat": 0.8, "clearcoat_gloss": 0.6, "flatness": 0.3,
    "anisotropic": 0.3, "specular": 0.6,
}  # fmt: skip
COLOR = [0.7, 0.35, 0.1]


def _dirs(n, seed):
    v = np.random.default_rng(seed).normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return v.astype(np.float32).astype(np.float64)


THIN_PARAMS = {
    "spec_trans": 0.4, "diff_trans": 0.9, "roughness": 0.5, "spec_tint": 0.5, "sheen": 0.7,
    "sheen_tint": 0.4, "flatness": 0.3, "anisotropic": 0.3, "eta": 1.4,
}  # fmt: skip


@pytest.mark.parametrize(("row", "thin"), [(0, False), (1, False), (0, True)])
def test_principled_plugin_matches_mitsuba_spectral(row, thin):
    """f cos and pdf equal Mitsuba's `eval` and `pdf` at four wavelengths of one path
    (`principled`, and `principledthin` from both sides)."""
    mi.set_variant("scalar_spectral")
    kind, params = ("principledthin", THIN_PARAMS) if thin else ("principled", PARAMS)
    bsdf = mi.load_dict({"type": kind, "base_color": {"type": "rgb", "value": COLOR}, **params})
    wo, wi = _dirs(60, 1), _dirs(60, 2)
    wl = WAVELENGTHS[row]
    ctx, ev, pd = mi.BSDFContext(), [], []
    for a, b in zip(wo, wi, strict=True):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(*map(float, a))
        si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
        si.wavelengths = mi.UnpolarizedSpectrum(*map(float, wl))
        w = mi.Vector3f(*map(float, b))
        ev.append(np.array(bsdf.eval(ctx, si, w)))
        pd.append(float(bsdf.pdf(ctx, si, w)))
    ev, pd = np.array(ev), np.array(pd)
    plugin = (PrincipledThin if thin else Principled).from_properties(
        {"base_color": LinearRGB(COLOR), **params}
    )
    assert np.asarray(plugin.transmissive_rows).tolist() == [True]
    assert bool(plugin.two_sided[0]) == thin
    n = wo.shape[0]
    b = MaterialSet.from_materials([plugin]).bxdf(
        jnp.zeros(n, jnp.int32), jnp.asarray(np.tile(wl, (n, 1)), jnp.float32), None
    )
    wo32, wi32 = jnp.asarray(wo, jnp.float32), jnp.asarray(wi, jnp.float32)
    f = np.asarray(b.f(wo32, wi32), np.float64) * np.abs(wi[:, 2:3])
    # float32 renders; the RGB-to-spectrum tables of the two renderers agree to ~1e-3.
    np.testing.assert_allclose(f, ev, rtol=5e-3, atol=2e-5)
    np.testing.assert_allclose(np.asarray(b.pdf(wo32, wi32)), pd, rtol=5e-3, atol=2e-5)
    assert np.count_nonzero(ev[:, 0]) > 20


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ({"eta": 1.5, "specular": 0.5}, "either 'eta' or 'specular'"),
        ({"metallic": 1.5}, r"'metallic' must lie in \[0.0, 1.0\], got 1.5"),
        ({"specular": -0.1}, r"'specular' must lie in \[0, 1\]"),
        ({"eta": 0.0}, "'eta' must be > 0"),
        ({"subsurface": 0.3}, "unsupported parameter"),
    ],
)
def test_bad_principled_parameters_are_named(params, message):
    with pytest.raises(ValueError, match=message):
        Principled.from_properties(params, where="scene.xml:3")


def test_spec_trans_makes_the_row_transmissive_and_eta_one_is_moved():
    """Mitsuba's `get_flag`: a `spec_trans` of 0 is no transmission lobe; eta = 1 with a
    transmission lobe becomes 1.001, specular = 0 becomes 1e-3, as in Mitsuba."""
    off = Principled.from_properties({"spec_trans": 0.0})
    on = Principled.from_properties({"spec_trans": 0.5, "eta": 1.0})
    tex = Principled.from_properties({"spec_trans": TextureSpec("checkerboard", colors=(0.0, 1.0))})
    assert [bool(p.transmits[0]) for p in (off, on, tex)] == [False, True, True]
    np.testing.assert_allclose(float(on.eta[0]), 1.001, rtol=1e-6)
    np.testing.assert_allclose(float(Principled.from_properties({}).eta[0]), 1.5, rtol=1e-6)


SIZE = 20
SPHERES = """<shape type="sphere"><point name="center" x="-0.95" y="-0.45" z="0.3"/>
    <float name="radius" value="0.5"/>
    <bsdf type="principled"><rgb name="base_color" value="0.9, 0.6, 0.2"/>
      <float name="metallic" value="0.9"/><float name="roughness" value="0.35"/>
      <float name="anisotropic" value="0.5"/></bsdf></shape>
  <shape type="sphere"><point name="center" x="0.0" y="-0.45" z="0.5"/>
    <float name="radius" value="0.5"/>
    <bsdf type="principled"><rgb name="base_color" value="0.95, 0.95, 0.95"/>
      <float name="spec_trans" value="1.0"/><float name="roughness" value="0.25"/>
      <float name="eta" value="1.5"/></bsdf></shape>
  <shape type="sphere"><point name="center" x="0.95" y="-0.45" z="0.3"/>
    <float name="radius" value="0.5"/>
    <bsdf type="principled"><rgb name="base_color" value="0.2, 0.35, 0.8"/>
      <float name="clearcoat" value="1.0"/><float name="clearcoat_gloss" value="0.7"/>
      <float name="roughness" value="0.7"/><float name="spec_tint" value="0.5"/></bsdf></shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.7"/><translate y="0.55" z="-0.6"/></transform>
    <bsdf type="principled"><texture type="checkerboard" name="base_color">
        <rgb name="color0" value="0.8, 0.2, 0.1"/><rgb name="color1" value="0.9, 0.9, 0.5"/>
        <transform name="to_uv"><scale x="3" y="3"/></transform></texture>
      <float name="sheen" value="1.0"/><float name="sheen_tint" value="0.6"/>
      <float name="roughness" value="0.9"/><float name="flatness" value="0.5"/></bsdf></shape>
  <shape type="rectangle">
    <transform name="to_world"><scale x="0.45" y="0.6"/><rotate y="1" angle="-60"/>
      <translate x="1.5" y="0.35" z="-0.2"/></transform>
    <bsdf type="principledthin"><rgb name="base_color" value="0.3, 0.7, 0.2"/>
      <float name="diff_trans" value="1.2"/><float name="spec_trans" value="0.3"/>
      <float name="roughness" value="0.4"/><float name="sheen" value="0.5"/></bsdf></shape>"""


def _scene(tmp_path, wrong: bool = False):
    body = (
        SPHERES.replace('name="metallic" value="0.9"', 'name="metallic" value="0.6"')
        if (wrong)
        else SPHERES
    )
    path = tmp_path / f"principled{int(wrong)}.xml"
    path.write_text(
        f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="8"/></integrator>
  {perspective_xml("0, 0.6, 3.6", 50, SIZE)}
  {floor_and_light_xml(4, 6)}
  <emitter type="constant"><rgb name="radiance" value="0.3"/></emitter>
  {body}
</scene>"""
    )
    return path


def test_principled_scene_loads(tmp_path):
    scene = load_scene(_scene(tmp_path))
    kinds = [m.type for m in scene.materials]
    assert kinds.count("principled") == 4 and kinds.count("principledthin") == 1, kinds


def test_principled_texture_for_an_unsupported_parameter_is_refused(tmp_path):
    path = tmp_path / "bad.xml"
    path.write_text(
        f"""<scene version="3.0.0">
  {perspective_xml("0, 0.6, 3.6", 50, 8)}
  <shape type="sphere"><bsdf type="principled"><texture type="checkerboard" name="eta"/>
  </bsdf></shape>
</scene>"""
    )
    with pytest.raises(SceneError, match="eta"):
        load_scene(path)


@pytest.mark.slow
def test_principled_scene_passes_the_z_test_against_mitsuba(tmp_path):
    from ._mitsuba import z_test_against_mitsuba

    res = z_test_against_mitsuba(_scene(tmp_path), spp=64, ref_spp=1024)
    assert res.passed, res.message


@pytest.mark.slow
def test_a_wrong_metallic_fails_the_z_test(tmp_path):
    """Negative control: our gold sphere is 0.6 metallic instead of 0.9."""
    from radiometria.montecarlo import pixel_z_test
    from radiometria.render import render

    from ._mitsuba import mitsuba_moments

    mean, var = mitsuba_moments(_scene(tmp_path), 1024, seed=1)
    ours = np.asarray(
        render(_scene(tmp_path, wrong=True), spp=64, return_xyz=True, progress=False), np.float64
    )
    res = pixel_z_test(ours, mean, var, 64, 1024)
    assert not res.passed, res.message
