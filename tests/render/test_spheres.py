"""Analytic spheres (thesis ch. 8): the ray-sphere test against closed forms and Mitsuba 3's
analytic sphere, its uv against the loader's tessellation, and the renderer with true spheres
against closed forms and against its tessellated spheres."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from radiometria.render import compile_scene, load_mitsuba_xml
from radiometria.render._accelerators import BVHAccelerator, SphereAccelerator
from radiometria.render._geometry._sphere import Spheres
from radiometria.render._scenes._shapes import SPHERE_MAX_RADIAL_ERROR, sphere

from .test_volpath import _box, _check_mean, _estimate, _medium, _scene

CENTERS = np.array([[0.0, 0.0, 0.0], [3.0, 0.5, -1.0], [-2.0, 2.0, 1.0]])
RADII = np.array([1.0, 0.5, 1.5])


def _rotation(seed):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def _spheres(dtype=jnp.float32):
    rot = np.stack([_rotation(i) for i in range(3)])
    return Spheres.from_arrays(CENTERS, RADII, rot, [10, 20, 30], dtype=dtype)


def _reference_t(o, d, t_max):
    """The first root in (0, t_max) over all spheres, in float64 (NumPy's polynomial roots),
    and which rays are too close to call in float32 (grazing a sphere, or with a root within
    a relative 1e-4 of 0 or `t_max`)."""
    best_t = np.full(len(o), np.inf)
    best_i = np.full(len(o), -1)
    close = np.zeros(len(o), bool)
    for i, (c, r) in enumerate(zip(CENTERS, RADII, strict=True)):
        for j in range(len(o)):
            f = o[j] - c
            a, b, cc = d[j] @ d[j], 2.0 * f @ d[j], f @ f - r * r
            close[j] |= abs(b * b - 4 * a * cc) < 1e-4 * (b * b + abs(4 * a * cc))
            roots = np.roots([a, b, cc])
            roots = roots[np.isreal(roots)].real
            scale = np.maximum(np.abs(roots), 1.0)
            close[j] |= np.any((np.abs(roots) < 1e-4 * scale) | (np.abs(roots - t_max[j])
                                                                 < 1e-4 * scale))  # fmt: skip
            roots = roots[(roots > 0) & (roots < t_max[j])]
            if len(roots) and roots.min() < best_t[j]:
                best_t[j], best_i[j] = roots.min(), i
    return best_t, best_i, close


def test_closest_hits_match_the_quadratic_in_float64():
    """Rays from outside and inside the spheres, of any direction length, with finite and
    infinite `t_max`: the closest root in float32 agrees with the float64 roots."""
    rng = np.random.default_rng(0)
    n = 400
    o = rng.uniform(-4, 4, (n, 3))
    o[:50] = CENTERS[rng.integers(0, 3, 50)] + 0.3 * rng.normal(size=(50, 3)) * 0.5  # inside
    target = CENTERS[rng.integers(0, 3, n)] + rng.normal(size=(n, 3))
    d = (target - o) * rng.uniform(0.2, 3.0, (n, 1))
    t_max = np.where(rng.uniform(size=n) < 0.3, rng.uniform(0.1, 2.0, n), np.inf)
    ref_t, ref_i, close = _reference_t(o, d, t_max)
    t, index = _spheres().intersect_closest(
        jnp.asarray(o, jnp.float32), jnp.asarray(d, jnp.float32), jnp.asarray(t_max, jnp.float32)
    )
    t, index = np.asarray(t, np.float64), np.asarray(index)
    hit = np.isfinite(ref_t)
    assert 0.3 * n < hit.sum() < n  # both hits and misses are tested
    clear = ~close
    assert clear.sum() > 0.95 * n
    np.testing.assert_array_equal(index[clear], ref_i[clear])
    both = hit & clear
    np.testing.assert_allclose(t[both], ref_t[both], rtol=2e-5, atol=1e-6)
    blocked = np.asarray(_spheres().intersect_any(jnp.asarray(o, jnp.float32),
                                                  jnp.asarray(d, jnp.float32),
                                                  jnp.asarray(t_max, jnp.float32)))  # fmt: skip
    np.testing.assert_array_equal(blocked[clear], hit[clear])


def test_far_rays_keep_float32_accuracy():
    """Rays from 1e4 radii away (where the textbook discriminant b^2 - 4ac loses all of r^2
    in float32) hit where the float64 roots say, to float32 rounding of the origin."""
    rng = np.random.default_rng(1)
    n = 200
    w = rng.normal(size=(n, 3))
    o = 1e4 * w / np.linalg.norm(w, axis=1, keepdims=True)
    aim = 0.9 * rng.uniform(-1, 1, (n, 3)) / np.sqrt(3)  # points well inside the unit sphere
    d = aim - o
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    t, index = _spheres().intersect_closest(
        jnp.asarray(o, jnp.float32), jnp.asarray(d, jnp.float32), jnp.full((n,), jnp.inf)
    )
    o32, d32 = o.astype(np.float32).astype(np.float64), d.astype(np.float32).astype(np.float64)
    ref_t, ref_i, _ = _reference_t(o32, d32, np.full(n, np.inf))
    assert np.all(np.isfinite(ref_t))
    np.testing.assert_array_equal(np.asarray(index), ref_i)
    # t ~ 1e4: float32 spacing there is 1e-3; the textbook formula is off by ~1 unit
    np.testing.assert_allclose(np.asarray(t, np.float64), ref_t, rtol=0, atol=4e-3)


@pytest.mark.parametrize(
    "transform",
    [
        "",
        '<rotate x="1" y="2" z="0.5" angle="70"/><scale value="1.7"/><translate x="0.3" z="-2"/>',
    ],
)
def test_uv_and_normals_match_the_loaders_tessellation(tmp_path, transform):
    """The true sphere of a loaded `sphere` (rotated, scaled) has at every vertex of its
    tessellation the vertex's uv and normal: the parametrisation and the rotation agree."""
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="3.0.0"><shape type="sphere"><float name="radius" '
                    f'value="0.6"/><transform name="to_world">{transform}</transform>'
                    '</shape></scene>')  # fmt: skip
    d = load_mitsuba_xml(path)
    (s,) = d.spheres
    spheres = Spheres.from_arrays([s.center], [s.radius], [s.rotation], [0], dtype=jnp.float64)
    v = d.vertices[np.unique(d.faces[s.triangles])]
    uv = d.vertex_uvs[np.unique(d.faces[s.triangles])]
    inner = (uv[:, 1] > 1e-6) & (uv[:, 1] < 1 - 1e-6) & (uv[:, 0] > 1e-6) & (uv[:, 0] < 1 - 1e-6)
    p, n, got = spheres.surface(jnp.zeros(len(v), jnp.int32), jnp.asarray(v))
    np.testing.assert_allclose(np.asarray(got)[inner], uv[inner], atol=1e-9)
    np.testing.assert_allclose(np.asarray(p), v, atol=1e-12)
    normals = d.vertex_normals[np.unique(d.faces[s.triangles])]
    np.testing.assert_allclose(np.asarray(n), normals, atol=1e-9)


def test_tangents_are_the_derivatives_of_the_parametrisation():
    """dp/du and dp/dv equal central differences of p(u, v) = c + R r (sin(pi v) cos(2 pi u),
    sin(pi v) sin(2 pi u), cos(pi v))."""
    rot = _rotation(7)
    c, r = np.array([0.2, -0.1, 0.4]), 1.3

    def point(u, v):
        th, ph = np.pi * v, 2 * np.pi * u
        local = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)
        return c + r * local @ rot.T

    rng = np.random.default_rng(2)
    u, v = rng.uniform(0.05, 0.95, 100), rng.uniform(0.05, 0.95, 100)
    spheres = Spheres.from_arrays([c], [r], [rot], [0], dtype=jnp.float64)
    p = point(u, v)
    _, n, uv = spheres.surface(jnp.zeros(100, jnp.int32), jnp.asarray(p))
    du, dv = spheres.tangents(jnp.zeros(100, jnp.int32), n)
    np.testing.assert_allclose(np.asarray(uv), np.stack([u, v], -1), atol=1e-12)
    h = 1e-6
    fd_u = (point(u + h, v) - point(u - h, v)) / (2 * h)
    fd_v = (point(u, v + h) - point(u, v - h)) / (2 * h)
    np.testing.assert_allclose(np.asarray(du), fd_u, atol=1e-6)
    np.testing.assert_allclose(np.asarray(dv), fd_v, atol=1e-6)


def test_geometry_matches_mitsubas_analytic_sphere():
    """t, normal, uv, dp/du and dp/dv of rays against a rotated, scaled, moved sphere, as
    Mitsuba 3's own `sphere` computes them (`ray_intersect`)."""
    mi = pytest.importorskip("mitsuba")
    from tests.render._mitsuba import VARIANT

    mi.set_variant(VARIANT)
    rot = _rotation(3)
    c, r = np.array([0.3, -0.2, 0.5]), 0.7
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = rot * r, c
    scene = mi.load_dict({"type": "scene", "s": {"type": "sphere",
                                                 "to_world": mi.ScalarTransform4f(m)}})  # fmt: skip
    spheres = Spheres.from_arrays([c], [r], [rot], [0], dtype=jnp.float64)
    rng = np.random.default_rng(4)
    n = 64
    o = c + rng.normal(size=(n, 3)) * 3.0
    d = c + rng.normal(size=(n, 3)) * 0.3 - o
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    ref = []
    for j in range(n):
        si = scene.ray_intersect(mi.Ray3f(mi.ScalarPoint3f(*o[j]), mi.ScalarVector3f(*d[j])))
        if si.is_valid():
            ref.append((j, si.t, [*si.n], [*si.uv], [*si.dp_du], [*si.dp_dv]))
    assert len(ref) > n // 2
    rows = np.array([x[0] for x in ref])
    t, index = spheres.intersect_closest(jnp.asarray(o), jnp.asarray(d), jnp.full(n, jnp.inf))
    idx = jnp.zeros(n, jnp.int32)
    p = jnp.asarray(o) + t[:, None] * jnp.asarray(d)
    _, normal, uv = spheres.surface(idx, jnp.where(jnp.isfinite(p), p, 0.0))
    du, dv = spheres.tangents(idx, normal)
    assert np.all(np.asarray(index)[rows] == 0)
    np.testing.assert_allclose(np.asarray(t)[rows], [x[1] for x in ref], rtol=1e-5)
    np.testing.assert_allclose(np.asarray(normal)[rows], [x[2] for x in ref], atol=1e-4)
    np.testing.assert_allclose(np.asarray(uv)[rows], [x[3] for x in ref], atol=1e-4)
    np.testing.assert_allclose(np.asarray(du)[rows], [x[4] for x in ref], atol=1e-3)
    np.testing.assert_allclose(np.asarray(dv)[rows], [x[5] for x in ref], atol=1e-3)


def test_sphere_accelerator_combines_triangles_and_spheres():
    """Against a BVH over the same scene with the sphere tessellated: rays that hit a triangle
    get the same face and t, rays that hit the sphere its triangle row and a t within the
    tessellation's radial error."""
    m = sphere((0.0, 0.0, 0.0), 1.0)
    box_v, box_f = _box([-3, -3, -3], [3, 3, 3], inward=True)
    v = np.concatenate([m.vertices, box_v])
    f = np.concatenate([m.faces, box_f + len(m.vertices)])
    is_sphere = np.arange(len(f)) < len(m.faces)
    spheres = Spheres.from_arrays([[0, 0, 0]], [1.0], [np.eye(3)], [0])
    acc = SphereAccelerator.from_triangles(v, f, spheres=spheres, sphere_faces=is_sphere)
    bvh = BVHAccelerator.from_triangles(v, f)
    rng = np.random.default_rng(5)
    n = 2000
    o = rng.uniform(-2.5, 2.5, (n, 3))
    d = rng.normal(size=(n, 3))
    d[: n // 2] = rng.uniform(-0.5, 0.5, (n // 2, 3)) - o[: n // 2]  # half aimed at the sphere
    o, d = jnp.asarray(o, jnp.float32), jnp.asarray(d, jnp.float32)
    t_max = jnp.full((n,), jnp.inf, jnp.float32)
    a, b = acc.intersect_closest(o, d, t_max), bvh.intersect_closest(o, d, t_max)
    a_prim, b_prim = np.asarray(a.prim), np.asarray(b.prim)
    on_box = (a_prim >= len(m.faces)) & (b_prim >= len(m.faces))
    assert on_box.sum() > n // 4
    np.testing.assert_array_equal(a_prim[on_box], b_prim[on_box])
    # (brute force over the 12 box triangles here, a BVH there: t to float32 rounding)
    np.testing.assert_allclose(np.asarray(a.t)[on_box], np.asarray(b.t)[on_box], rtol=1e-6)
    on_sphere = (a_prim == 0) & (b_prim < len(m.faces)) & (b_prim >= 0)
    assert on_sphere.sum() > n // 4
    length = np.linalg.norm(np.asarray(d), axis=1)[on_sphere]
    gap = np.abs(np.asarray(a.t) - np.asarray(b.t))[on_sphere] * length
    assert gap.max() < 2 * SPHERE_MAX_RADIAL_ERROR / np.sqrt(1e-2)  # grazing rays: longer gaps
    np.testing.assert_array_equal(
        np.asarray(acc.intersect_any(o, d, a.t * 0.999)),
        np.zeros(n, bool),  # nothing lies before the closest hit
    )
    np.testing.assert_array_equal(np.asarray(acc.intersect_any(o, d, t_max)), a_prim >= 0)


def test_hits_lie_on_the_true_sphere():
    """Rays from the centre of a loaded sphere mesh (intersected analytically) hit at the
    radius, with the radial normal as geometric and shading normal and the uv of the ray's
    direction, to float32 rounding; the tessellation itself sags by up to
    `SPHERE_MAX_RADIAL_ERROR` of the radius."""
    from radiometria.render._integrators._path import _vertex

    m = sphere((0.5, -0.2, 0.1), 0.8)
    tri = np.arange(len(m.faces))
    scene = _scene([(m.vertices, m.faces, 0, False, -2, -2)], [_medium(1.0, 0.0)],
                   spheres=[((0.5, -0.2, 0.1), 0.8, np.eye(3), tri)])  # fmt: skip
    n = 1000
    w = np.random.default_rng(8).normal(size=(n, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    o = np.broadcast_to(np.array([0.5, -0.2, 0.1]), (n, 3))
    v = _vertex(scene, jnp.asarray(o, jnp.float32), jnp.asarray(w, jnp.float32))
    assert np.all(np.asarray(v.valid))
    np.testing.assert_allclose(np.asarray(v.p, np.float64), o + 0.8 * w, atol=2e-6)
    np.testing.assert_allclose(np.asarray(v.n, np.float64), w, atol=2e-6)
    np.testing.assert_allclose(np.asarray(v.ns, np.float64), w, atol=2e-6)
    phi = np.mod(np.arctan2(w[:, 1], w[:, 0]), 2 * np.pi)
    uv = np.stack([phi / (2 * np.pi), np.arccos(w[:, 2]) / np.pi], -1)
    seam = np.minimum(uv[:, 0], 1 - uv[:, 0]) < 1e-5
    np.testing.assert_allclose(np.asarray(v.uv, np.float64)[~seam], uv[~seam], atol=2e-6)
    np.testing.assert_allclose(np.asarray(v.cos_o), -1.0, atol=1e-6)  # seen from inside


def test_absorbing_true_sphere_seen_from_its_centre():
    """As `test_volpath.test_absorbing_sphere_seen_from_its_centre`, the medium bounded by the
    loader's sphere mesh intersected analytically (medium changes across the true sphere's
    normals): every direction sees exp(-sigma R), with no tolerance for a sag."""
    m = sphere((0.0, 0.0, 0.0), 0.8)
    radius, sigma = 0.8, 1.5
    room = _box([-3, -3, -3], [3, 3, 3], inward=True)
    parts = [(m.vertices, m.faces, 1, False, 0, -1), (*room, 0, True, -2, -2)]
    tri = np.arange(len(m.faces))
    scene = _scene(parts, [_medium(sigma, 0.0)], camera_medium=0,
                   spheres=[((0, 0, 0), radius, np.eye(3), tri)])  # fmt: skip
    assert isinstance(scene.accelerator, SphereAccelerator)
    n = 4096
    w = jax.random.normal(jax.random.key(5), (n, 3), jnp.float32)
    d = w / jnp.linalg.norm(w, axis=-1, keepdims=True)
    out, _ = _estimate(scene, jnp.zeros((n, 3), jnp.float32), d, max_depth=2)
    _check_mean(out, np.exp(-sigma * radius), model=1e-5)


def test_render_with_true_spheres_matches_the_tessellation(tmp_path):
    """A diffuse sphere, a rough-conductor sphere with anisotropic roughness (which needs the
    sphere's dp/du) and a textured sphere on a floor: the image with true spheres and the
    image with their tessellations agree within their noise, pixel by pixel."""
    from radiometria.montecarlo import pixel_z_test
    from radiometria.render import render

    path = tmp_path / "scene.xml"
    path.write_text("""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="4"/></integrator>
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 1, 4.5" target="0, 0.3, 0" up="0, 1, 0"/>
    </transform><film type="hdrfilm"><integer name="width" value="24"/>
    <integer name="height" value="16"/><rfilter type="box"/></film></sensor>
  <emitter type="constant"><rgb name="radiance" value="0.1"/></emitter>
  <shape type="rectangle"><transform name="to_world"><scale x="1.5" y="0.2"/>
      <rotate x="1" angle="90"/><translate y="2.5" z="1"/></transform>
    <emitter type="area"><rgb name="radiance" value="20"/></emitter></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/>
    </transform><bsdf type="diffuse"/></shape>
  <shape type="sphere"><point name="center" value="-1.1, 0.5, 0"/><float name="radius" value="0.5"/>
    <bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
      <transform name="to_uv"><scale x="8" y="4"/></transform></texture></bsdf></shape>
  <shape type="sphere"><point name="center" value="0, 0.5, 0"/><float name="radius" value="0.5"/>
    <transform name="to_world"><rotate x="1" angle="30"/></transform>
    <bsdf type="roughconductor"><float name="alpha_u" value="0.02"/>
      <float name="alpha_v" value="0.5"/></bsdf></shape>
  <shape type="sphere"><point name="center" value="1.1, 0.5, 0"/><float name="radius" value="0.5"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.4, 0.2"/></bsdf></shape>
</scene>""")
    d = load_mitsuba_xml(path)
    assert len(d.spheres) == 3
    runs, spp = 8, 16
    images, variances = {}, {}
    for analytic in (True, False):
        scene, camera, rfilter = compile_scene(d, analytic_spheres=analytic)
        assert isinstance(scene.accelerator, SphereAccelerator) == analytic
        out = np.stack([np.asarray(render(scene, camera=camera, rfilter=rfilter, spp=spp,
                                          seed=s + 10 * analytic, progress=False), np.float64)
                        for s in range(runs)])  # fmt: skip
        images[analytic] = out.mean(axis=0)
        variances[analytic] = out.var(axis=0, ddof=1) * spp  # per-sample variance
    result = pixel_z_test(
        images[True], images[False], variances[False], runs * spp, runs * spp,
        image_variance=variances[True],
    )  # fmt: skip
    assert result.passed, result


@pytest.mark.parametrize(
    "shape",
    [
        '<shape type="sphere"><transform name="to_world"><rotate x="1" angle="40"/></transform>',
        '<shape type="rectangle"><transform name="to_world"><rotate z="1" angle="35"/>'
        '<rotate x="1" angle="-70"/></transform>',
    ],
    ids=["sphere", "rectangle"],
)
def test_anisotropic_roughness_turns_with_dpdu_as_in_mitsuba(tmp_path, shape):
    """An anisotropic rough conductor (alpha_u 0.02, alpha_v 0.5) on a rotated sphere and a
    rotated rectangle: its highlight is stretched along dp/dv as in Mitsuba 3 (any other
    tangent frame fails the per-pixel z-test: 97.8 % of the sphere's pixels passed with
    `coordinate_system(n)`)."""
    pytest.importorskip("mitsuba")
    from tests.render._mitsuba import floor_and_light_xml, perspective_xml, z_test_against_mitsuba

    path = tmp_path / "aniso.xml"
    path.write_text(f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  {perspective_xml("0, 1, 4.5", 35, 32)}
  {floor_and_light_xml(3, 8)}
  {shape}<bsdf type="roughconductor"><float name="alpha_u" value="0.02"/>
    <float name="alpha_v" value="0.5"/></bsdf></shape>
</scene>""")
    result = z_test_against_mitsuba(path, spp=64, ref_spp=2048)
    assert result.passed, result.message


def test_which_spheres_are_intersected_analytically(tmp_path):
    """Emitting spheres are analytic too (their light samples lie on the true sphere, density
    P_e / 4 pi r^2); all spheres of a scene with more than `MAX_ANALYTIC_SPHERES` stay
    tessellated; bad sphere tables are refused with the argument named."""
    from radiometria.render._geometry._sphere import MAX_ANALYTIC_SPHERES

    def scene_xml(n_plain, emitter=True):
        plain = "".join(
            f'<shape type="sphere"><point name="center" value="{3 * i}, 0, 0"/>'
            '<float name="radius" value="0.5"/></shape>'
            for i in range(n_plain)
        )
        lit = (
            (
                '<shape type="sphere"><point name="center" value="0, 5, 0"/><emitter type="area">'
                '<rgb name="radiance" value="1"/></emitter></shape>'
            )
            if emitter
            else ""
        )
        path = tmp_path / f"s{n_plain}.xml"
        path.write_text(f'<scene version="3.0.0">{plain}{lit}</scene>')
        return load_mitsuba_xml(path)

    d = scene_xml(2)
    scene, _, _ = compile_scene(d)
    assert isinstance(scene.accelerator, SphereAccelerator)
    assert scene.spheres.center.shape == (3, 3)
    lit = np.asarray(d.face_emitter) >= 0
    assert np.all(np.asarray(scene.face_sphere)[lit] == 2)
    pdf = np.asarray(scene.light.light_pdf_area)[lit]
    np.testing.assert_allclose(pdf, 1.0 / (4.0 * np.pi), rtol=1e-6)  # the only light, r = 1
    many, _, _ = compile_scene(scene_xml(MAX_ANALYTIC_SPHERES + 1, emitter=False))
    assert many.spheres is None and not isinstance(many.accelerator, SphereAccelerator)
    with pytest.raises(ValueError, match=r"spheres\[0\].*distinct indices"):
        m = sphere()
        _scene([(m.vertices, m.faces, 0, False, -2, -2)], [_medium(1.0, 0.0)],
               spheres=[((0, 0, 0), 1.0, np.eye(3), [0, 0])])  # fmt: skip
    with pytest.raises(ValueError, match="radii must be positive"):
        Spheres.from_arrays([[0, 0, 0]], [0.0], [np.eye(3)], [0])


@pytest.mark.slow
@pytest.mark.parametrize("ours", ["path", "bdpt"])
def test_textured_sphere_light_passes_the_z_test_against_mitsuba(tmp_path, ours):
    """A sphere light whose radiance is one colour on each half (phi < pi, phi > pi: a
    checkerboard stretched over v) over a floor, rotated so that the floor sees both halves:
    its light samples are points on the true sphere (by area: a textured light has no cone)
    with the uv of the rotated frame, and bdpt's light paths start there, against Mitsuba's
    analytic sphere light (the uv of an unrotated frame fails)."""
    from radiometria.render import BDPT
    from tests.render._mitsuba import perspective_xml, z_test_against_mitsuba

    path = tmp_path / "sphere_light.xml"
    path.write_text(f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  {perspective_xml("0, 1.2, 3.2", 55, 16)}
  <shape type="rectangle"><transform name="to_world"><scale value="3"/>
    <rotate x="1" angle="-90"/><translate y="-0.6"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.6"/></bsdf></shape>
  <shape type="sphere"><float name="radius" value="0.4"/>
    <transform name="to_world"><rotate x="1" angle="60"/><translate y="0.3"/></transform>
    <emitter type="area"><texture type="checkerboard" name="radiance">
      <rgb name="color0" value="0.95, 0.3, 0.1"/><rgb name="color1" value="0.1, 0.4, 0.95"/>
      <transform name="to_uv"><scale x="1" y="0.5"/></transform></texture></emitter></shape>
</scene>""")
    kwargs = {"integrator": BDPT(max_depth=3)} if ours == "bdpt" else {}
    res = z_test_against_mitsuba(path, spp=64, ref_spp=1024, **kwargs)
    assert res.passed, res.message
