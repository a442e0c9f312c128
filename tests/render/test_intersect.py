"""Ray-triangle intersection: BVH traversal against brute force, watertightness, any-hit."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from radiometria.render import (
    Hit,
    TriangleMesh,
    build_bvh,
    icosphere,
    intersect_any,
    intersect_brute_force_any,
    intersect_brute_force_closest,
    intersect_closest,
    sample_triangle_point,
    triangle_areas,
    triangle_normals,
)


def _soup(rng, n_tri, dtype):
    """Random triangles of random sizes in [-1, 1]^3 (they overlap and intersect)."""
    centre = rng.uniform(-1, 1, (n_tri, 1, 3))
    size = rng.uniform(0.02, 0.4, (n_tri, 1, 1))
    v = (centre + size * rng.normal(size=(n_tri, 3, 3))).reshape(-1, 3).astype(dtype)
    return v, np.arange(3 * n_tri, dtype=np.int32).reshape(-1, 3)


def _rays(rng, n, dtype, spread=1.6):
    o = rng.uniform(-spread, spread, (n, 3)).astype(dtype)
    d = rng.normal(size=(n, 3)).astype(dtype)
    return o, d


def _assert_same_hits(h: Hit, ref: Hit, rtol: float):
    """Same triangles; `t` within `rtol` relative to max(t, 1) (the scene's size is ~1: a small
    `t` carries the absolute rounding of coordinates of size 1, whichever fusion computes it)."""
    np.testing.assert_array_equal(np.asarray(h.prim), np.asarray(ref.prim))
    hit = np.asarray(ref.prim) >= 0
    np.testing.assert_allclose(np.asarray(h.t)[hit], np.asarray(ref.t)[hit], rtol=rtol, atol=rtol)
    assert np.all(np.isinf(np.asarray(h.t)[~hit]))
    np.testing.assert_allclose(np.asarray(h.b1)[hit], np.asarray(ref.b1)[hit], atol=10 * rtol)
    np.testing.assert_allclose(np.asarray(h.b2)[hit], np.asarray(ref.b2)[hit], atol=10 * rtol)


# One ray count everywhere, and meshes whose BVHs fall in one size bucket (1280 triangles,
# <= 512 nodes), so the eager calls share compiled traversals across tests.
N_RAYS = 1024
N_SOUP = 1280  # = icosphere(3)


def _chunked(fn, o, d, *args):
    """`fn` on batches of `N_RAYS` rays (one compiled shape), results concatenated."""
    parts = [fn(o[i : i + N_RAYS], d[i : i + N_RAYS], *args) for i in range(0, len(o), N_RAYS)]
    return jax.tree.map(lambda *x: np.concatenate([np.asarray(y) for y in x]), *parts)


@pytest.fixture(scope="module")
def scenes():
    """Random triangle soups (float32, float64) and a sphere, with their BVHs and rays."""
    out = {}
    for name, dtype in (("soup32", np.float32), ("soup64", np.float64), ("sphere32", np.float32)):
        rng = np.random.default_rng(len(out) + 1)
        if name.startswith("soup"):
            v, f = _soup(rng, N_SOUP, dtype)
        else:
            v, f = icosphere(3)
            v = v.astype(dtype)
        o, d = _rays(rng, N_RAYS, dtype)
        tmax = np.where(rng.uniform(size=N_RAYS) < 0.3, rng.uniform(0.5, 3, N_RAYS), np.inf)
        out[name] = (v, f, build_bvh(v, f), o, d, tmax.astype(dtype))
    return out


@pytest.mark.parametrize("backend", ["native", "jax"])
@pytest.mark.parametrize("name", ["soup32", "soup64", "sphere32"])
def test_intersect_closest_matches_brute_force(scenes, name, backend):
    v, f, bvh, o, d, tmax = scenes[name]
    dtype = v.dtype
    h = intersect_closest(bvh, o, d, tmax, backend=backend)
    ref = intersect_brute_force_closest(TriangleMesh(v, f), o, d, tmax)
    assert h.t.dtype == jnp.dtype(dtype) and h.prim.dtype == jnp.int32
    assert 0.1 < float(np.mean(np.asarray(ref.prim) >= 0)) < 0.95
    _assert_same_hits(h, ref, rtol=1e-6 if dtype == np.float32 else 1e-12)
    # the hit point from the barycentrics lies on the ray
    hit = np.asarray(h.prim) >= 0
    tri = v[f[np.asarray(h.prim)[hit]]].astype(np.float64)
    b1, b2 = np.asarray(h.b1)[hit, None], np.asarray(h.b2)[hit, None]
    p = (1 - b1 - b2) * tri[:, 0] + b1 * tri[:, 1] + b2 * tri[:, 2]
    q = o[hit] + np.asarray(h.t)[hit, None] * d[hit]
    np.testing.assert_allclose(p, q, atol=1e-4 if dtype == np.float32 else 1e-10)


@pytest.mark.parametrize("name", ["soup32", "soup64", "sphere32"])
def test_native_brute_force_matches_the_jax_loop(scenes, name):
    """The two brute-force backends: same triangles, `t` and barycentrics to rounding, same
    occlusion; also under vmap (a batch of ray batches)."""
    v, f, _, o, d, tmax = scenes[name]
    mesh = TriangleMesh(v, f)
    native = intersect_brute_force_closest(mesh, o, d, tmax, backend="native")
    ref = intersect_brute_force_closest(mesh, o, d, tmax, backend="jax")
    _assert_same_hits(native, ref, rtol=1e-6 if v.dtype == np.float32 else 1e-12)
    np.testing.assert_array_equal(
        np.asarray(intersect_brute_force_any(mesh, o, d, tmax, backend="native")),
        np.asarray(intersect_brute_force_any(mesh, o, d, tmax, backend="jax")),
    )
    batched = jax.vmap(
        lambda oo, dd, tt: intersect_brute_force_closest(mesh, oo, dd, tt, backend="native").prim
    )(o.reshape(4, -1, 3), d.reshape(4, -1, 3), tmax.reshape(4, -1))
    np.testing.assert_array_equal(np.asarray(batched).ravel(), np.asarray(ref.prim))


@pytest.mark.parametrize("backend", ["native", "jax"])
def test_brute_force_on_partial_blocks_and_an_empty_mesh(scenes, backend):
    """Ray counts that leave the native kernel's blocks (256 rays, axis classes padded to 16
    lanes) partly filled give the hits of full batches; a mesh of no triangles is missed by
    every ray (t = inf, prim = -1, zero barycentrics)."""
    v, f, _, o, d, tmax = scenes["soup32"]
    mesh = TriangleMesh(v, f)
    full = intersect_brute_force_closest(mesh, o, d, tmax, backend=backend)
    for n in (1, 17, 257):
        part = intersect_brute_force_closest(mesh, o[:n], d[:n], tmax[:n], backend=backend)
        _assert_same_hits(part, jax.tree.map(lambda x, n=n: x[:n], full), rtol=0)
    empty = TriangleMesh(np.zeros((0, 3), v.dtype), np.zeros((0, 3), np.int32))
    miss = intersect_brute_force_closest(empty, o[:17], d[:17], tmax[:17], backend=backend)
    np.testing.assert_array_equal(np.asarray(miss.prim), -1)
    np.testing.assert_array_equal(np.asarray(miss.t), np.inf)
    np.testing.assert_array_equal(np.asarray(miss.b1), 0)
    np.testing.assert_array_equal(np.asarray(miss.b2), 0)
    assert not np.any(np.asarray(intersect_brute_force_any(empty, o[:17], d[:17], backend=backend)))


def test_brute_force_accepts_bvh_and_mesh(scenes):
    v, f, bvh, o, d, tmax = scenes["soup64"]
    a = intersect_brute_force_closest(bvh, o, d, tmax)
    b = intersect_brute_force_closest(TriangleMesh(v, f), o, d, tmax)
    _assert_same_hits(a, b, rtol=0)
    np.testing.assert_array_equal(
        np.asarray(intersect_brute_force_any(bvh, o, d, tmax)), np.asarray(b.prim) >= 0
    )


@pytest.mark.parametrize("backend", ["native", "jax"])
@pytest.mark.parametrize("name", ["soup32", "soup64"])
def test_intersect_any_consistent_with_closest(scenes, name, backend):
    v, f, bvh, o, d, _ = scenes[name]
    tmax = np.random.default_rng(4).uniform(0.1, 3.0, N_RAYS).astype(v.dtype)
    closest = intersect_closest(bvh, o, d, np.full(N_RAYS, np.inf, v.dtype), backend=backend)
    occluded = np.asarray(intersect_any(bvh, o, d, tmax, backend=backend))
    expect = np.asarray(closest.t) < tmax
    np.testing.assert_array_equal(occluded, expect)
    assert 0.1 < expect.mean() < 0.9


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_watertight_rays_through_edges_and_vertices_never_miss(dtype):
    """Rays aimed exactly at shared vertices and edge points of a closed mesh always hit it."""
    v, f = icosphere(3)
    rng = np.random.default_rng(5)
    rot = np.linalg.qr(rng.normal(size=(3, 3)))[0]  # avoid axis-aligned special cases
    centre = np.asarray([0.1, -0.2, 0.05], dtype)
    v = (v @ rot.T * 1.3 + centre).astype(dtype)
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    edges = np.unique(np.sort(e, 1), axis=0)
    w = rng.uniform(0, 1, (len(edges), 1)).astype(dtype)
    targets = np.concatenate(
        [
            v,  # vertices (5 or 6 triangles meet)
            ((v[edges[:, 0]] + v[edges[:, 1]]) * dtype(0.5)).astype(dtype),  # edge midpoints
            (v[edges[:, 0]] * w + v[edges[:, 1]] * (1 - w)).astype(dtype),  # points on edges
        ]
    )
    mesh, bvh = TriangleMesh(v, f), build_bvh(v, f)
    inside = (centre, centre + np.asarray([0.3, 0.2, -0.1], dtype))
    o = np.concatenate([np.broadcast_to(c, targets.shape) for c in inside]).astype(dtype)
    d = (np.concatenate([targets, targets]) - o).astype(dtype)
    # and from outside, through the same points towards the centre
    o_out = (targets + (targets - centre) * dtype(2.0)).astype(dtype)
    o = np.concatenate([o, o_out])
    d = np.concatenate([d, (targets - o_out).astype(dtype)])
    for backend in ("native", "jax"):
        brute = _chunked(
            lambda oo, dd, b=backend: intersect_brute_force_closest(mesh, oo, dd, backend=b).prim,
            o,
            d,
        )
        assert np.all(brute >= 0), backend
    # the native traversal in both dtypes, the JAX traversal in float32 (float64: same code)
    for backend in ("native", "jax") if dtype == np.float32 else ("native",):
        hit = _chunked(lambda oo, dd, b=backend: intersect_closest(bvh, oo, dd, backend=b), o, d)
        assert np.all(np.asarray(hit.prim) >= 0), backend
        np.testing.assert_allclose(np.asarray(hit.t)[-len(targets) :], 1.0, rtol=1e-3)


@pytest.mark.parametrize("backend", ["native", "jax"])
def test_intersect_closest_jit_and_vmap(scenes, backend):
    v, f, bvh, o, d, tmax = scenes["soup32"]
    eager = intersect_closest(bvh, o, d, tmax, backend=backend)
    jitted = eqx.filter_jit(intersect_closest)(bvh, o, d, tmax, backend=backend)
    _assert_same_hits(jitted, eager, rtol=0)
    batched = jax.vmap(lambda oo, dd, tt: intersect_closest(bvh, oo, dd, tt, backend=backend).prim)(
        o.reshape(4, -1, 3), d.reshape(4, -1, 3), tmax.reshape(4, -1)
    )
    np.testing.assert_array_equal(np.asarray(batched).ravel(), np.asarray(eager.prim))


@pytest.mark.parametrize("backend", ["native", "jax"])
def test_t_min_and_t_max_are_exclusive_bounds(backend):
    v = np.array([[0, 0, 1], [1, 0, 1], [0, 1, 1.0]])
    f = np.array([[0, 1, 2]], np.int32)
    bvh = build_bvh(v, f)
    o = np.array([[0.2, 0.2, 0.0]] * 3)
    d = np.array([[0, 0, 1.0]] * 3)
    h = intersect_closest(bvh, o, d, np.array([2.0, 1.0, 0.5]), backend=backend)
    np.testing.assert_array_equal(np.asarray(h.prim), [0, -1, -1])
    np.testing.assert_allclose(np.asarray(h.t)[0], 1.0)
    np.testing.assert_allclose([float(h.b1[0]), float(h.b2[0])], [0.2, 0.2])
    h = intersect_closest(
        bvh, o, d, np.array([2.0, 2.0, 2.0]), t_min=np.array([0.5, 1.0, 1.5]), backend=backend
    )
    np.testing.assert_array_equal(np.asarray(h.prim), [0, -1, -1])
    np.testing.assert_array_equal(
        np.asarray(intersect_any(bvh, o, d, np.array([2, 1, 0.5]), backend=backend)), [1, 0, 0]
    )


def test_intersect_rejects_bad_shapes():
    bvh = build_bvh(np.eye(3), np.array([[0, 1, 2]]))
    with pytest.raises(ValueError, match="origins"):
        intersect_closest(bvh, np.zeros((4, 2)), np.zeros((4, 2)))
    with pytest.raises(ValueError, match="directions"):
        intersect_closest(bvh, np.zeros((4, 3)), np.zeros((5, 3)))
    with pytest.raises(ValueError, match="t_max"):
        intersect_closest(bvh, np.zeros((4, 3)), np.ones((4, 3)), np.ones(3))
    with pytest.raises(TypeError, match="BVH"):
        intersect_closest(
            TriangleMesh(np.eye(3), np.array([[0, 1, 2]])), np.zeros((1, 3)), np.ones((1, 3))
        )


def test_triangle_helpers():
    v = jnp.array([[0.0, 0, 0], [2, 0, 0], [0, 3, 0], [1, 1, 1]])
    f = jnp.array([[0, 1, 2], [0, 0, 3]], dtype=jnp.int32)

    @jax.jit
    def run(v, u):
        areas, normals = triangle_areas(v, f), triangle_normals(v, f)
        grad = jax.grad(lambda x: jnp.sum(triangle_areas(x, f) + triangle_normals(x, f).sum()))(v)
        return (
            areas,
            normals,
            grad,
            sample_triangle_point(v, f, jnp.zeros(u.shape[0], jnp.int32), u),
        )

    u = jax.random.uniform(jax.random.key(0), (20000, 2), dtype=jnp.float64)
    areas, normals, grad, (p, n, b) = run(v, u)
    np.testing.assert_allclose(np.asarray(areas), [3.0, 0.0])
    np.testing.assert_allclose(np.asarray(normals), [[0, 0, 1], [0, 0, 0]])
    assert np.all(np.isfinite(np.asarray(grad)))
    np.testing.assert_allclose(np.asarray(n), np.tile([0.0, 0, 1], (20000, 1)))
    assert np.all(np.asarray(b) >= 0) and np.all(np.asarray(b).sum(1) <= 1)
    # uniform by area: the mean is the centroid, and barycentrics reproduce the points
    np.testing.assert_allclose(np.asarray(p).mean(0), [2 / 3, 1.0, 0.0], atol=0.02)
    b1, b2 = np.asarray(b[:, :1]), np.asarray(b[:, 1:])
    np.testing.assert_allclose(np.asarray(p), b1 * [2, 0, 0] + b2 * [0, 3, 0], atol=1e-12)
