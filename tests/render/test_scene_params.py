"""Scene parameters that were once accepted and ignored (issue 12): the microfacet
`distribution` of rough BSDFs (Mitsuba's default Beckmann), `hide_emitters` of `path`,
sampler seeds and sample counts, film crop windows and principal point offsets (rendered,
against Mitsuba 3), `focus_distance` of a pinhole camera, and spectra from `.spd` files and
`regular`/`irregular` spectrum plugins."""

import numpy as np
import pytest

from radiometria.render._materials._rough_conductor import GGXRoughConductor, RoughConductor
from radiometria.render._materials._rough_dielectric import GGXRoughDielectric, RoughDielectric
from radiometria.render._scenes._mitsuba_xml import load_mitsuba_xml

SIZE = 16


def _xml(body: str, *, integrator: str = "", sensor: str = "", film: str = "", sampler: str = ""):
    """A sphere on a grey floor, lit by a rectangle light that the camera sees."""
    return f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="4"/>{integrator}</integrator>
  <sensor type="perspective">
    <float name="fov" value="50"/>{sensor}
    <transform name="to_world"><lookat origin="0, 0.5, 4" target="0, 0.3, 0" up="0, 1, 0"/>
    </transform>
    <sampler type="independent"><integer name="sample_count" value="16"/>{sampler}</sampler>
    <film type="hdrfilm"><integer name="width" value="{SIZE}"/>
      <integer name="height" value="{SIZE}"/><rfilter type="gaussian"/>{film}</film>
  </sensor>
  <shape type="rectangle">
    <transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/>
      <translate y="-1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale x="1.5" y="0.4"/><translate y="1.9" z="-1.5"/>
    </transform>
    <emitter type="area"><rgb name="radiance" value="5, 5, 5"/></emitter>
  </shape>
  {body}
</scene>
"""


BECKMANN_BALL = """<shape type="sphere"><float name="radius" value="0.8"/>
    <bsdf type="roughconductor"><string name="material" value="Cu"/>
      <float name="alpha" value="0.3"/></bsdf></shape>"""


@pytest.mark.slow
def test_beckmann_rough_conductor_matches_mitsuba(tmp_path):
    """A copper ball (roughconductor with Mitsuba's default distribution, Beckmann) against
    Mitsuba 3, pixel by pixel."""
    pytest.importorskip("mitsuba")
    from ._mitsuba import z_test_against_mitsuba

    path = tmp_path / "scene.xml"
    path.write_text(_xml(BECKMANN_BALL))
    res = z_test_against_mitsuba(path, spp=64, ref_spp=512)
    assert res.passed, res.message


def test_hide_emitters_blackens_only_directly_seen_emitters(tmp_path):
    from radiometria.render import Path, render

    path = tmp_path / "scene.xml"
    path.write_text(_xml(BECKMANN_BALL))
    a, b = (
        np.asarray(
            render(path, spp=4, return_xyz=True, progress=False,
                   integrator=Path(max_depth=4, hide_emitters=hide))
        )[..., 1]
        for hide in (False, True)
    )  # fmt: skip
    # The light (Y = 5 x the luminance of white) fills some pixels of the top rows; hidden,
    # those pixels keep only what the reconstruction filter (radius 2 px) brings in from rays
    # that hit the scene around the light.
    lit = a > 4.0
    assert lit.any() and float(b[lit].max()) < 0.01 * float(a[lit].min())
    np.testing.assert_array_less(b, a * (1 + 1e-5) + 1e-7)
    # Beyond the filter's reach of the light's pixels the same samples give the same estimate.
    far = np.arange(a.shape[0])[:, None] > np.nonzero(lit)[0].max() + 2
    np.testing.assert_allclose(b[far[:, 0]], a[far[:, 0]], rtol=1e-5, atol=1e-7)
    assert Path.from_properties({"hide_emitters": True}).hide_emitters
    with pytest.raises(ValueError, match="scene.xml:3.*hide_emitters"):
        Path.from_properties({"hide_emitters": 1}, where="scene.xml:3")


def test_distribution_selects_the_plugin_kind():
    where = "scene.xml:7"
    for cls, ggx in ((RoughConductor, GGXRoughConductor), (RoughDielectric, GGXRoughDielectric)):
        assert type(cls.from_properties({}, where=where)) is cls  # Mitsuba's default: Beckmann
        assert cls.from_properties({}, where=where).DISTRIBUTION == "beckmann"
        assert type(cls.from_properties({"distribution": "beckmann"}, where=where)) is cls
        assert type(cls.from_properties({"distribution": "ggx"}, where=where)) is ggx
        with pytest.raises(ValueError, match="scene.xml:7.*'phong'.*'beckmann', 'ggx'"):
            cls.from_properties({"distribution": "phong"}, where=where)


@pytest.mark.parametrize(
    "where,xml,match",
    [
        ("sampler", '<integer name="seed" value="-3"/>', r"seed must be in \[0, 2\^31\), got -3"),
        ("sampler", '<integer name="scramble_seed" value="2"/>', "'scramble_seed' = 2.*only 0"),
        # Crop windows that leave the film, refused as Mitsuba refuses them.
        ("film", '<integer name="crop_width" value="20"/>', r"crop window 20 x 16 at \(0, 0\)"),
        ("film", '<integer name="crop_offset_y" value="2"/>', r"16 x 16 at \(0, 2\).*does not"),
        (
            "film",
            '<integer name="crop_offset_x" value="-1"/><integer name="crop_width" value="4"/>',
            "offsets >= 0",
        ),
    ],
)
def test_unsupported_sensor_values_are_refused(tmp_path, where, xml, match):
    path = tmp_path / "scene.xml"
    path.write_text(_xml("", **{where: xml}))
    with pytest.raises(ValueError, match=rf"scene.xml:\d+: .*{match}"):
        load_mitsuba_xml(path)


def test_sampler_seed_and_sample_count_set_the_render(tmp_path):
    """The file's sampler `seed` and `sample_count` are the render's defaults (Mitsuba's
    meaning: the seed offsets the random sequence): `render(path)` without `spp`/`seed` is
    `render(path, spp=sample_count, seed=seed)`, the caller's arguments win, and a scene
    without `sample_count` needs `spp`."""
    from radiometria.render import render

    seeded, plain = tmp_path / "seeded.xml", tmp_path / "plain.xml"
    seeded.write_text(
        _xml("", sampler='<integer name="seed" value="3"/>').replace('"16"/>', '"2"/>', 1)
    )
    plain.write_text(_xml(""))
    desc = load_mitsuba_xml(seeded)
    assert (desc.seed, desc.spp, load_mitsuba_xml(plain).seed) == (3, 2, None)

    def y(scene, **kw):
        return np.asarray(render(scene, return_xyz=True, progress=False, **kw))[..., 1]

    default = y(seeded)
    np.testing.assert_array_equal(default, y(plain, spp=2, seed=3))  # the same render
    assert not np.array_equal(default, y(plain, spp=2, seed=0))  # the seed took effect
    assert not np.array_equal(default, y(seeded, seed=0))  # the caller's seed wins
    np.testing.assert_array_equal(y(seeded, seed=0), y(plain, spp=2))
    no_count = tmp_path / "no_count.xml"
    no_count.write_text(_xml("").replace('<integer name="sample_count" value="16"/>', ""))
    with pytest.raises(ValueError, match="`spp` is required.*sample_count"):
        render(no_count, progress=False)


def test_crop_window_and_principal_point_match_mitsuba(tmp_path):
    """A 10 x 7 crop window at (4, 6) of the 16 x 16 film, seen through a principal point
    offset (0.12, -0.08): the image is the window's size and agrees with Mitsuba 3 pixel by
    pixel (a diffuse ball: no heavy-tailed glints at 64 spp); the same window without the
    principal point offset (the image shifted by about two pixels) fails."""
    pytest.importorskip("mitsuba")
    from radiometria.montecarlo import pixel_z_test
    from radiometria.render import compile_scene, load_scene, render

    from ._mitsuba import mitsuba_moments

    crop = (
        '<integer name="crop_offset_x" value="4"/><integer name="crop_offset_y" value="6"/>'
        '<integer name="crop_width" value="10"/><integer name="crop_height" value="7"/>'
    )
    pp = (
        '<float name="principal_point_offset_x" value="0.12"/>'
        '<float name="principal_point_offset_y" value="-0.08"/>'
    )
    path, plain = tmp_path / "scene.xml", tmp_path / "plain.xml"
    ball = (
        '<shape type="sphere"><float name="radius" value="0.8"/>'
        '<bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.5, 0.3"/></bsdf></shape>'
    )
    path.write_text(_xml(ball, film=crop, sensor=pp))
    plain.write_text(_xml(ball, film=crop))
    desc = load_scene(path)
    assert desc.film.crop == (4, 6, 10, 7) and desc.camera.principal_point == (0.12, -0.08)
    with pytest.raises(ValueError, match=r"crop window 10 x 7 at \(4, 6\).*32 x 32"):
        compile_scene(desc, width=32, height=32)  # would move the window: refused
    mean, var = mitsuba_moments(path, 512, seed=1)
    assert mean.shape == (7, 10, 3)  # Mitsuba's image is the window too
    for scene, passes in ((path, True), (plain, False)):
        ours = render(scene, spp=64, return_xyz=True, progress=False)
        res = pixel_z_test(np.asarray(ours, np.float64), mean, var, 64, 512)
        assert res.passed is passes, (scene.name, res.message)


def test_default_sensor_values_are_accepted(tmp_path):
    """Values equal to Mitsuba's defaults change nothing; a pinhole's `focus_distance` is
    read and unused, as by Mitsuba 3's `perspective` (only `thinlens` focuses)."""
    path = tmp_path / "scene.xml"
    path.write_text(
        _xml(
            "",
            sampler='<integer name="seed" value="0"/>',
            film=f'<integer name="crop_width" value="{SIZE}"/><integer name="crop_offset_x" '
            'value="0"/>',
            sensor='<float name="focus_distance" value="3"/><float '
            'name="principal_point_offset_y" value="0"/>',
        )
    )
    desc = load_mitsuba_xml(path)
    assert (desc.film.width, desc.film.height) == (SIZE, SIZE)
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_spectral")
    # Mitsuba's perspective camera queries focus_distance (no "unused property" error).
    mi.load_dict({"type": "perspective", "focus_distance": 3.0})


def _reflectance(tmp_path, spectrum: str):
    path = tmp_path / "scene.xml"
    path.write_text(_xml(f'<shape type="sphere"><bsdf type="diffuse">{spectrum}</bsdf></shape>'))
    desc = load_mitsuba_xml(path)
    return [m for m in desc.materials if "reflectance" in m.params][-1].params["reflectance"]


def test_spectrum_files_and_tabulated_spectra(tmp_path):
    wl = np.array([400.0, 480.0, 550.0, 700.0])
    val = np.array([0.1, 0.5, 0.3, 0.9])
    lines = [
        "# measured reflectance",
        "",
        *(f"{a}  {b}   # ok" for a, b in zip(wl, val, strict=True)),
    ]
    (tmp_path / "r.spd").write_text("\n".join(lines) + "\n")
    x = np.linspace(380.0, 720.0, 35)
    ref = np.interp(x, wl, val, left=0.0, right=0.0)
    spec = _reflectance(tmp_path, '<spectrum name="reflectance" filename="r.spd"/>')
    np.testing.assert_allclose(np.asarray(spec(x)), ref, rtol=1e-12)
    irr = (
        '<spectrum name="reflectance" type="irregular"><string name="wavelengths" '
        'value="400, 480, 550, 700"/><string name="values" value="0.1, 0.5, 0.3, 0.9"/>'
        "</spectrum>"
    )
    np.testing.assert_allclose(np.asarray(_reflectance(tmp_path, irr)(x)), ref, rtol=1e-12)
    reg = (
        '<spectrum name="reflectance" type="regular"><float name="wavelength_min" value="400"/>'
        '<float name="wavelength_max" value="700"/><string name="values" value="0.2, 0.8, 0.4"/>'
        "</spectrum>"
    )
    ref = np.interp(x, [400.0, 550.0, 700.0], [0.2, 0.8, 0.4], left=0.0, right=0.0)
    np.testing.assert_allclose(np.asarray(_reflectance(tmp_path, reg)(x)), ref, rtol=1e-12)


@pytest.mark.parametrize(
    "content,match",
    [
        ("400 0.5\n500 oops\n", r"r.spd, line 2.*oops"),
        ("400 0.5 1\n", r"r.spd, line 1"),
        ("500 0.5\n400 0.5\n", "strictly increasing"),
        ("400 0.5\n500 -1\n", "reflectance"),
    ],
)
def test_bad_spectrum_files_name_file_and_line(tmp_path, content, match):
    (tmp_path / "r.spd").write_text(content)
    with pytest.raises(ValueError, match=rf"scene.xml:\d+: .*{match}"):
        _reflectance(tmp_path, '<spectrum name="reflectance" filename="r.spd"/>')


def test_missing_spectrum_file(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"scene.xml:\d+: .*nope.spd"):
        _reflectance(tmp_path, '<spectrum name="reflectance" filename="nope.spd"/>')


@pytest.mark.parametrize("kind", ["path", "direct", "volpath"])
def test_hide_emitters_in_the_file_reaches_the_integrator(tmp_path, kind):
    """`<boolean name="hide_emitters">` of the file's integrator is kept by the loader and
    given to the integrator plugin (also when `--integrator` picks another one that takes
    it)."""
    from radiometria.render._scenes._compile import scene_integrator

    xml = _xml("").replace(
        '<integrator type="path"><integer name="max_depth" value="4"/>',
        f'<integrator type="{kind}"><boolean name="hide_emitters" value="true"/>',
    )
    path = tmp_path / "scene.xml"
    path.write_text(xml)
    description = load_mitsuba_xml(path)
    assert scene_integrator(description).hide_emitters is True
    assert scene_integrator(description, name="path").hide_emitters is True


def _checker(name: str, c0: float, c1: float) -> str:
    return (
        f'<texture type="checkerboard" name="{name}"><float name="color0" value="{c0}"/>'
        f'<float name="color1" value="{c1}"/><transform name="to_uv"><scale x="2" y="1"/>'
        "</transform></texture>"
    )


def _ior_balls(eta: tuple[float, float], k: tuple[float, float]) -> str:
    """Two rough metal balls under a grey sky (whose reflection shows their reflectance)."""
    return (
        '<emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>'
        '<shape type="sphere"><float name="radius" value="0.5"/><point name="center" x="-0.6" '
        'y="-0.2" z="0"/><bsdf type="roughconductor"><float name="alpha" value="0.25"/>'
        f"{_checker('eta', *eta)}{_checker('k', *k)}</bsdf></shape>"
        '<shape type="sphere"><float name="radius" value="0.5"/><point name="center" x="0.6" '
        'y="-0.2" z="0"/><bsdf type="roughconductor"><string name="distribution" value="ggx"/>'
        '<float name="alpha" value="0.4"/><spectrum name="eta" value="0.3"/>'
        f"{_checker('k', *k)}</bsdf></shape>"
    )


@pytest.mark.slow
def test_textured_conductor_index_matches_mitsuba(tmp_path):
    """`eta` and `k` of rough conductors (Beckmann and GGX) as checkerboards (Mitsuba's
    conductors read them as textures): agrees with Mitsuba 3 pixel by pixel; the squares of
    `eta` swapped fail. (A smooth conductor ball would cast a caustic on the floor, whose
    heavy-tailed noise no 64-spp z-test judges; the smooth `conductor` reads its index
    through the same code, `test_smooth_conductor_reads_a_textured_index`.)"""
    pytest.importorskip("mitsuba")
    from ._mitsuba import z_test_against_mitsuba

    path, swapped = tmp_path / "scene.xml", tmp_path / "swapped.xml"
    path.write_text(_xml(_ior_balls((0.2, 1.5), (3.0, 0.5))))
    swapped.write_text(_xml(_ior_balls((1.5, 0.2), (3.0, 0.5))))
    res = z_test_against_mitsuba(path, spp=256, ref_spp=1024)
    assert res.passed, res.message
    res = z_test_against_mitsuba(path, spp=256, ref_spp=1024, ours_path=swapped)
    assert not res.passed, res.message


def test_smooth_conductor_reads_a_textured_index():
    """A smooth conductor's `k` checkerboard is looked up at the hit's uv: its Fresnel
    reflectance at normal incidence, ((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2), follows the
    squares."""
    import jax.numpy as jnp

    from radiometria.render._materials._conductor import Conductor
    from radiometria.render._textures import TextureSpec

    spec = TextureSpec("checkerboard", colors=(3.0, 0.5))
    m = Conductor.from_properties({"eta": 0.3, "k": spec}, where="test")
    wl = jnp.full((2, 4), 550.0, jnp.float32)
    uv = jnp.asarray([[0.25, 0.25], [0.75, 0.25]], jnp.float32)  # color0, then color1
    bxdf = m.bxdf(jnp.zeros(2, jnp.int32), wl, uv)
    w = jnp.asarray([[0.0, 0.0, 1.0]] * 2, jnp.float32)
    r = np.asarray(bxdf.sample_f(w, jnp.zeros(2), jnp.zeros((2, 2))).f)
    expected = [((0.3 - 1) ** 2 + k * k) / ((0.3 + 1) ** 2 + k * k) for k in (3.0, 0.5)]
    np.testing.assert_allclose(r[:, 0], expected, rtol=1e-4)


def _sheet(kind: str, t0: float, t1: float) -> str:
    """A sheet in front of the camera whose transmittance is a checkerboard, over the lit
    floor (the camera sees the floor through it). It reflects nothing: its reflection would
    show the floor between it and the camera, lit only through the sheet, whose
    heavy-tailed noise no 64-spp z-test judges."""
    return (
        '<shape type="rectangle"><transform name="to_world"><scale x="1.6" y="1.2"/>'
        f'<translate y="0.2" z="2"/></transform><bsdf type="{kind}">'
        '<float name="specular_reflectance" value="0"/>'
        f"{_checker('specular_transmittance', t0, t1)}</bsdf></shape>"
    )


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["thindielectric", "dielectric"])
def test_textured_dielectric_transmittance_matches_mitsuba(tmp_path, kind):
    """`specular_transmittance` of a thin and a smooth dielectric sheet as a checkerboard
    (Mitsuba's dielectrics read it as a texture): agrees with Mitsuba 3 pixel by pixel; the
    squares swapped fail."""
    pytest.importorskip("mitsuba")
    from ._mitsuba import z_test_against_mitsuba

    path, swapped = tmp_path / "scene.xml", tmp_path / "swapped.xml"
    path.write_text(_xml(_sheet(kind, 0.2, 1.0)))
    swapped.write_text(_xml(_sheet(kind, 1.0, 0.2)))
    res = z_test_against_mitsuba(path, spp=64, ref_spp=512)
    assert res.passed, res.message
    res = z_test_against_mitsuba(path, spp=64, ref_spp=512, ours_path=swapped)
    assert not res.passed, res.message
