"""BVH build: structure invariants, edge cases, and agreement with brute force."""

import numpy as np
import pytest

from radiometria.render import (
    BVH,
    TriangleMesh,
    build_bvh,
    icosphere,
    intersect_brute_force_closest,
    intersect_closest,
    intersect_closest as _intersect_closest,
)
from radiometria.render._geometry._bvh import EMPTY


def _leaves(bvh: BVH):
    """(start, count) of every leaf, and the depth of the tree, by walking it in NumPy."""
    ch = np.asarray(bvh.node_children)
    boxes = np.asarray(bvh.node_boxes)
    leaves, depth, stack = [], 0, [(0, 1)]
    parent_box = {}
    while stack:
        node, level = stack.pop()
        depth = max(depth, level)
        for side in (0, 1):
            c = int(ch[node, side])
            box = boxes[node, 6 * side : 6 * side + 6]
            if c == EMPTY:
                continue
            if c >= 0:
                parent_box[c] = box
                stack.append((c, level + 1))
            else:
                code = ~c
                leaves.append((code >> 3, (code & 7) + 1, box))
    return leaves, depth


@pytest.mark.parametrize("max_leaf_size", [1, 4])
def test_build_bvh_invariants(max_leaf_size):
    rng = np.random.default_rng(0)
    v, f = icosphere(4)  # 5120 triangles, > 16: both the binned and the sweep splits run
    v = v * rng.uniform(0.5, 2.0, 3)
    bvh = build_bvh(v, f, max_leaf_size=max_leaf_size)
    leaves, depth = _leaves(bvh)
    starts = np.concatenate([np.arange(s, s + c) for s, c, _ in leaves])
    # every triangle is in exactly one leaf, leaves are small, the stack is deep enough
    np.testing.assert_array_equal(np.sort(starts), np.arange(len(f)))
    assert max(c for _, c, _ in leaves) <= max_leaf_size
    assert depth <= bvh.stack_size
    np.testing.assert_array_equal(np.sort(np.asarray(bvh.prim_ids)), np.arange(len(f)))
    # the reordered triangles are the original ones, and each leaf box bounds its triangles
    tri = np.asarray(bvh.triangles).reshape(-1, 3, 3)
    np.testing.assert_array_equal(tri, v[f[np.asarray(bvh.prim_ids)]])
    for s, c, box in leaves:
        pts = tri[s : s + c].reshape(-1, 3)
        assert np.all(pts >= box[:3]) and np.all(pts <= box[3:])
    np.testing.assert_allclose(np.asarray(bvh.bounds), [v.min(0), v.max(0)])
    # a good tree is shallow: about log2(f / leaf) levels
    assert depth <= 2 * np.log2(len(f)) + 2


@pytest.mark.parametrize("backend", ["native", "jax"])
def test_build_bvh_edge_cases(backend):
    def intersect_closest(*args):
        return _intersect_closest(*args, backend=backend)

    # empty mesh: every ray misses
    bvh = build_bvh(np.zeros((0, 3)), np.zeros((0, 3), np.int32))
    o, d = np.zeros((4, 3)), np.ones((4, 3))
    assert np.all(np.asarray(intersect_closest(bvh, o, d).prim) == -1)
    # one triangle, and many coincident triangles (all centroids equal: median splits)
    v = np.array([[0, 0, 1.0], [1, 0, 1], [0, 1, 1]])
    for faces in (np.array([[0, 1, 2]]), np.tile([[0, 1, 2]], (37, 1))):
        bvh = build_bvh(v, faces)
        leaves, _ = _leaves(bvh)
        assert sum(c for _, c, _ in leaves) == len(faces)
        h = intersect_closest(bvh, np.array([[0.2, 0.2, 0.0]] * 4), np.array([[0, 0, 1.0]] * 4))
        np.testing.assert_array_equal(np.asarray(h.prim), 0)  # ties: the lowest face index
    # degenerate triangles are kept and never hit
    v = np.array([[0, 0, 1.0], [1, 0, 1], [0, 1, 1], [2, 2, 1]])
    bvh = build_bvh(v, np.array([[0, 1, 1], [0, 1, 2], [0, 0, 0]]))
    h = intersect_closest(bvh, np.array([[0.5, 0.0, 0.0]] * 4), np.array([[0, 0, 1.0]] * 4))
    assert np.all(np.asarray(h.prim) == 1)


def test_build_bvh_rejects_bad_input():
    v, f = icosphere(0)
    with pytest.raises(ValueError, match="vertices"):
        build_bvh(v[:, :2], f)
    with pytest.raises(ValueError, match="faces"):
        build_bvh(v, f.astype(float))
    with pytest.raises(ValueError, match="faces"):
        build_bvh(v, f + 100)
    with pytest.raises(ValueError, match="max_leaf_size"):
        build_bvh(v, f, max_leaf_size=9)
    with pytest.raises(ValueError, match="finite"):
        build_bvh(np.where(v > 0.5, np.nan, v), f)


def test_bvh_on_a_large_mesh_matches_brute_force_on_sampled_rays():
    """20k triangles, rays aimed at random triangles (all hit), plus random rays."""
    v, f = icosphere(5)
    bvh = build_bvh(v, f)
    rng = np.random.default_rng(7)
    o = rng.uniform(-2, 2, (1024, 3))
    target = v[f[rng.integers(0, len(f), 1024)]].mean(1)
    d = np.where(rng.uniform(size=(1024, 1)) < 0.5, target - o, rng.normal(size=(1024, 3)))
    h = intersect_closest(bvh, o, d)
    ref = intersect_brute_force_closest(TriangleMesh(v, f), o, d)
    np.testing.assert_array_equal(np.asarray(h.prim), np.asarray(ref.prim))
    np.testing.assert_allclose(np.asarray(h.t), np.asarray(ref.t), rtol=1e-12)
