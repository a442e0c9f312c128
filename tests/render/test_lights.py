r"""Point, spot, directional and constant lights and the light set, against closed forms.

Each scene is a small Mitsuba XML file: a camera straight above a large grey diffuse plane
(reflectance 0.5, a flat spectrum) lit by one light. The box filter makes a pixel the mean of
the radiance over its square, whose footprint on the plane (parallel to the film) is a square
too, so the expected pixel is a NumPy quadrature of the closed-form radiance
$\rho/\pi\, E(x, y)$ over that square. The scenes are symmetric under the film's flips, so
the camera's orientation conventions do not enter the reference. White RGB light emits D65
with Y = 1, which renders as linear sRGB (1, 1, 1) (thesis 2.2.3).
"""

import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.render as rr
from radiometria.montecarlo import pixel_z_test
from radiometria.render import LinearRGB, SceneError
from radiometria.render._lights import (
    ConstantLight,
    DirectionalLight,
    LightSet,
    PointLight,
    spot_falloff,
)

from ._mitsuba import perspective_xml

pytestmark = pytest.mark.slow

SIZE = 16
HEIGHT = 3.0  # camera height above the plane [scene units]
FOV = 60.0  # [deg]
RHO = 0.5


def _scene(light: str, *, integrator: str = "direct", plane: bool = True, extra: str = "") -> str:
    shape = (
        '<shape type="rectangle"><transform name="to_world"><scale value="10"/></transform>'
        f'<bsdf type="diffuse"><rgb name="reflectance" value="{RHO}"/></bsdf></shape>'
        if plane
        else ""
    )
    return f"""<scene version="3.0.0">
  <integrator type="{integrator}"/>
  {perspective_xml(f"0, 0, {HEIGHT}", FOV, SIZE, rfilter="box")}
  {shape}
  {light}
  {extra}
</scene>
"""


def _write(tmp_path, text, name="scene.xml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _pixel_means(radiance, n_sub: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """Mean and variance of `radiance(x, y)` over each pixel's footprint on the plane z = 0
    (midpoint rule on n_sub x n_sub points per pixel), each `(SIZE, SIZE)`."""
    half = HEIGHT * np.tan(np.radians(FOV) / 2)
    edges = np.linspace(-half, half, SIZE + 1)
    t = (np.arange(n_sub) + 0.5) / n_sub
    pts = (edges[:-1, None] + np.diff(edges)[:, None] * t[None, :]).ravel()
    x, y = np.meshgrid(pts, pts, indexing="xy")
    values = radiance(x, y).reshape(SIZE, n_sub, SIZE, n_sub)
    return values.mean(axis=(1, 3)), values.var(axis=(1, 3))


def _render(path, spp, seed=0):
    """Our render as XYZ `(H, W, 3)` (Y is in the unit of the scene's radiance: white light
    of radiance 1 has Y = 1)."""
    return np.asarray(
        rr.render(path, spp=spp, seed=seed, progress=False, return_xyz=True), np.float64
    )


# Relative standard deviation of one sample's luminance from hero-wavelength sampling of a
# white (D65) light on a grey surface, measured: 1.1 % at 64 spp, so 9 % per sample.
_SPECTRAL_SD = 0.09


def _check_image(xyz, expected, spp, what, mean_rtol=5e-3, sample_sd=_SPECTRAL_SD):
    """The luminance Y of every pixel within 5.5 standard deviations of the closed form (the
    variance of one sample: the radiance's variance over the pixel, where the box filter
    places the sample uniformly, plus the spectral noise; false failure rate below 1e-5 for
    the image), the image's mean Y within `mean_rtol`, and its mean colour the light's white
    (D65: x = 0.3127, y = 0.3290). `expected` is `_pixel_means`' (mean, variance)."""
    mean, var = expected
    y = xyz[..., 1]
    sd = np.sqrt((var + (sample_sd * mean) ** 2) / spp)
    err = np.abs(y - mean)
    bound = 5.5 * sd + 1e-4
    worst = np.unravel_index(np.argmax(err / bound), err.shape)
    assert np.all(err <= bound), (
        f"{what}: pixel {worst} has Y = {y[worst]:.5f}, closed form {mean[worst]:.5f} "
        f"+- {sd[worst]:.5f}"
    )
    assert abs(y.mean() / mean.mean() - 1) < mean_rtol, (what, y.mean(), mean.mean())
    total = xyz.reshape(-1, 3).sum(axis=0)
    np.testing.assert_allclose(total[:2] / total.sum(), [0.3127, 0.3290], atol=3e-3)


def _constant(value):
    return np.full((SIZE, SIZE), float(value)), np.zeros((SIZE, SIZE))


def test_point_light_closed_form(tmp_path):
    # A point of intensity I at height h: E = I h / (x^2 + y^2 + h^2)^(3/2) on the plane.
    intensity, h = 4.0, 1.0
    light = (
        f'<emitter type="point"><point name="position" x="0" y="0" z="{h}"/>'
        f'<rgb name="intensity" value="{intensity}"/></emitter>'
    )
    image = _render(_write(tmp_path, _scene(light)), spp=64)
    expected = _pixel_means(
        lambda x, y: RHO / np.pi * intensity * h / (x * x + y * y + h * h) ** 1.5
    )
    _check_image(image, expected, 64, "point light")


def test_spot_light_closed_form(tmp_path):
    # A spot pointing down: E = I f(theta) cos(theta) / r^2 with Mitsuba's falloff f, written
    # here from its definition (1 inside the beam, linear in the angle to 0 at the cutoff).
    intensity, h, cutoff, beam = 6.0, 1.0, 40.0, 25.0
    light = (
        '<emitter type="spot"><transform name="to_world">'
        f'<lookat origin="0, 0, {h}" target="0, 0, 0" up="0, 1, 0"/></transform>'
        f'<rgb name="intensity" value="{intensity}"/>'
        f'<float name="cutoff_angle" value="{cutoff}"/><float name="beam_width" value="{beam}"/>'
        "</emitter>"
    )

    def radiance(x, y):
        r2 = x * x + y * y + h * h
        theta = np.arccos(h / np.sqrt(r2))
        c, b = np.radians(cutoff), np.radians(beam)
        f = np.where(theta <= b, 1.0, np.clip((c - theta) / (c - b), 0.0, 1.0))
        return RHO / np.pi * intensity * f * h / r2**1.5

    image = _render(_write(tmp_path, _scene(light)), spp=64)
    _check_image(image, _pixel_means(radiance, n_sub=48), 64, "spot light", mean_rtol=0.01)


def test_spot_falloff_matches_definition():
    theta = np.radians(np.linspace(0.0, 60.0, 601))
    c, b = np.radians(30.0), np.radians(20.0)
    expected = np.where(theta <= b, 1.0, np.where(theta < c, (c - theta) / (c - b), 0.0))
    np.testing.assert_allclose(spot_falloff(np.cos(theta), c, b), expected, atol=1e-12)


def test_directional_light_closed_form(tmp_path):
    # Irradiance E from 30 degrees off the normal: every point gets E cos(30 deg).
    e = 2.0
    d = np.array([np.sin(np.radians(30.0)), 0.0, -np.cos(np.radians(30.0))])
    light = (
        '<emitter type="directional">'
        f'<vector name="direction" x="{d[0]}" y="{d[1]}" z="{d[2]}"/>'
        f'<rgb name="irradiance" value="{e}"/></emitter>'
    )
    image = _render(_write(tmp_path, _scene(light)), spp=16)
    expected = _constant(RHO / np.pi * e * np.cos(np.radians(30.0)))
    _check_image(image, expected, 16, "directional light")


def test_constant_environment_seen_directly(tmp_path):
    # No geometry in view: every camera ray escapes and sees the constant radiance.
    light = '<emitter type="constant"><rgb name="radiance" value="0.7"/></emitter>'
    text = _scene(light, plane=False, extra=_far_triangle())
    image = _render(_write(tmp_path, text), spp=64)
    _check_image(image, _constant(0.7), 64, "constant seen directly")


def _far_triangle() -> str:
    """A tiny triangle behind the camera (a scene needs a shape)."""
    return (
        '<shape type="rectangle"><transform name="to_world"><scale value="0.01"/>'
        '<translate z="50"/></transform></shape>'
    )


def test_constant_environment_furnace(tmp_path):
    # A white (albedo 1) diffuse plane under a constant sky of radiance L reflects exactly L
    # (the sky covers its hemisphere): the MIS of light and BSDF samples of escaped rays.
    light = '<emitter type="constant"><rgb name="radiance" value="1"/></emitter>'
    text = _scene(light).replace(f'value="{RHO}"', 'value="1"')
    image = _render(_write(tmp_path, text), spp=64)
    # One sample's Y has a relative standard deviation of 0.25 here (measured: light and BSDF
    # samples under MIS and the spectral noise); 0.35 bounds it.
    _check_image(image, _constant(1.0), 64, "constant furnace", sample_sd=0.35, mean_rtol=0.01)


def test_path_hide_emitters_under_a_constant_sky(tmp_path):
    # Mitsuba's `hide_emitters`: the sky seen directly by camera rays is black, and the sky
    # still lights the white plane, which therefore reflects exactly L = 1 (the furnace
    # above, through `path` and escapes after the first segment only).
    light = '<emitter type="constant"><rgb name="radiance" value="1"/></emitter>'
    hidden = '<integrator type="path"><boolean name="hide_emitters" value="true"/></integrator>'

    def scene(**kw):
        return _scene(light, integrator="path", **kw).replace('<integrator type="path"/>', hidden)

    sky = _render(_write(tmp_path, scene(plane=False, extra=_far_triangle()), "sky.xml"), 4)
    assert np.all(sky == 0), np.abs(sky).max()
    text = scene().replace(f'value="{RHO}"', 'value="1"')
    image = _render(_write(tmp_path, text), spp=64)
    _check_image(image, _constant(1.0), 64, "hidden sky furnace", sample_sd=0.35, mean_rtol=0.01)


_FOG = (
    '<medium type="homogeneous" id="fog"><{kind} name="sigma_t" value="{sigma}"/>'
    '<float name="albedo" value="1"/><phase type="hg"><float name="g" value="0.6"/></phase>'
    "</medium>"
)
_FOG_SPHERE = '<shape type="sphere"><bsdf type="null"/><ref name="interior" id="fog"/></shape>'
_SKY = '<emitter type="constant"><rgb name="radiance" value="1"/></emitter>'


@pytest.mark.parametrize(
    "integrator, sigma, sample_sd",
    [("volpath", "2", 0.35), ("volpathmis", "1, 2, 4", 0.4)],
)
def test_volumetric_furnace_under_a_constant_sky(tmp_path, integrator, sigma, sample_sd):
    # A purely scattering (albedo 1) forward-scattering fog in a null sphere under a constant
    # sky of radiance 1: every ray sees exactly 1, whether it misses the sphere or leaves it
    # after any number of scatterings. Light reaches the medium both by next-event
    # estimation through the null boundary and by phase samples that escape; the escapes are
    # looked up once per path after the last segment, with the throughput (here with the
    # spectral-MIS weights of a chromatic fog's free flights), density and direction of the
    # segment they left along. One sample's Y has a relative standard deviation of 0.23
    # (grey fog, volpath) and 0.26 (chromatic, volpathmis), measured over 6 seeds; the
    # pixels' extremes lie within 6.1 of those, so the bounds are 0.35 and 0.4. (volpath's
    # per-segment spectral MIS on the chromatic fog has rare fireflies: 35 standard
    # deviations once in 6 images, unbiased but too heavy-tailed for a per-pixel bound.)
    fog = _FOG.format(kind="rgb" if "," in sigma else "float", sigma=sigma)
    integ = f'<integrator type="{integrator}"><integer name="max_depth" value="64"/></integrator>'
    text = _scene(_SKY, integrator=integrator, plane=False, extra=fog + _FOG_SPHERE)
    text = text.replace(f'<integrator type="{integrator}"/>', integ)
    image = _render(_write(tmp_path, text), spp=64)
    _check_image(image, _constant(1.0), 64, f"{integrator} furnace", sample_sd=sample_sd,
                 mean_rtol=0.01)  # fmt: skip


def test_volpath_hide_emitters_inside_a_fog_under_a_constant_sky(tmp_path):
    # The camera at the centre of a null sphere of radius R = 1 filled with a grey purely
    # scattering fog (sigma_t s) under a constant sky of radiance 1, with `hide_emitters`:
    # the sky seen through the fog along a camera ray (transmittance exp(-s R)) is hidden,
    # and the radiance in-scattered along the ray is the rest, 1 - exp(-s R) exactly (the
    # radiance field inside the sphere is 1 everywhere, in every direction, for any phase
    # function). Fails if escapes of the camera segment are shown, or those of later
    # segments hidden.
    sigma = 0.8
    integ = (
        '<integrator type="volpath"><integer name="max_depth" value="64"/>'
        '<boolean name="hide_emitters" value="true"/></integrator>'
    )
    sensor = perspective_xml("0, 0, 0.001", FOV, SIZE, rfilter="box").replace(
        "</sensor>", '<ref id="fog"/></sensor>'
    )
    text = f"""<scene version="3.0.0">{integ}{sensor}{_FOG.format(kind="float", sigma=sigma)}
      {_FOG_SPHERE}{_SKY}</scene>"""
    image = _render(_write(tmp_path, text), spp=64)
    # Measured: one sample's Y has a relative standard deviation of 1.07 (6 seeds), so the
    # image mean's is 0.8 %: the bounds are 1.3 per sample and 3.5 % for the mean.
    _check_image(image, _constant(1.0 - np.exp(-sigma)), 64, "hidden sky through fog",
                 sample_sd=1.3, mean_rtol=0.035)  # fmt: skip


def test_light_set_picks_by_power():
    # Two point lights (intensities 1 and 3) and a directional one: probabilities are the
    # powers 4 pi I and pi r^2 E over their sum.
    point = PointLight.from_properties(
        [{"intensity": 1.0, "position": np.zeros(3)}, {"intensity": 3.0, "position": np.ones(3)}],
        where=["a", "b"],
    )
    sun = DirectionalLight.from_properties(
        [{"irradiance": 2.0, "direction": np.array([0.0, 0.0, -1.0])}], where=["c"]
    )
    radius = 1.5
    lights = LightSet.from_lights([point, sun], scene_radius=radius)
    power = np.array([4 * np.pi * 4.0, np.pi * radius**2 * 2.0])
    np.testing.assert_allclose(np.asarray(lights.prob), power / power.sum(), rtol=1e-6)
    np.testing.assert_allclose(
        np.diff(np.concatenate([[0.0], np.asarray(point.cdf)])), [0.25, 0.75], rtol=1e-6
    )


def test_light_set_sampling_frequencies():
    # Sampled lights occur with their probabilities (chi-square against the power split).
    from scipy import stats

    point = PointLight.from_properties(
        [{"intensity": 1.0, "position": np.array([0.0, 0.0, 1.0])},
         {"intensity": 3.0, "position": np.array([0.0, 0.0, 2.0])}],
        where=["a", "b"],
    )  # fmt: skip
    sky = ConstantLight.from_properties([{"radiance": 0.05}], where=["c"])
    lights = LightSet.from_lights([point, sky], scene_radius=1.0)
    n = 20000
    rng = np.random.default_rng(0)
    u = jnp.asarray(rng.random(n), jnp.float32)
    u2 = jnp.asarray(rng.random((n, 2)), jnp.float32)
    p = jnp.zeros((n, 3), jnp.float32)
    wl = jnp.full((n, 4), 550.0, jnp.float32)
    s = lights.sample_li(p, u, u2, wl)
    dist = np.asarray(s.dist)
    counts = np.array([np.sum(np.isclose(dist, 1.0)), np.sum(np.isclose(dist, 2.0)),
                       np.sum(np.isinf(dist))])  # fmt: skip
    prob = np.asarray(lights.prob, np.float64)
    expected = np.array([prob[0] * 0.25, prob[0] * 0.75, prob[1]])
    expected = n * expected / expected.sum()
    assert counts.sum() == n
    assert stats.chisquare(counts, expected).pvalue > 1e-6
    delta = np.asarray(s.delta)
    assert np.all(delta == ~np.isinf(dist))


def test_light_errors(tmp_path):
    cases = {
        "negative": '<emitter type="point"><rgb name="intensity" value="-1"/></emitter>',
        "beam": '<emitter type="spot"><float name="cutoff_angle" value="10"/>'
        '<float name="beam_width" value="20"/></emitter>',
        "both": '<emitter type="point"><point name="position" x="0" y="0" z="1"/>'
        '<transform name="to_world"><translate x="1"/></transform></emitter>',
        "unknown": '<emitter type="point"><float name="radius" value="1"/></emitter>',
        "inshape": None,
    }
    for name, light in cases.items():
        if light is None:
            text = _scene("").replace("</bsdf></shape>", '</bsdf><emitter type="point"/></shape>')
        else:
            text = _scene(light)
        path = _write(tmp_path, text, f"{name}.xml")
        with pytest.raises(SceneError, match=rf"{name}\.xml:\d+"):
            rr.load_scene(path)
    two = _scene(
        '<emitter type="constant"/>', extra='<emitter type="constant"><float name="radiance" '
        'value="2"/></emitter>'
    )  # fmt: skip
    with pytest.raises(SceneError, match="one environment emitter"):
        rr.compile_scene(rr.load_scene(_write(tmp_path, two, "two.xml")))


def test_light_set_matches_mitsuba(tmp_path):
    # Point, spot and area lights in one scene: our light set picks one by power, Mitsuba
    # uniformly; the expectations agree (path tracing with MIS). Picking by power makes the
    # spot a rarer pick than Mitsuba's 1/3, so our render takes 256 spp against the
    # reference's per-sample variance (128 spp fails 2 of 768 channels by noise; measured).
    # (Lights at infinity count
    # the power falling on the scene, which makes the others rare picks and their pixels
    # noisier than Mitsuba's; they are checked one at a time above and in test_envmap.)
    pytest.importorskip("mitsuba")
    from ._mitsuba import z_test_against_mitsuba

    lights = (
        '<emitter type="point"><point name="position" x="-0.8" y="0.5" z="1"/>'
        '<rgb name="intensity" value="0.5, 0.4, 0.3"/></emitter>'
        '<emitter type="spot"><transform name="to_world">'
        '<lookat origin="0.6, -0.4, 1.2" target="0.3, 0, 0" up="0, 1, 0"/></transform>'
        '<rgb name="intensity" value="3, 3, 5"/><float name="cutoff_angle" value="30"/></emitter>'
    )
    card = (
        '<shape type="rectangle"><transform name="to_world"><scale value="0.3"/>'
        '<rotate x="1" angle="-60"/><translate x="0.5" y="0.8" z="0.6"/></transform>'
        '<emitter type="area"><rgb name="radiance" value="2, 2, 1"/></emitter></shape>'
    )
    text = _scene(lights, integrator="path", extra=card)
    result = z_test_against_mitsuba(_write(tmp_path, text), spp=256, ref_spp=1024)
    assert result.passed, result.message


def test_float_emission_is_a_grey_illuminant_as_in_mitsuba(tmp_path):
    """Mitsuba 3 reads an emitter's `<float>` intensity or radiance as `<rgb value="v, v, v">`
    (a D65-shaped grey), and a `<spectrum value="v">` as flat: checked on Mitsuba's point
    light at three wavelengths; our loader turns the float into that grey and keeps the
    spectrum flat."""
    mi = pytest.importorskip("mitsuba")
    dr = pytest.importorskip("drjit")
    mi.set_variant("scalar_spectral")

    def weights(value):
        e = mi.load_dict({"type": "point", "position": [0, 0, 1], "intensity": value})
        it = dr.zeros(mi.Interaction3f)
        out = []
        for wl in (400.0, 550.0, 700.0):
            it.wavelengths = [wl] * 4
            out.append(e.sample_direction(it, [0.5, 0.5])[1][0])
        return np.array(out)

    grey = weights({"type": "rgb", "value": [5.0, 5.0, 5.0]})
    np.testing.assert_allclose(weights(5.0), grey, rtol=1e-6)
    np.testing.assert_allclose(weights({"type": "uniform", "value": 5.0}), 5.0, rtol=1e-6)
    assert np.ptp(grey) > 1.0  # the D65 shape: not flat

    light = (
        '<emitter type="point"><point name="position" value="0, 0, 1"/>'
        '<float name="intensity" value="5"/></emitter>'
        '<emitter type="spot"><spectrum name="intensity" value="5"/></emitter>'
    )
    area = (
        '<shape type="rectangle"><emitter type="area"><float name="radiance" value="2"/>'
        "</emitter></shape>"
    )
    desc = rr.load_scene(_write(tmp_path, _scene(light, extra=area)))
    point, spot = desc.lights
    assert isinstance(point.params["intensity"], LinearRGB)
    np.testing.assert_array_equal(point.params["intensity"].rgb, [5.0, 5.0, 5.0])
    assert spot.params["intensity"] == 5.0  # flat
    (emitter,) = desc.emitters
    assert isinstance(emitter.radiance, LinearRGB)
    np.testing.assert_array_equal(emitter.radiance.rgb, [2.0, 2.0, 2.0])


# Light tracing (`ptracer`, issue 14) from lights at infinity: emitted rays start on a disk of
# the scene's bounding-sphere radius R across their direction. A plane of half-size S has
# R = S sqrt(2) (half its bounding box's diagonal, as RenderScene computes it).
_PT_HALF = 1.8  # the plane's half-size: just covers the view (half-width 3 tan 30 = 1.73)


def _ptracer_check(image, expected, spp, hits_per_pixel, what):
    """`_check_image` with the per-sample spread of light tracing: a pixel's estimate is a
    sum over the light paths that land in its footprint (Poisson with mean `hits_per_pixel`,
    each of nearly the same value), so its relative variance is ~1/hits, plus the spectral
    noise; written as the `sample_sd` of `spp` samples (1.5x margin on the variance for the
    camera importance's spread over a pixel)."""
    sample_sd = np.sqrt(1.5 * spp / hits_per_pixel + _SPECTRAL_SD**2)
    mean_rtol = 5.0 * sample_sd / np.sqrt(spp * SIZE * SIZE)
    _check_image(image, expected, spp, what, mean_rtol=mean_rtol, sample_sd=sample_sd)


def _pt_scene(light):
    text = _scene(light, integrator="ptracer")
    return text.replace('<scale value="10"/>', f'<scale value="{_PT_HALF}"/>')


def _pixel_area() -> float:
    return (2.0 * HEIGHT * np.tan(np.radians(FOV) / 2) / SIZE) ** 2


def test_ptracer_directional_light_closed_form(tmp_path):
    # L = rho/pi E cos(30 deg) everywhere; a light path lands in a pixel's footprint with
    # probability A_pix cos(30 deg) / (pi R^2) (uniform origins on the disk).
    e, spp = 2.0, 64
    d = np.array([np.sin(np.radians(30.0)), 0.0, -np.cos(np.radians(30.0))])
    light = (
        '<emitter type="directional">'
        f'<vector name="direction" x="{d[0]}" y="{d[1]}" z="{d[2]}"/>'
        f'<rgb name="irradiance" value="{e}"/></emitter>'
    )
    image = _render(_write(tmp_path, _pt_scene(light)), spp=spp)
    r2 = 2.0 * _PT_HALF**2
    hits = spp * SIZE * SIZE * _pixel_area() * np.cos(np.radians(30.0)) / (np.pi * r2)
    expected = _constant(RHO / np.pi * e * np.cos(np.radians(30.0)))
    _ptracer_check(image, expected, spp, hits, "ptracer directional")


def test_ptracer_constant_environment_closed_form(tmp_path):
    # The plane sees the whole upper hemisphere of sky and nothing else: L = rho L_env. Rays
    # from the disk with uniform directions reach a footprint's front with probability
    # A_pix E[max(cos, 0)] / (pi R^2) = A_pix / (4 pi R^2).
    l_env, spp = 1.5, 256
    light = f'<emitter type="constant"><rgb name="radiance" value="{l_env}"/></emitter>'
    image = _render(_write(tmp_path, _pt_scene(light)), spp=spp)
    r2 = 2.0 * _PT_HALF**2
    hits = spp * SIZE * SIZE * _pixel_area() / (4.0 * np.pi * r2)
    _ptracer_check(image, _constant(RHO * l_env), spp, hits, "ptracer constant")


# Bidirectional path tracing (`bdpt`) and MLT over it (`pssmlt`) under the same lights: every
# strategy that can reach a light at infinity (camera rays that escape, next-event estimation
# of its direction, light paths from the disk) with its MIS weight.
_L_ENV, _E_DIR = 1.5, 2.0
_DIR = np.array([np.sin(np.radians(30.0)), 0.0, -np.cos(np.radians(30.0))])
_AT_INFINITY = {
    "constant": (
        f'<emitter type="constant"><rgb name="radiance" value="{_L_ENV}"/></emitter>',
        RHO * _L_ENV,
    ),
    "directional": (
        '<emitter type="directional">'
        f'<vector name="direction" x="{_DIR[0]}" y="{_DIR[1]}" z="{_DIR[2]}"/>'
        f'<rgb name="irradiance" value="{_E_DIR}"/></emitter>',
        RHO / np.pi * _E_DIR * np.cos(np.radians(30.0)),
    ),
}


def _bidirectional_scene(tmp_path, kind, integrator):
    light, expected = _AT_INFINITY[kind]
    text = _pt_scene(light).replace(
        '<integrator type="ptracer"/>',
        f'<integrator type="{integrator}"><integer name="max_depth" value="2"/></integrator>',
    )
    return _write(tmp_path, text), expected


@pytest.mark.parametrize("kind", ["constant", "directional"])
def test_bdpt_lights_at_infinity_closed_form(tmp_path, kind):
    # The closed forms above from bdpt: each pixel of the mean of 16 independent renders
    # passes the z-test against the closed form with its variance measured across the renders
    # (16, not fewer: light paths land in a pixel a Poisson number of times, so its estimates
    # are skewed and a variance from a handful of renders is unreliable), the image's mean is
    # within 1 %, and a closed form 10 % brighter fails the same z-test.
    path, value = _bidirectional_scene(tmp_path, kind, "bdpt")
    _seeds_z_test(path, np.full((SIZE, SIZE), value))


def _seeds_z_test(path, expected, spp=8, seeds=range(16)):
    """Each pixel's Y, the mean of independent renders, against `expected` `(SIZE, SIZE)` by
    the z-test with the variance measured across the renders; the image's mean within 1 %;
    a reference 10 % brighter fails the same z-test."""
    images = np.stack([_render(path, spp, seed=s)[..., 1] for s in seeds])
    mean, var = images.mean(0), images.var(0, ddof=1) / len(seeds)
    total = spp * len(seeds)

    def z_test(reference):
        return pixel_z_test(mean, reference, var * total, total, None, variance_floor=1e-10,
                            required_fraction=0.99)  # fmt: skip

    result = z_test(expected)
    assert result.passed, result.message
    assert abs(mean.mean() / expected.mean() - 1) < 0.01, (mean.mean(), expected.mean())
    assert not z_test(1.1 * expected).passed


def test_pssmlt_directional_light_closed_form(tmp_path):
    # MLT's image mean is its bootstrap's estimate of the whole image: within 2 % of the
    # closed form for each of 8 renders; its 4 x 4 pixel blocks (mean of the renders) pass the
    # z-test against the closed form with the variance measured across the renders (one of
    # the 16 may fail: a chain's correlated samples make the variance of 8 renders rough).
    path, value = _bidirectional_scene(tmp_path, "directional", "pssmlt")
    images = np.stack([_render(path, 64, seed=s)[..., 1] for s in range(8)])
    np.testing.assert_allclose(images.mean(axis=(1, 2)), value, rtol=0.02)
    blocks = images.reshape(len(images), 4, SIZE // 4, 4, SIZE // 4).mean(axis=(2, 4))
    result = pixel_z_test(
        blocks.mean(0), np.full((4, 4), value), blocks.var(0, ddof=1) / len(images), 1, None,
        variance_floor=1e-10, required_fraction=0.9,
    )  # fmt: skip
    assert result.passed, result.message


# Projectors (Mitsuba's `projector`): a constant image cast squarely onto the plane from height
# h has irradiance pi s E / h^2 on its footprint (|x|, |y| < h tan(fov/2)) and none outside.
_PROJ_H, _PROJ_FOV, _PROJ_SCALE = 2.0, 40.0, 1.5


def _projector_xml(extra: str = "", fov: float = _PROJ_FOV) -> str:
    return (
        f'<emitter type="projector"><float name="fov" value="{fov}"/>'
        f'<float name="scale" value="{_PROJ_SCALE}"/>'
        '<transform name="to_world"><lookat origin="0, 0, '
        f'{_PROJ_H}" target="0, 0, 0" up="0, 1, 0"/></transform>{extra}</emitter>'
    )


@pytest.mark.parametrize("integrator", ["direct", "ptracer", "bdpt"])
def test_projector_closed_form(tmp_path, integrator):
    # Next-event estimation (direct), light paths from the image (ptracer) and both with MIS
    # (bdpt) against L = rho s E / h^2 on the footprint (E = 1: white light of Y = 1), 0
    # outside.
    half = _PROJ_H * np.tan(np.radians(_PROJ_FOV) / 2)
    text = _scene(_projector_xml(), integrator=integrator)
    if integrator != "direct":  # one bounce off the plane is all there is
        text = text.replace(
            f'<integrator type="{integrator}"/>',
            f'<integrator type="{integrator}"><integer name="max_depth" value="2"/></integrator>',
        )
    path = _write(tmp_path, text)
    mean, _ = _pixel_means(
        lambda x, y: np.where(
            (np.abs(x) < half) & (np.abs(y) < half), RHO * _PROJ_SCALE / _PROJ_H**2, 0.0
        ),
        n_sub=96,  # the footprint's edges cut pixels: a fine quadrature of their coverage
    )
    _seeds_z_test(path, mean)


def test_projector_bad_parameters(tmp_path):
    for extra, match in (
        ('<float name="fov" value="190"/>', r"fov.*\(0, 180\).*190"),
        ('<float name="scale" value="-1"/>', r"scale.*>= 0.*-1"),
        ('<string name="fov_axis" value="z"/>', r"fov_axis.*'z'"),
    ):
        text = _scene(
            '<emitter type="projector"><transform name="to_world"><translate z="2"/>'
            f"</transform>{extra}</emitter>"
        )
        with pytest.raises(SceneError, match=rf"scene\.xml:\d+: .*projector.*{match}"):
            rr.load_scene(_write(tmp_path, text))
    text = _scene(
        '<emitter type="projector"><transform name="to_world"><scale value="2"/>'
        "</transform></emitter>"
    )
    with pytest.raises(SceneError, match=r"rotation and a translation"):
        rr.load_scene(_write(tmp_path, text))


SPHERE_LIGHT = """<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="0.5"/>
    <transform name="to_world"><lookat origin="1.5, 0.5, 3" target="1.5, -1, 0" up="0, 1, 0"/>
    </transform>
    <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/>
      <rfilter type="box"/></film></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="0.5"/>
    <rotate x="1" angle="-90"/><translate x="1.5" y="-1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6"/></bsdf></shape>
  <shape type="sphere"><point name="center" value="0, 0.2, 0"/><float name="radius" value="0.6"/>
    <emitter type="area"><rgb name="radiance" value="4"/></emitter></shape>
</scene>
"""


@pytest.mark.parametrize(
    "integrator",
    [rr.Direct(emitter_samples=1, bsdf_samples=0), rr.Path(max_depth=2), rr.VolPath(max_depth=2)],
    ids=["direct-light-samples-only", "path", "volpath"],
)
def test_sphere_light_irradiance_closed_form(tmp_path, integrator):
    """A floor patch lit by a sphere light of radiance L, radius R, centre at distance D and
    zenith angle theta: E = pi L (R / D)^2 cos(theta) (the sphere entirely above the
    horizon), so the patch's radiance is rho L (R / D)^2 cos(theta). The camera sees a 0.03
    wide spot, where it varies by < 0.1 %; 65 536 paths give a standard error of about
    0.5 % (measured over seeds), so the test allows 2 %. Next-event estimation's shadow
    rays end on the curved emitter at grazing angles near its silhouette: shifted parallel
    to themselves off the floor, they once met the emitter before their end, and this
    estimate was 9.6 % low."""
    path = tmp_path / "sphere_light.xml"
    path.write_text(SPHERE_LIGHT)
    y = np.asarray(
        rr.render(path, spp=4096, return_xyz=True, integrator=integrator, progress=False)
    )[..., 1]
    d = np.hypot(1.5, 1.2)
    expected = 0.6 * 4.0 * (0.6 / d) ** 2 * (1.2 / d)  # the white radiance's Y is 4
    assert abs(y.mean() / expected - 1) < 0.02, (y.mean(), expected)


SPHERE_LIGHT_VIEW = """<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0, 1.5, 5" target="0, 0, 0" up="0, 1, 0"/>
    </transform>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/>
      <rfilter type="gaussian"/></film></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="4"/>
    <rotate x="1" angle="-90"/><translate y="-1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6"/></bsdf></shape>
  <shape type="sphere"><point name="center" value="0, 0.2, 0"/><float name="radius" value="0.6"/>
    <emitter type="area"><rgb name="radiance" value="{radiance}"/></emitter></shape>
</scene>
"""


@pytest.mark.slow
def test_sphere_light_matches_mitsuba_by_the_z_test(tmp_path):
    """A sphere light over a floor against Mitsuba 3's analytic sphere, pixel by pixel, by
    Mitsuba's own one-sample test: light samples from the cone the sphere subtends give
    Mitsuba's noise (points sampled by area on the tessellated sphere had 63 times its
    per-sample variance and failed this test at any spp). The light 8 % dimmer fails."""
    pytest.importorskip("mitsuba")
    from ._mitsuba import mitsuba_moments

    path, dim = tmp_path / "sphere.xml", tmp_path / "dim.xml"
    path.write_text(SPHERE_LIGHT_VIEW.format(radiance=4.0))
    dim.write_text(SPHERE_LIGHT_VIEW.format(radiance=3.68))
    mean, var = mitsuba_moments(path, 1024, seed=1)
    for scene, passes in ((path, True), (dim, False)):
        image = np.asarray(rr.render(scene, spp=64, seed=3, return_xyz=True, progress=False))
        res = pixel_z_test(image.astype(np.float64), mean, var, 64, 1024)
        assert res.passed is passes, (scene.name, res.message)


def test_sphere_light_cone_sampling(tmp_path):
    """Light samples of a sphere emitter seen from outside: directions uniform in the cone
    the true sphere subtends (chi-square against the closed-form density
    1 / (2 pi (1 - cos theta_max)), sin theta_max = R / D), points on the true sphere, and
    the density `pdf_li` gives a BSDF sample that hits the light's triangles equal to the
    light sample's (the two sides of MIS). From inside the sphere, triangles are sampled by
    area as before."""
    import jax

    from radiometria.montecarlo import chi2_test
    from radiometria.render._integrators._path import _vertex

    # cos theta_max = 0.96, a boundary of the chi-square grid's cells (400 in cos theta)
    center, radius, dist = np.array([0.0, 0.2, 0.0]), 0.6, 0.6 / 0.28
    scene, _, _ = rr.compile_scene(rr.load_scene(_write(tmp_path, SPHERE_LIGHT, "s.xml")))
    light = scene.light
    assert light.sphere_radius is not None
    p0 = center - np.array([0.0, 0.0, dist])  # the cone's axis is +z
    cos_max = np.sqrt(1.0 - (radius / dist) ** 2)

    def sample(u, p=p0):
        n = u.shape[0]
        p = jnp.broadcast_to(jnp.asarray(p, jnp.float32), (n, 3))
        wl = jnp.full((n, 4), 550.0, jnp.float32)
        return light.sample_li(p, u[:, 0], u[:, 1:3], wl)

    def pdf(w):
        cos = np.asarray(w)[:, 2]
        return np.where(cos >= cos_max, 1.0 / (2.0 * np.pi * (1.0 - cos_max)), 0.0)

    res = chi2_test(
        lambda u: sample(u.astype(jnp.float32)).wi, pdf, domain="sphere", n_samples=100_000,
        key=jax.random.key(7), u_dim=3, resolution=(400, 12),
    )  # fmt: skip
    assert res.passed, res.message

    u = jax.random.uniform(jax.random.key(1), (4096, 3), jnp.float32)
    for p in (p0, center + np.array([1.0, 0.5, -0.7])):
        ls = sample(u, p)
        y = p + np.asarray(ls.dist)[:, None] * np.asarray(ls.wi)
        np.testing.assert_allclose(np.linalg.norm(y - center, axis=1), radius, rtol=1e-4)
        origin = jnp.broadcast_to(jnp.asarray(p, jnp.float32), (4096, 3))
        hit = _vertex(scene, origin, ls.wi)
        ok = np.asarray(hit.valid)
        assert ok.mean() > 0.99  # all but the sliver between the mesh and the true sphere
        pdf_hit = np.asarray(light.pdf_li(hit.face, hit.t, hit.cos_o, origin))
        np.testing.assert_allclose(pdf_hit[ok], np.asarray(ls.pdf)[ok], rtol=1e-4)
    # inside the sphere: area sampling of the triangles, the density pdf_li has without origin
    ls = sample(u, center + np.array([0.1, 0.0, 0.0]))
    hit = _vertex(scene, jnp.broadcast_to(jnp.asarray(center + [0.1, 0, 0], jnp.float32),
                  (4096, 3)), ls.wi)  # fmt: skip
    ok = np.asarray(hit.valid & (ls.pdf > 0))
    np.testing.assert_allclose(np.asarray(light.pdf_li(hit.face, hit.t, hit.cos_o))[ok],
                               np.asarray(ls.pdf)[ok], rtol=2e-3)  # fmt: skip
