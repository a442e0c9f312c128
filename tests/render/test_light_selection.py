"""Next-event estimation's choice among several area emitters by their estimated
contribution at the shading point (`radiometria.render._lights._selection`): never zero where
an emitter can light the point, densities consistent with `pdf_li` (the two sides of MIS),
emitters picked as often as their probabilities say, and light-sample estimates of the
emitters' solid-angle-weighted radiance equal to the exact solid angles."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import stats

import radiometria.render as rr
from radiometria.render._integrators._path import _vertex

# A large dim emitter behind, a small bright one above facing down, a sphere emitter aside
# and a small one facing away from the origin (+x side, normal +x).
SCENE = """<scene version="3.0.0">
  <shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="-3"/>
    </transform><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.5"/>
    <rotate x="1" angle="90"/><translate y="2"/></transform>
    <emitter type="area"><rgb name="radiance" value="4"/></emitter></shape>
  <shape type="sphere"><point name="center" value="2, 0, 0"/><float name="radius" value="0.3"/>
    <emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.4"/>
    <rotate y="1" angle="90"/><translate x="-2" y="1"/></transform>
    <emitter type="area"><rgb name="radiance" value="3"/></emitter></shape>
</scene>
"""
# Rectangles `(center, half-size, unit normal, in-plane axes)` of SCENE, for the references.
RECTS = [
    ((0, 0, -3), 3.0, (0, 0, 1), ((1, 0, 0), (0, 1, 0))),
    ((0, 2, 0), 0.5, (0, -1, 0), ((1, 0, 0), (0, 0, 1))),
    ((-2, 1, 0), 0.4, (1, 0, 0), ((0, 1, 0), (0, 0, 1))),
]
SPHERE = ((2.0, 0.0, 0.0), 0.3)
POINTS = np.array(
    [
        [0.0, 0.0, 0.0],
        [0.3, 1.6, 0.2],  # close under the small bright emitter
        [0.5, -0.5, -2.5],  # close to the large one
        [-2.5, 2.2, 1.5],  # behind the one facing +x
        [3.5, 2.5, -3.5],  # above the bright one, behind the large one: only the sphere
    ]
)


@pytest.fixture(scope="module")
def light(tmp_path_factory):
    path = tmp_path_factory.mktemp("selection") / "lights.xml"
    path.write_text(SCENE)
    scene, _, _ = rr.compile_scene(rr.load_scene(path))
    assert scene.light.selection is not None
    return scene


def _triangle_solid_angle(p, a, b, c):
    """Van Oosterom & Strackee (1983): the solid angle of triangle abc seen from p. [sr]"""
    r = [np.asarray(x, np.float64) - p for x in (a, b, c)]
    n = [np.linalg.norm(x) for x in r]
    num = np.dot(r[0], np.cross(r[1], r[2]))
    den = n[0] * n[1] * n[2] + np.dot(r[0], r[1]) * n[2] + np.dot(r[0], r[2]) * n[1]
    den += np.dot(r[1], r[2]) * n[0]
    return abs(2.0 * np.arctan2(num, den))


def _rect_solid_angle(p, rect):
    """Solid angle of a one-sided rectangle seen from p (0 from behind). [sr]"""
    c, h, n, (s, t) = (np.asarray(x, np.float64) if i != 1 else x for i, x in enumerate(rect))
    s, t = np.asarray(s, np.float64), np.asarray(t, np.float64)
    if np.dot(p - c, n) <= 0:
        return 0.0
    q = [c + h * (i * s + j * t) for i, j in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return _triangle_solid_angle(p, q[0], q[1], q[2]) + _triangle_solid_angle(p, q[0], q[2], q[3])


def _reference(p):
    """`[(radiance row value, solid angle)]` per emitter row (scene order) seen from p."""
    c, r = np.asarray(SPHERE[0]), SPHERE[1]
    d = np.linalg.norm(p - c)
    sphere = 2.0 * np.pi * (1.0 - np.sqrt(1.0 - (r / d) ** 2))
    return [
        (1.0, _rect_solid_angle(p, RECTS[0])),
        (4.0, _rect_solid_angle(p, RECTS[1])),
        (2.0, sphere),
        (3.0, _rect_solid_angle(p, RECTS[2])),
    ]


def test_every_emitter_that_can_light_a_point_keeps_a_positive_probability(light):
    """At random points, an emitter has probability 0 only if none of its triangles' points
    faces the point (for a flat triangle, none of its corners: the facing test is linear on
    it); the probabilities sum to 1."""
    sel = light.light.selection
    lt = light.light
    pts = np.random.default_rng(3).uniform(-4.0, 4.0, (2000, 3))
    probs = np.asarray(sel.probabilities(jnp.asarray(pts, jnp.float32)))
    np.testing.assert_allclose(probs.sum(axis=1), 1.0, rtol=1e-5)
    p0, e1, e2 = (np.asarray(x, np.float64) for x in (lt.p0, lt.e1, lt.e2))
    corners = np.concatenate([p0, p0 + e1, p0 + e2])
    normal = np.tile(np.asarray(lt.normal, np.float64), (3, 1))
    slot = np.asarray(sel.slot)[np.asarray(lt.face_emitter)[np.asarray(lt.light_face)]]
    slot = np.tile(slot, 3)
    for e in range(probs.shape[1]):
        y, n = corners[slot == e], normal[slot == e]
        facing = np.any(np.einsum("pyk,yk->py", pts[:, None] - y[None], n) > 0, axis=1)
        assert np.all(probs[facing, e] > 0), (e, pts[facing & (probs[:, e] <= 0)][:3])
    assert np.any(probs == 0) and np.any((probs > 0) & (probs < 0.05))  # it discriminates


def test_light_samples_agree_with_pdf_li_and_pick_emitters_at_their_rates(light):
    """From each point: the emitters are picked with the probabilities `probabilities`
    gives (chi-square), and a BSDF-style ray along each light sample's direction meets the
    light where `pdf_li` gives it the light sample's own density."""
    lt = light.light
    n = 20_000
    u = jax.random.uniform(jax.random.key(5), (n, 3), jnp.float32)
    wl = jnp.full((n, 4), 550.0, jnp.float32)
    for p in POINTS:
        origin = jnp.broadcast_to(jnp.asarray(p, jnp.float32), (n, 3))
        ls = lt.sample_li(origin, u[:, 0], u[:, 1:3], wl)
        hit = _vertex(light, origin, ls.wi)
        dist = np.asarray(ls.dist)
        ok = np.asarray(hit.valid & (ls.pdf > 0)) & (np.abs(np.asarray(hit.t) - dist) < 1e-3)
        assert ok.sum() > 2000, (p, ok.mean())  # the rest are shadowed by other emitters
        pdf_hit = np.asarray(lt.pdf_li(hit.face, hit.t, hit.cos_o, origin))
        np.testing.assert_allclose(pdf_hit[ok], np.asarray(ls.pdf)[ok], rtol=2e-3)
        probs = np.asarray(lt.selection.probabilities(origin[:1]), np.float64)[0]
        probs /= probs.sum()
        # the emitter of each sample, by where its point lies (the rectangles' planes)
        y = p + dist[:, None] * np.asarray(ls.wi, np.float64)
        row = np.select(
            [np.abs(y[:, 2] + 3) < 1e-3, np.abs(y[:, 1] - 2) < 1e-3, np.abs(y[:, 0] + 2) < 1e-3],
            [0, 1, 3],
            2,
        )
        seen = np.bincount(np.asarray(lt.selection.slot)[row], minlength=probs.size)
        live = probs > 0
        assert np.all(seen[~live] == 0), (p, seen, probs)
        expected = probs[live] * seen.sum()
        assert stats.chisquare(seen[live], expected).pvalue > 1e-3, (p, seen, expected)


def test_light_sample_estimate_of_the_emitters_radiance_is_unbiased(light):
    """The light-sample estimate of sum_e L_e Omega_e (each emitter's radiance times the solid
    angle of its front side seen from the point: exact for the rectangles, by the
    Van Oosterom-Strackee formula, and the sphere's cone) equals it within 4.5 standard
    errors at every point, also where emitters face away or are far."""
    lt = light.light
    n = 200_000
    u = jax.random.uniform(jax.random.key(11), (n, 3), jnp.float32)
    wl = jnp.full((n, 4), 550.0, jnp.float32)
    rows = jnp.arange(4, dtype=jnp.int32)
    le_rows = np.asarray(lt.radiance(rows, jnp.full((4, 4), 550.0, jnp.float32), None))[:, 0]
    for p in POINTS:
        origin = jnp.broadcast_to(jnp.asarray(p, jnp.float32), (n, 3))
        ls = lt.sample_li(origin, u[:, 0], u[:, 1:3], wl)
        pdf = np.asarray(ls.pdf, np.float64)
        est = np.where(pdf > 0, np.asarray(ls.radiance, np.float64)[:, 0] / np.where(
            pdf > 0, pdf, 1.0), 0.0)  # fmt: skip
        ref = sum(le * omega for le, (_, omega) in zip(le_rows, _reference(p), strict=True))
        se = est.std() / np.sqrt(n)
        assert abs(est.mean() - ref) < 4.5 * se + 1e-4 * ref, (p, est.mean(), ref, se)
        # the rows' radiances are the scene's values times one spectrum
        np.testing.assert_allclose(le_rows / le_rows[0], [1, 4, 2, 3], rtol=1e-5)
