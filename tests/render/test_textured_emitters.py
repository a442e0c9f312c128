"""Textured `area` emitters (issue 12): the radiance of an area light looked up at the uv of
the point that emits, in every integrator that evaluates emission (hits, next-event
estimation, emitted rays). Proven against Mitsuba 3 (its emitter's `eval` at given uv, and a
scene with the per-pixel z-test and a negative control) and a closed form (a texture of one
constant value renders what that constant radiance renders, sample by sample)."""

import numpy as np
import pytest

from radiometria.render import load_scene, render

from ._mitsuba import perspective_xml

mi = pytest.importorskip("mitsuba")
dr = pytest.importorskip("drjit")

SIZE = 16
CHECKER = """<texture type="checkerboard" name="radiance">
        <rgb name="color0" value="{c0}"/><rgb name="color1" value="{c1}"/>
        <transform name="to_uv"><scale x="2" y="2"/></transform></texture>"""


def _scene(tmp_path, radiance: str, integrator: str = "path", name: str = "scene") -> str:
    path = tmp_path / f"{name}.xml"
    path.write_text(
        f"""<scene version="3.0.0">
  <integrator type="{integrator}"><integer name="max_depth" value="3"/></integrator>
  {perspective_xml("0, 1.2, 3.2", 55, SIZE)}
  <shape type="rectangle">
    <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/>
      <translate y="-0.6"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.6"/></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale x="0.9" y="0.6"/><rotate x="1" angle="20"/>
      <translate y="0.2" z="-0.4"/></transform>
    <emitter type="area">{radiance}</emitter>
  </shape>
</scene>"""
    )
    return path


def test_textured_radiance_matches_mitsuba_emitter_eval():
    """Our area light's radiance at a uv equals Mitsuba's emitter `eval` there (albedo
    spectra of the checkerboard's colours, no D65, as Mitsuba 3.9)."""
    import jax.numpy as jnp

    from radiometria.render._lights import AreaLight
    from radiometria.render._spectral import LinearRGB
    from radiometria.render._textures import TextureSpec

    mi.set_variant("scalar_spectral")
    c0, c1 = [0.9, 0.3, 0.1], [0.1, 0.5, 0.9]
    checker = {"type": "checkerboard", "color0": {"type": "rgb", "value": c0},
               "color1": {"type": "rgb", "value": c1}}  # fmt: skip
    emitter = {"type": "area", "radiance": checker}
    em = mi.load_dict({"type": "scene", "r": {"type": "rectangle", "emitter": emitter}})
    em = em.emitters()[0]
    tex = AreaLight.radiance_texture(
        [TextureSpec("checkerboard", colors=(LinearRGB(c0), LinearRGB(c1)))]
    )
    wl = np.array([430.0, 510.0, 580.0, 660.0])
    uv = np.array([[0.1, 0.2], [0.7, 0.2], [0.3, 0.8], [0.9, 0.9]])
    ours = np.asarray(
        tex(jnp.zeros(4, jnp.int32), jnp.asarray(np.tile(wl, (4, 1)), jnp.float32),
            jnp.asarray(uv, jnp.float32))
    )  # fmt: skip
    theirs = []
    for u in uv:
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(0, 0, 1)
        si.n = mi.Vector3f(0, 0, 1)
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        si.uv = mi.Point2f(*map(float, u))
        si.wavelengths = mi.UnpolarizedSpectrum(*map(float, wl))
        theirs.append(np.array(em.eval(si)))
    np.testing.assert_allclose(ours, np.array(theirs), rtol=2e-3, atol=1e-5)
    assert abs(ours[0, 0] - ours[1, 0]) > 0.1  # the two squares differ


@pytest.mark.parametrize(
    "integrator",
    ["path", pytest.param("ptracer", marks=pytest.mark.slow),
     pytest.param("volpath", marks=pytest.mark.slow),
     pytest.param("bdpt", marks=pytest.mark.slow)],
)  # fmt: skip
def test_constant_texture_equals_constant_radiance(tmp_path, integrator):
    """A checkerboard of two equal flat spectra renders, sample by sample, what the same
    flat spectrum as the emitter's radiance renders."""
    flat = '<spectrum name="{n}" value="2.5"/>'
    textured = _scene(
        tmp_path,
        CHECKER.replace('<rgb name="color0" value="{c0}"/>', flat.format(n="color0")).replace(
            '<rgb name="color1" value="{c1}"/>', flat.format(n="color1")
        ),
        integrator,
        "textured",
    )
    plain = _scene(tmp_path, flat.format(n="radiance"), integrator, "plain")
    a = np.asarray(render(textured, spp=4, progress=False, return_xyz=True))
    b = np.asarray(render(plain, spp=4, progress=False, return_xyz=True))
    assert float(b.mean()) > 0
    np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-6)


def test_textured_emitter_scene_loads(tmp_path):
    path = _scene(tmp_path, CHECKER.format(c0="0.9, 0.3, 0.1", c1="0.1, 0.5, 0.9"))
    assert len(load_scene(path).emitters) == 1


@pytest.mark.slow
@pytest.mark.parametrize("ours", ["path", "bdpt"])
def test_checkerboard_emitter_passes_the_z_test_against_mitsuba(tmp_path, ours):
    """The checkerboard light seen directly and lighting the floor (its NEE samples look the
    texture up at the sampled point; bdpt's emitted rays and connections too), against
    Mitsuba's `path` (Mitsuba has no bdpt)."""
    from radiometria.render import BDPT

    from ._mitsuba import z_test_against_mitsuba

    path = _scene(tmp_path, CHECKER.format(c0="0.95, 0.3, 0.1", c1="0.1, 0.4, 0.95"))
    kwargs = {"integrator": BDPT(max_depth=3)} if ours == "bdpt" else {}
    res = z_test_against_mitsuba(path, spp=64, ref_spp=1024, **kwargs)
    assert res.passed, res.message


@pytest.mark.slow
def test_a_mirrored_emitter_texture_fails_the_z_test(tmp_path):
    """Negative control: our checkerboard's colours swapped (Mitsuba's scene unchanged)."""
    from radiometria.montecarlo import pixel_z_test

    from ._mitsuba import mitsuba_moments

    good = _scene(tmp_path, CHECKER.format(c0="0.95, 0.3, 0.1", c1="0.1, 0.4, 0.95"), name="g")
    bad = _scene(tmp_path, CHECKER.format(c0="0.1, 0.4, 0.95", c1="0.95, 0.3, 0.1"), name="b")
    mean, var = mitsuba_moments(good, 1024, seed=1)
    ours = np.asarray(render(bad, spp=64, return_xyz=True, progress=False), np.float64)
    assert not pixel_z_test(ours, mean, var, 64, 1024).passed
