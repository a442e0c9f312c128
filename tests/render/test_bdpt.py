"""Bidirectional path tracing (`bdpt`): MIS weights against their definition, agreement with
the path tracer by the per-pixel z-test, bad parameters, the command line (issue 14)."""

import itertools

import jax.numpy as jnp
import numpy as np
import pytest

from radiometria.camera import BoxFilter, read_exr, write_exr
from radiometria.cli import main
from radiometria.montecarlo import pixel_z_test
from radiometria.render import OwenSobol, Path, bdpt_strategy_images, render
from radiometria.render._integrators import BDPT, bdpt_mis_weight

from ._mitsuba import cornell_box_materials_xml
from .test_envmap import _CARD, _colour_map, _envmap, _scene as _envmap_scene
from .test_ptracer import _cornell_light_coverage, _cornell_light_luminance

# -- MIS weights --------------------------------------------------------------------------


def _reference_weights(p_cam, p_light, delta, light_delta, beta, light_infinite=False):
    """Weights of every strategy (s, t) of one path x_0 (camera) .. x_m (light) straight from
    Veach's definition w = p_st^beta / sum_i p_i^beta (eq. 10.9), p_st = prod_{i<t} p_cam[i]
    prod_{i>=t} p_light[i]; a strategy is impossible (p = 0) when it connects through a delta
    vertex (x_{t-1} or x_t), has to hit a delta light (s = 0), or joins the camera to a light
    at infinity ((1, 1))."""
    m = len(p_cam) - 1
    p = {}
    for t in range(1, m + 2):
        s = m + 1 - t
        ok = not (t - 1 >= 1 and delta[t - 1]) and not (s >= 1 and t <= m and delta[t])
        ok = ok and not (s == 0 and light_delta)
        ok = ok and not (s == 1 and t == 1 and light_infinite)
        p[(s, t)] = np.prod(p_cam[:t]) * np.prod(p_light[t:]) if ok else 0.0
    total = sum(v**beta for v in p.values())
    if total == 0:  # no strategy can sample the path (a directional light seen directly)
        return {}
    return {st: v**beta / total for st, v in p.items()}


def _ours(p_cam, p_light, delta, light_delta, s, t, heuristic, light_infinite=False):
    """`bdpt_mis_weight` for strategy (s, t) of the same path, in the subpath layout the
    integrator builds: camera vertices z_j = x_j (fwd: camera-side densities), light vertices
    y_j = x_{m-j} (fwd: light-side densities), padded with junk beyond the strategy."""
    m = len(p_cam) - 1
    rng = np.random.default_rng(7)
    size = m + 2
    fwd_c, rev_c = rng.uniform(0.1, 5, size), rng.uniform(0.1, 5, size)
    delta_c = rng.uniform(size=size) < 0.5
    fwd_l, rev_l = rng.uniform(0.1, 5, size), rng.uniform(0.1, 5, size)
    delta_l = rng.uniform(size=size) < 0.5
    fwd_c[:t], rev_c[:t], delta_c[:t] = p_cam[:t], p_light[:t], delta[:t]
    idx = [m - j for j in range(s)]
    fwd_l[:s], rev_l[:s], delta_l[:s] = p_light[idx], p_cam[idx], delta[idx]
    if t >= 1:
        delta_c[t - 1] = False  # the connection vertices (as the integrator sets them)
    if s >= 1:
        delta_l[s - 1] = False
    col = lambda a, dt=jnp.float64: jnp.asarray(a, dt)[:, None]  # noqa: E731
    w = bdpt_mis_weight(
        col(fwd_c), col(rev_c), col(delta_c, bool), t, col(fwd_l), col(rev_l),
        col(delta_l, bool), jnp.asarray([light_delta]), s, heuristic=heuristic,
        light_infinite=jnp.asarray([light_infinite]),
    )  # fmt: skip
    return float(w[0])


@pytest.mark.parametrize("heuristic", ["balance", "power"])
def test_bdpt_mis_weights_sum_to_one_and_match_the_definition(heuristic):
    # Random paths of 2..6 vertices with random densities (spanning 6 decades), random
    # specular vertices, delta lights and lights at infinity: each strategy's weight by the
    # ratio recursion equals Veach's p^beta / sum p^beta, and the weights of all strategies
    # sum to 1.
    beta = 2 if heuristic == "power" else 1
    rng = np.random.default_rng(1)
    for trial in range(60):
        m = 1 + trial % 5
        p_cam = 10 ** rng.uniform(-3, 3, m + 1)
        p_light = 10 ** rng.uniform(-3, 3, m + 1)
        p_cam[0] = 1.0  # the pinhole
        delta = rng.uniform(size=m + 1) < 0.25
        delta[0] = delta[m] = False  # the end points are not specular surfaces
        light_delta = bool(rng.uniform() < 0.3)
        infinite = bool(rng.uniform() < 0.3)
        ref = _reference_weights(p_cam, p_light, delta, light_delta, beta, infinite)
        ours = {}
        for (s, t), w_ref in ref.items():
            if w_ref == 0:  # impossible strategy: the integrator never evaluates it
                continue
            ours[(s, t)] = _ours(p_cam, p_light, delta, light_delta, s, t, heuristic, infinite)
            np.testing.assert_allclose(ours[(s, t)], w_ref, rtol=1e-9, err_msg=str((s, t, m)))
        if ref:
            np.testing.assert_allclose(sum(ours.values()), 1.0, rtol=1e-9)


def test_bdpt_mis_weight_negative_control():
    # The ratio recursion with one vertex's reverse density changed no longer sums to 1.
    p_cam = np.array([1.0, 0.3, 2.0, 0.7])
    p_light = np.array([5.0, 1.5, 0.2, 3.0])
    delta = np.zeros(4, bool)
    total = sum(_ours(p_cam, p_light, delta, False, 4 - t, t, "power") for t in range(1, 5))
    np.testing.assert_allclose(total, 1.0, rtol=1e-9)
    p_bad = p_light.copy()
    p_bad[2] *= 1.5
    total = sum(_ours(p_cam, p_bad if t > 2 else p_light, delta, False, 4 - t, t, "power")
                for t in range(1, 5))  # fmt: skip
    assert abs(total - 1.0) > 1e-3


# -- agreement with the path tracer ---------------------------------------------------------


def _moments(scene, integrator, seeds, spp, size):
    # Owen-scrambled Sobol points, independent across seeds: the variance of the mean over
    # the renders is estimated from them.
    images = np.stack([
        np.asarray(render(scene, spp=spp, width=size, height=size, seed=s, sampler=OwenSobol(),
                          integrator=integrator, return_xyz=True, progress=False), np.float64)
        for s in seeds
    ])  # fmt: skip
    return images.mean(axis=0), images.var(axis=0, ddof=1) / len(seeds)


def _z_test(image, var, ref, var_ref, total):
    # The variance of the difference of two independent means, as one per-sample variance.
    return pixel_z_test(
        image, ref, (var + var_ref) * total, total, None, required_fraction=0.99,
        variance_floor=1e-8,
    )  # fmt: skip


@pytest.mark.slow
def test_bdpt_agrees_with_path_on_cornell_box():
    # Both estimate the filtered pixel values (Gaussian filter, splatting) of the built-in
    # Cornell box; the negative control (bdpt's image 5 % brighter, as if the light were)
    # must fail the same test.
    # Emitters seen directly are hidden on both sides: bdpt sees them almost only by light
    # tracing, checked against the closed form below.
    # The path tracer's reference takes 4x the samples (it is cheaper, and its rare caustic
    # samples make its variance estimate heavy-tailed); both variances come from 8 renders.
    size, spp, depth, n = 10, 16, 3, 8
    bdpt = BDPT(max_depth=depth, hide_emitters=True, heuristic="balance")  # (power: below)
    ours, var = _moments("cornell-box", bdpt, range(n), spp, size)
    path = Path(max_depth=depth, hide_emitters=True)
    ref, var_ref = _moments("cornell-box", path, range(50, 50 + n), 4 * spp, size)
    result = _z_test(ours, var, ref, var_ref, n * spp)
    assert result.passed, result.message
    np.testing.assert_allclose(ours.mean(axis=(0, 1)), ref.mean(axis=(0, 1)), rtol=0.03)
    bad = _z_test(1.05 * ours, 1.05**2 * var, ref, var_ref, n * spp)
    assert not bad.passed, bad.message


def test_bdpt_cornell_light_pixels_closed_form():
    # max_depth 1 (box filter): the light's pixels are Y(L) times the area of its image in
    # each (the closed form of the ptracer tests); both strategies (0, 2) and (1, 1) count.
    size = 16
    expected = _cornell_light_luminance() * _cornell_light_coverage(size)
    image = np.asarray(
        render("cornell-box", spp=256, width=size, height=size, integrator=BDPT(max_depth=1),
               rfilter=BoxFilter(), return_xyz=True, progress=False)
    )[..., 1]  # fmt: skip
    lit = expected > 0.05 * expected.max()
    np.testing.assert_allclose(image[lit], expected[lit], rtol=0.02)
    np.testing.assert_allclose(image.sum(), expected.sum(), rtol=5e-3)
    np.testing.assert_array_equal(image[expected == 0], 0.0)
    hidden = render("cornell-box", spp=2, width=4, height=4, progress=False,
                    integrator=BDPT(max_depth=1, hide_emitters=True))  # fmt: skip
    assert float(np.max(np.abs(hidden))) == 0.0


def _specular_scene(tmp_path):
    """Mitsuba's Cornell box with a rough gold box (GGX) and a glass box, lit by its area light
    and a point light near the ceiling. (The mirror back wall of `cornell_box_materials_xml`
    is left white: its caustics reach the path tracer only by rare BSDF samples, whose
    heavy-tailed estimates need far more samples than CI affords for a variance estimate.)"""
    xml = cornell_box_materials_xml(8, 8).replace('<ref id="mirror"/>', '<ref id="white"/>')
    assert 'id="gold"/>' in xml and 'id="glass"/>' in xml
    point = ('  <emitter type="point"><point name="position" x="-0.4" y="0.7" z="0.3"/>'
             '<rgb name="intensity" value="0.6 0.6 0.6"/></emitter>\n')  # fmt: skip
    xml = xml.replace("</scene>", point + "</scene>")
    path = tmp_path / "specular.xml"
    path.write_text(xml)
    return path


@pytest.mark.slow
def test_bdpt_agrees_with_path_on_specular_scene(tmp_path):
    # Glass and glossy gold (delta and near-delta vertices, connections through delta ones
    # refused, their densities excluded from the weights) and a point light (a delta light).
    # Emitters seen directly hidden, as on the Cornell box (the light seen in the mirror stays).
    scene = _specular_scene(tmp_path)
    size, spp, depth, n = 10, 16, 3, 8
    path = Path(max_depth=depth, hide_emitters=True)
    ref, var_ref = _moments(scene, path, range(50, 50 + n), 4 * spp, size)
    integrator = BDPT(max_depth=depth, heuristic="power", hide_emitters=True)
    ours, var = _moments(scene, integrator, range(n), spp, size)
    result = _z_test(ours, var, ref, var_ref, n * spp)
    assert result.passed, result.message
    np.testing.assert_allclose(ours.mean(axis=(0, 1)), ref.mean(axis=(0, 1)), rtol=0.04)


def _sky_scene(tmp_path):
    """A colour environment map seen directly around a tilted diffuse card and a rough gold
    sphere on a grey floor, with a directional light: the lights at infinity of issue 14."""
    exr = write_exr(tmp_path / "sky.exr", _colour_map())
    sun = ('<emitter type="directional"><vector name="direction" x="0.3" y="0.2" z="-1"/>'
           '<rgb name="irradiance" value="1.5"/></emitter>')  # fmt: skip
    body = (
        _CARD + '<shape type="rectangle"><transform name="to_world"><scale value="1.2"/>'
        '<translate z="-0.6"/></transform><bsdf type="diffuse"><rgb name="reflectance" '
        'value="0.4"/></bsdf></shape>'
        '<shape type="sphere"><point name="center" x="0.45" y="0.35" z="0.35"/><float '
        'name="radius" value="0.25"/><bsdf type="roughconductor"><string name="material" '
        'value="Au"/><float name="alpha" value="0.3"/></bsdf></shape>' + sun
    )
    path = tmp_path / "sky.xml"
    path.write_text(_envmap_scene(_envmap(exr), body, size=10))
    return path


@pytest.mark.slow
def test_bdpt_agrees_with_path_under_lights_at_infinity(tmp_path):
    # An environment map (seen directly: strategy (0, 2) alone, as (1, 1) cannot reach a point
    # at infinity), escaped camera rays weighted against next-event estimation of the map's
    # directions and against light paths from the scene's disk, and a directional light (a
    # delta light at infinity). A 5 % brighter image fails the same test.
    scene = _sky_scene(tmp_path)
    size, spp, depth, n = 10, 16, 3, 8
    ref, var_ref = _moments(scene, Path(max_depth=depth), range(50, 50 + n), 4 * spp, size)
    ours, var = _moments(scene, BDPT(max_depth=depth), range(n), spp, size)
    result = _z_test(ours, var, ref, var_ref, n * spp)
    assert result.passed, result.message
    np.testing.assert_allclose(ours.mean(axis=(0, 1)), ref.mean(axis=(0, 1)), rtol=0.02)
    bad = _z_test(1.05 * ours, 1.05**2 * var, ref, var_ref, n * spp)
    assert not bad.passed, bad.message


# -- per-strategy images ---------------------------------------------------------------------

_K = 2  # path length (segments) of the per-strategy tests: s + t - 1 = 2, one bounce
_SIZE, _SPP, _SEEDS = 8, 8, range(16)  # many seeds: the variance estimates are t-distributed


@pytest.fixture(scope="module")
def length_k_reference():
    # The path tracer's image of the paths of exactly k segments, per seed: max_depth = k
    # minus max_depth = k - 1 with the same samples (their shorter paths cancel); its mean
    # and the variance of that mean over the seeds.
    def one(depth, seed):
        return np.asarray(
            render("cornell-box", spp=4 * _SPP, width=_SIZE, height=_SIZE, seed=seed,
                   sampler=OwenSobol(), integrator=Path(max_depth=depth), return_xyz=True,
                   batch=_SIZE * _SIZE * 4 * _SPP, progress=False), np.float64)  # fmt: skip

    diffs = np.stack([one(_K, 50 + s) - one(_K - 1, 50 + s) for s in _SEEDS])
    return diffs.mean(axis=0), diffs.var(axis=0, ddof=1) / len(_SEEDS)


def _strategy_moments(weighted, strategies):
    per_seed = [
        bdpt_strategy_images("cornell-box", max_depth=_K, spp=_SPP, weighted=weighted,
                             strategies=strategies, width=_SIZE, height=_SIZE, seed=s,
                             sampler=OwenSobol(), return_xyz=True, batch=_SIZE * _SIZE * _SPP)
        for s in _SEEDS
    ]  # fmt: skip
    out = {}
    for st in strategies:
        images = np.stack([np.asarray(p[st], np.float64) for p in per_seed])
        out[st] = images
    return out


@pytest.mark.slow
def test_bdpt_weighted_strategy_images_of_one_length_sum_to_the_path_tracers(
    length_k_reference,
):
    # Veach eq. 10.9: the MIS weights of a path's strategies sum to 1, so the weighted images
    # of the strategies with s + t - 1 = k sum to the image of the paths of exactly k
    # segments, here the path tracer's (an independent estimator: NEE + BSDF sampling). The
    # sum without one strategy (the negative control) must fail the same z-test.
    ref, var_ref = length_k_reference
    pairs = [(s, _K + 1 - s) for s in range(_K + 1)]  # (0, 3), (1, 2), (2, 1)
    images = _strategy_moments(True, pairs)
    total = sum(images.values())
    n = len(_SEEDS)
    result = _z_test(total.mean(0), total.var(0, ddof=1) / n, ref, var_ref, n * _SPP)
    assert result.passed, result.message
    np.testing.assert_allclose(total.mean(axis=(0, 1, 2)), ref.mean(axis=(0, 1)), rtol=0.03)
    dropped = total - images[(1, _K)]  # without the one-bounce next-event strategy
    bad = _z_test(dropped.mean(0), dropped.var(0, ddof=1) / n, ref, var_ref, n * _SPP)
    assert not bad.passed, bad.message


@pytest.mark.slow
def test_bdpt_unweighted_strategy_images_are_each_unbiased(length_k_reference):
    # Without MIS weights each strategy alone estimates the whole length-k image (on the
    # diffuse Cornell box every strategy can sample every path): light tracing (2, 1) and
    # next-event estimation (1, 2) each pass the z-test against the path tracer's length-k
    # image; a 10 % brighter (1, 2) fails. (Hitting the small light by BSDF sampling, (0, 3),
    # is left out: at CI sample counts most seeds never hit the light in most pixels, so its
    # variance cannot be estimated from them.)
    ref, var_ref = length_k_reference
    pairs = [(1, _K), (2, _K - 1)]
    images = _strategy_moments(False, pairs)
    n = len(_SEEDS)
    for st, im in images.items():
        result = _z_test(im.mean(0), im.var(0, ddof=1) / n, ref, var_ref, n * _SPP)
        assert result.passed, f"{st}: {result.message}"
    im = 1.1 * images[(1, _K)]
    bad = _z_test(im.mean(0), im.var(0, ddof=1) / n, ref, var_ref, n * _SPP)
    assert not bad.passed, bad.message


def test_bdpt_strategy_images_bad_input():
    with pytest.raises(ValueError, match=r"\(3, 1\).*max_depth=1"):
        bdpt_strategy_images("cornell-box", max_depth=1, spp=1, strategies=[(3, 1)])
    with pytest.raises(TypeError, match="integrator"):
        bdpt_strategy_images("cornell-box", max_depth=1, spp=1, integrator=Path())
    with pytest.raises(TypeError, match="weighted"):
        bdpt_strategy_images("cornell-box", max_depth=1, spp=1, weighted=1)


# -- bad input, command line ------------------------------------------------------------------


def test_bdpt_bad_parameters():
    with pytest.raises(ValueError, match=r"heuristic.*\['balance', 'power'\].*'max'"):
        BDPT(heuristic="max")
    with pytest.raises(ValueError, match="max_depth.*>= 1.*0"):
        BDPT(max_depth=0)
    with pytest.raises(ValueError, match="scene.xml.*bdpt.*max_depth"):
        BDPT.from_properties({"max_depth": 0}, where="scene.xml")
    with pytest.raises(ValueError, match="scene.xml: unknown bdpt parameter"):
        BDPT.from_properties({"max_depht": 3}, where="scene.xml")
    with pytest.raises(ValueError, match="scene.xml: bdpt: .*heuristic.*'veach'"):
        BDPT.from_properties({"heuristic": "veach"}, where="scene.xml")
    b = BDPT.from_properties({"max_depth": 4, "heuristic": "balance", "hide_emitters": True})
    assert (b.max_depth, b.heuristic, b.hide_emitters) == (4, "balance", True)
    with pytest.raises(TypeError, match="render"):
        b.radiance(None, None, None, None, None, None)
    # every (s, t) with s + t - 1 <= max_depth, once
    cam, light = BDPT(max_depth=3).strategies()
    expected = {(s, t) for s, t in itertools.product(range(5), range(1, 5)) if 2 <= s + t <= 4}
    assert sorted(cam + light) == sorted(expected) and len(cam + light) == len(expected)


@pytest.mark.slow
def test_bdpt_from_the_command_line(tmp_path):
    exr = tmp_path / "x.exr"
    argv = ["render", "cornell-box", "--width", "8", "--height", "8", "--spp", "2"]
    assert main(argv + ["--integrator", "bdpt", "--max-depth", "2", "--out", str(exr)]) == 0
    rgb, meta = read_exr(exr)
    assert rgb.shape == (8, 8, 3) and np.all(np.isfinite(rgb)) and rgb.mean() > 0
    assert meta["integrator"] == "bdpt"
