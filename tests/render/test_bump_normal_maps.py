"""Normal and bump maps (issue 12): Mitsuba's `normalmap` and `bumpmap` adapters.

The plugins' BxDFs at hits with given differential geometry (dp/du, dp/dv, uv) are compared
with Mitsuba 3's own adapters (`eval`, `pdf`, `scalar_rgb`, the same surface interaction),
the texture gradient with Mitsuba's `eval_1_grad`, and a scene with both with the per-pixel
z-test against Mitsuba 3 `scalar_spectral`, with a negative control that must fail.
"""

import jax.numpy as jnp
import numpy as np
import pytest
from PIL import Image

from radiometria.render import SceneError, load_scene
from radiometria.render._materials import (
    BumpMap,
    Diffuse,
    HitGeometry,
    MaterialSet,
    NormalMap,
    PerturbedBxDF,
)
from radiometria.render._textures import RawImage, TextureSpec, read_texture_image
from radiometria.scattering import ConductorBxDF, DiffuseBxDF, RoughConductorBxDF

from ._mitsuba import floor_and_light_xml, perspective_xml

mi = pytest.importorskip("mitsuba")
dr = pytest.importorskip("drjit")


def _images(tmp_path):
    rng = np.random.default_rng(0)
    normals = rng.normal(size=(3, 4, 3)) * [0.4, 0.4, 1.0]
    normals[..., 2] = np.abs(normals[..., 2]) + 0.3
    normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
    rgb = np.round((normals + 1) / 2 * 255).astype(np.uint8)
    Image.fromarray(rgb).save(tmp_path / "normals.png")
    mirrored = rgb.copy()
    mirrored[..., :2] = 255 - mirrored[..., :2]  # tilts mirrored: (-x, -y, z)
    Image.fromarray(mirrored).save(tmp_path / "mirrored.png")
    Image.fromarray(rng.integers(0, 256, (5, 3), dtype=np.uint8)).save(tmp_path / "height.png")


def _dirs(n, seed):
    v = np.random.default_rng(seed).normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = np.abs(v[:, 2])
    return v.astype(np.float32).astype(np.float64)


# One hit geometry: shading normal +z (the world's), dp/du and dp/dv oblique.
DPDU = np.array([1.2, 0.3, 0.25])
DPDV = np.array([-0.2, 0.9, -0.1])


def _frame():
    """Mitsuba's shading frame: s = dp/du made orthogonal to n, t = n x s."""
    n = np.array([0.0, 0.0, 1.0])
    s = DPDU - n * (n @ DPDU)
    s /= np.linalg.norm(s)
    return s, np.cross(n, s), n


def _mitsuba_eval_pdf(params, wo, wi, uv):
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict(params)
    s, t, n = _frame()
    ctx, ev, pd = mi.BSDFContext(), [], []
    for a, b, c in zip(wo, wi, uv, strict=True):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.uv = mi.Point2f(*map(float, c))
        si.n = mi.Normal3f(*n)
        si.dp_du, si.dp_dv = mi.Vector3f(*DPDU), mi.Vector3f(*DPDV)
        frame = mi.Frame3f(mi.Vector3f(*s), mi.Vector3f(*t), mi.Vector3f(*n))
        si.sh_frame = frame
        si.wi = mi.Vector3f(*map(float, a))
        w = mi.Vector3f(*map(float, b))
        ev.append(float(bsdf.eval(ctx, si, w)[0]))
        pd.append(float(bsdf.pdf(ctx, si, w)))
    return np.array(ev), np.array(pd)


def _ours(plugin, wo, wi, uv):
    s, t, n = _frame()
    local = np.stack([s, t, n])  # rows: world -> local
    m = wo.shape[0]
    geometry = HitGeometry(
        *(jnp.asarray(np.tile(local @ x, (m, 1)), jnp.float32) for x in (DPDU, DPDV, n))
    )
    mats = MaterialSet.from_materials([plugin])
    wl = jnp.full((m, 4), 550.0, jnp.float32)
    b = mats.bxdf(jnp.zeros(m, jnp.int32), wl, jnp.asarray(uv, jnp.float32), geometry)
    wo32, wi32 = jnp.asarray(wo, jnp.float32), jnp.asarray(wi, jnp.float32)
    f = np.asarray(b.f(wo32, wi32), np.float64)[:, 0] * np.abs(wi[:, 2])
    return f, np.asarray(b.pdf(wo32, wi32), np.float64)


def _spec(path, filter_type="bilinear"):
    return TextureSpec("bitmap", rgb=read_texture_image(path, raw=True), filter_type=filter_type)


@pytest.mark.parametrize("kind", ["normalmap", "bumpmap"])
def test_adapters_match_mitsuba_eval_and_pdf(tmp_path, kind):
    _images(tmp_path)
    wo, wi = _dirs(64, 1), _dirs(64, 2)
    uv = np.random.default_rng(3).uniform(0, 1, (64, 2))
    nested = Diffuse.from_properties({"reflectance": 0.6})
    mi_nested = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.6] * 3}}
    if kind == "normalmap":
        ours = NormalMap.from_properties(
            {"normalmap": _spec(tmp_path / "normals.png"), "bsdf_0": nested}
        )
        texture = {"type": "bitmap", "filename": str(tmp_path / "normals.png"), "raw": True}
        params = {"type": "normalmap", "normalmap": texture, "b": mi_nested}
    else:
        ours = BumpMap.from_properties(
            {"texture": _spec(tmp_path / "height.png"), "scale": 0.3, "bsdf_0": nested}
        )
        texture = {"type": "bitmap", "filename": str(tmp_path / "height.png"), "raw": True}
        params = {"type": "bumpmap", "t": texture, "scale": 0.3, "b": mi_nested}
    ev, pd = _mitsuba_eval_pdf(params, wo, wi, uv)
    f, pdf = _ours(ours, wo, wi, uv)
    assert (ev == 0).any() and (ev > 0).sum() > 32  # some directions fall below the tilt
    np.testing.assert_allclose(f, ev, rtol=2e-4, atol=1e-6)
    np.testing.assert_allclose(pdf, pd, rtol=2e-4, atol=1e-6)


def _perturbed(nested, rows: int, seed: int) -> PerturbedBxDF:
    """A `PerturbedBxDF` with tilted normals (up to ~70 degrees), flips and shadowing on."""
    n = np.random.default_rng(seed).normal(size=(rows, 3)) * [0.6, 0.6, 1.0]
    n[:, 2] = np.abs(n[:, 2]) + 0.2
    on = jnp.ones(rows, bool)
    return PerturbedBxDF(nested, jnp.asarray(n), on, on)


_NESTED = {
    "diffuse": lambda: DiffuseBxDF(jnp.asarray([0.3, 0.6, 0.9])),
    "roughconductor": lambda: RoughConductorBxDF(0.3, jnp.asarray([0.2, 0.9, 1.5]), 3.0),
}


@pytest.mark.parametrize("nested", sorted(_NESTED))
def test_importance_mode_is_the_adjoint_of_radiance_mode(nested):
    # A light tracer's BxDF is the adjoint f*(wo, wi) = f(wi, wo) (Veach 1997 §3.7.6) of the
    # path tracer's, whose radiance mode is Mitsuba's own (above). A normal map is not
    # reciprocal: evaluating it in importance mode as in radiance mode (Mitsuba 3.9's
    # ptracer) is another BxDF, whose images disagree with the path tracer's (the scene test
    # below).
    rows = 512
    b = _perturbed(_NESTED[nested](), rows, 4)
    light, cam = jnp.asarray(_dirs(rows, 5)), jnp.asarray(_dirs(rows, 6))
    adjoint = np.asarray(b.f(light, cam, mode="importance"))
    np.testing.assert_allclose(adjoint, np.asarray(b.f(cam, light)), rtol=1e-6, atol=1e-15)
    assert (adjoint == 0).any() and (adjoint > 0).mean() > 0.5
    as_radiance = np.asarray(b.f(light, cam))
    assert np.abs(as_radiance - adjoint).max() > 0.2 * adjoint.max()


@pytest.mark.parametrize("nested", sorted(_NESTED))
def test_importance_samples_carry_the_adjoints_value_and_their_density(nested):
    # The light tracer samples in the frame of the given (light-side) direction; each sample's
    # value is the adjoint's and its density is `pdf`'s, so the weight f |cos| / pdf is
    # unbiased for the adjoint wherever it is sampled.
    rows = 1024
    b = _perturbed(_NESTED[nested](), rows, 7)
    light = jnp.asarray(_dirs(rows, 8))
    u = np.random.default_rng(9).uniform(size=(rows, 3))
    s = b.sample_f(light, jnp.asarray(u[:, 0]), jnp.asarray(u[:, 1:]), mode="importance")
    ok = np.asarray(s.pdf) > 0
    assert ok.mean() > 0.5
    f = np.asarray(b.f(light, s.wi, mode="importance"))
    np.testing.assert_allclose(np.asarray(s.f)[ok], f[ok], rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(np.asarray(s.pdf)[ok], np.asarray(b.pdf(light, s.wi))[ok],
                               rtol=1e-10)  # fmt: skip


def test_importance_mode_through_a_perturbed_mirror_reverses_the_radiance_sample():
    # A perturbed mirror (delta lobe): light arriving along l leaves along c with the value
    # that the path tracer's sample from c (back along l) has, F G(l) / |cos l| (the adjoint of
    # a delta lobe), not Mitsuba's F G(c) / |cos c_m| (frames that agree: no flipped normal).
    rows = 512
    b = _perturbed(ConductorBxDF(jnp.asarray([0.2, 1.1]), jnp.asarray([3.0, 2.5])), rows, 10)
    light = jnp.asarray(_dirs(rows, 11))
    u = jnp.asarray(np.random.default_rng(12).uniform(size=(rows, 3)))
    imp = b.sample_f(light, u[:, 0], u[:, 1:], mode="importance")
    rad = b.sample_f(imp.wi, u[:, 0], u[:, 1:])
    n = np.asarray(b.n)
    same_frame = np.ones(rows, bool)
    for w in (np.asarray(light), np.asarray(imp.wi)):
        same_frame &= w[:, 2] * np.einsum("ij,ij->i", w, n) > 0
    ok = same_frame & (np.asarray(imp.pdf) > 0) & (np.asarray(rad.pdf) > 0)
    assert ok.mean() > 0.5 and np.asarray(imp.is_delta).all()
    np.testing.assert_allclose(np.asarray(rad.wi)[ok], np.asarray(light)[ok], atol=1e-12)
    np.testing.assert_allclose(np.asarray(imp.f)[ok], np.asarray(rad.f)[ok], rtol=1e-10)


def test_texture_gradient_matches_mitsubas_eval_1_grad(tmp_path):
    _images(tmp_path)
    mi.set_variant("scalar_rgb")
    to_uv = np.array([[2.0, 0.5, 0.0, 0.1], [-0.3, 1.5, 0.0, 0.2], [0, 0, 1, 0], [0, 0, 0, 1]])
    tex = mi.load_dict({"type": "bitmap", "filename": str(tmp_path / "height.png"), "raw": True,
                        "to_uv": mi.ScalarTransform4f(to_uv)})  # fmt: skip
    img = RawImage.from_array(
        read_texture_image(tmp_path / "height.png", raw=True)[..., :1], to_uv=to_uv,
        dtype=jnp.float64,
    )  # fmt: skip
    uv = np.random.default_rng(4).uniform(-1, 2, (32, 2))
    expected_value, expected_grad = [], []
    for c in uv:
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.uv = mi.Point2f(*map(float, c))
        expected_value.append(tex.eval_1(si))
        expected_grad.append(list(tex.eval_1_grad(si)))
    np.testing.assert_allclose(np.asarray(img(jnp.asarray(uv)))[:, 0], expected_value, atol=2e-6)
    np.testing.assert_allclose(np.asarray(img.grad(jnp.asarray(uv)))[:, 0], expected_grad,
                               rtol=1e-4, atol=1e-4)  # fmt: skip


# -- scenes ------------------------------------------------------------------------------------

SIZE = 16
BODY = """<shape type="rectangle">
    <transform name="to_world"><scale value="0.9"/><rotate y="1" angle="25"/>
      <translate x="-0.95"/></transform>
    <bsdf type="normalmap"><texture type="bitmap" name="normalmap">
        <string name="filename" value="{normals}"/><boolean name="raw" value="true"/>
      </texture>
      <bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.9"/><rotate y="1" angle="-25"/>
      <translate x="0.95"/></transform>
    <bsdf type="bumpmap"><texture type="bitmap"><string name="filename" value="height.png"/>
        <boolean name="raw" value="true"/></texture>
      <float name="scale" value="{scale}"/>
      <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.5, 0.2"/></bsdf></bsdf>
  </shape>"""


def _scene(tmp_path, scale=0.3, normals="normals.png"):
    _images(tmp_path)
    path = tmp_path / f"scene{scale}{normals}.xml"
    path.write_text(
        f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  {perspective_xml("0, 1, 4", 45, SIZE)}
  {floor_and_light_xml(4, 6)}
  {BODY.format(scale=scale, normals=normals)}
</scene>"""
    )
    return path


@pytest.mark.slow
@pytest.mark.parametrize("integrator", ["path", "volpath"])
def test_normal_and_bump_map_scene_passes_the_z_test_against_mitsuba(tmp_path, integrator):
    # volpath (a scene without media: the same estimate as path) shades with the same frame.
    from radiometria.render import VolPath

    from ._mitsuba import z_test_against_mitsuba

    ours = {} if integrator == "path" else {"integrator": VolPath(max_depth=3)}
    res = z_test_against_mitsuba(_scene(tmp_path), spp=64, ref_spp=1024, **ours)
    assert res.passed, res.message


@pytest.mark.slow
@pytest.mark.parametrize("integrator", ["ptracer", "bdpt"])
def test_bidirectional_methods_render_normal_and_bump_maps_as_the_path_tracer(tmp_path, integrator):
    # Light paths scatter by the maps' adjoint (importance mode), so a light tracer and
    # bdpt estimate the path tracer's image: judged against Mitsuba's path tracer (its own
    # ptracer evaluates the maps as in radiance mode: with a box filter, 90.9 % of its pixel
    # channels pass against its path tracer, its mean 5.6 % low, and 99.9 % without the
    # maps). 16 renders give our per-sample variance; the mirrored maps fail.
    from radiometria.render import BDPT, PTracer

    from ._mitsuba import z_test_against_mitsuba

    ours = (PTracer if integrator == "ptracer" else BDPT)(max_depth=3)
    kwargs = dict(spp=32, ref_spp=1024, renders=16, integrator=ours)
    res = z_test_against_mitsuba(_scene(tmp_path), **kwargs)
    assert res.passed, res.message
    if integrator == "ptracer":
        wrong = _scene(tmp_path, scale=-0.3, normals="mirrored.png")
        res = z_test_against_mitsuba(_scene(tmp_path), ours_path=wrong, **kwargs)
        assert not res.passed, res.message


@pytest.mark.slow
def test_mirrored_normals_and_bumps_fail_the_z_test(tmp_path):
    """Negative control: our normal map's tilts mirrored and the bump scale negated
    (Mitsuba's scene unchanged)."""
    from ._mitsuba import z_test_against_mitsuba

    wrong = _scene(tmp_path, scale=-0.3, normals="mirrored.png")
    res = z_test_against_mitsuba(_scene(tmp_path), spp=64, ref_spp=1024, ours_path=wrong)
    assert not res.passed, res.message


@pytest.mark.parametrize(
    ("bsdf", "message"),
    [
        ('<bsdf type="normalmap"><bsdf type="diffuse"/></bsdf>', "needs a 'normalmap'"),
        ('<bsdf type="bumpmap"><bsdf type="diffuse"/></bsdf>', "needs a nested height"),
        ('<bsdf type="normalmap"><texture type="checkerboard" name="normalmap"/>'
         '<bsdf type="diffuse"/></bsdf>', "must be a bitmap texture"),
    ],
)  # fmt: skip
def test_bad_adapters_name_file_line_and_problem(tmp_path, bsdf, message):
    path = tmp_path / "bad.xml"
    path.write_text(
        f'<scene version="3.0.0">\n<shape type="rectangle">\n{bsdf}\n</shape>\n</scene>'
    )
    with pytest.raises(SceneError, match=message) as info:
        load_scene(path)
    assert str(info.value).startswith(f"{path}:3"), str(info.value)
