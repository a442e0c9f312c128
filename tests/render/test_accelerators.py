"""Accelerators: BVH and brute force give the brute-force reference's hits; the choice by size."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from radiometria.render._accelerators import (
    ACCELERATORS,
    BRUTE_FORCE_MAX_TRIANGLES,
    AbstractAccelerator,
    BruteForceAccelerator,
    BVHAccelerator,
    build_accelerator,
)
from radiometria.render._geometry import (
    JaxTraversal,
    TriangleMesh,
    intersect_brute_force_any,
    intersect_brute_force_closest,
)


def _soup(rng, n_tri):
    """Random overlapping triangles in [-1, 1]^3, float64 vertices."""
    centre = rng.uniform(-1, 1, (n_tri, 1, 3))
    size = rng.uniform(0.05, 0.5, (n_tri, 1, 1))
    v = (centre + size * rng.normal(size=(n_tri, 3, 3))).reshape(-1, 3)
    return v, np.arange(3 * n_tri, dtype=np.int32).reshape(-1, 3)


@pytest.mark.parametrize("dtype", [jnp.float32, jnp.float64])
@pytest.mark.parametrize("kind", sorted(ACCELERATORS))
def test_accelerators_match_the_brute_force_reference_under_jit(kind, dtype):
    rng = np.random.default_rng(7)
    v, f = _soup(rng, 200)
    o = rng.uniform(-1.6, 1.6, (512, 3))
    d = rng.normal(size=(512, 3))
    tmax = np.where(rng.uniform(size=512) < 0.3, rng.uniform(0.5, 3, 512), np.inf)
    o, d, tmax = (x.astype(np.dtype(dtype)) for x in (o, d, tmax))
    acc = build_accelerator(v, f, kind=kind, dtype=dtype)
    assert isinstance(acc, ACCELERATORS[kind]) and isinstance(acc, AbstractAccelerator)

    hit = eqx.filter_jit(lambda a, *r: a.intersect_closest(*r))(acc, o, d, tmax)
    occluded = eqx.filter_jit(lambda a, *r: a.intersect_any(*r))(acc, o, d, tmax)

    mesh = TriangleMesh(jnp.asarray(v, dtype), f)
    ref = intersect_brute_force_closest(mesh, o, d, tmax, backend="jax")
    ref_any = intersect_brute_force_any(mesh, o, d, tmax, backend="jax")
    rtol = 1e-6 if dtype == jnp.float32 else 1e-12
    assert hit.t.dtype == jnp.dtype(dtype) and hit.prim.dtype == jnp.int32
    np.testing.assert_array_equal(np.asarray(hit.prim), np.asarray(ref.prim))
    found = np.asarray(ref.prim) >= 0
    assert 0.1 < found.mean() < 0.95
    # `t` to rtol relative to max(t, 1), as in test_intersect: a small `t` carries the absolute
    # rounding of coordinates of size 1, whichever fusion computes it
    t, t_ref = np.asarray(hit.t)[found], np.asarray(ref.t)[found]
    np.testing.assert_allclose(t, t_ref, rtol=rtol, atol=rtol)
    assert np.all(np.isinf(np.asarray(hit.t)[~found]))
    np.testing.assert_allclose(np.asarray(hit.b1), np.asarray(ref.b1), atol=10 * rtol)
    np.testing.assert_allclose(np.asarray(hit.b2), np.asarray(ref.b2), atol=10 * rtol)
    np.testing.assert_array_equal(np.asarray(occluded), np.asarray(ref_any))
    np.testing.assert_array_equal(np.asarray(occluded), found)


def test_build_accelerator_picks_brute_force_up_to_the_threshold():
    rng = np.random.default_rng(3)
    v, f = _soup(rng, BRUTE_FORCE_MAX_TRIANGLES + 1)
    small = build_accelerator(v, f[:BRUTE_FORCE_MAX_TRIANGLES])
    large = build_accelerator(v, f)
    assert BRUTE_FORCE_MAX_TRIANGLES == 64
    assert isinstance(small, BruteForceAccelerator) and isinstance(large, BVHAccelerator)
    assert isinstance(build_accelerator(v, f, kind="brute_force"), BruteForceAccelerator)
    assert isinstance(build_accelerator(v[:9], f[:3], kind="bvh"), BVHAccelerator)
    # float32 by default, as the renderer stores its scenes
    assert small.mesh.vertices.dtype == jnp.float32 and large.bvh.triangles.dtype == jnp.float32


def test_build_accelerator_rejects_a_bad_kind_and_bad_arrays():
    v, f = _soup(np.random.default_rng(0), 4)
    with pytest.raises(ValueError, match="accelerator 'octree'.*'auto', 'bvh', 'brute_force'"):
        build_accelerator(v, f, kind="octree")
    with pytest.raises(ValueError, match="vertices"):
        build_accelerator(v[:, :2], f)
    with pytest.raises(ValueError, match="faces"):
        build_accelerator(v, f.astype(float))


def test_accelerators_take_a_backend_name_or_object():
    rng = np.random.default_rng(5)
    v, f = _soup(rng, 100)
    o, d = rng.uniform(-1.6, 1.6, (256, 3)), rng.normal(size=(256, 3))
    tmax = np.full(256, np.inf)
    base = BVHAccelerator.from_triangles(v, f, dtype=jnp.float64)
    by_name = BVHAccelerator(base.bvh, backend="jax").intersect_closest(o, d, tmax)
    by_object = BVHAccelerator(base.bvh, backend=JaxTraversal()).intersect_closest(o, d, tmax)
    for a, b in zip(jax.tree.leaves(by_name), jax.tree.leaves(by_object), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    with pytest.raises(ValueError, match="backend 'embree'"):
        BruteForceAccelerator(TriangleMesh(jnp.asarray(v), f), backend="embree")
