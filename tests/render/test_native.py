"""The native CPU BVH traversal (XLA FFI): availability, fallback, vmap over BVHs, grad."""

import os
import shutil
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from radiometria.render import (
    build_bvh,
    icosphere,
    intersect_any,
    intersect_closest,
    native_status,
)
from radiometria.render._geometry import (
    TRAVERSAL_BACKENDS,
    JaxTraversal,
    NativeCPUTraversal,
    resolve_backend,
)

_HAS_COMPILER = any(shutil.which(c) for c in (os.environ.get("CXX") or "c++", "g++", "clang++"))


def _rays(n, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(-1.5, 1.5, (n, 3)), rng.normal(size=(n, 3))


@pytest.mark.skipif(not _HAS_COMPILER, reason="no C++ compiler: the JAX traversal is used")
def test_native_kernel_builds_and_loads_where_a_compiler_exists():
    ok, reason = native_status()
    assert ok, reason


def test_vmap_over_bvhs_runs_one_query_per_bvh():
    """A batch of BVHs (same tree shape: the mesh scaled) gives each batch element its own hits."""
    v, f = icosphere(2)
    scales = (0.5, 1.0, 1.4)
    bvhs = [build_bvh(v * s, f) for s in scales]
    batched = jax.tree.map(lambda *x: jnp.stack(x), *bvhs)
    o, d = _rays(256)
    t = jax.vmap(lambda b: intersect_closest(b, o, d, backend="native").t)(batched)
    for k, bvh in enumerate(bvhs):
        ref = intersect_closest(bvh, o, d, backend="jax")
        np.testing.assert_allclose(np.asarray(t[k]), np.asarray(ref.t), rtol=1e-12)
    # and nested vmap over ray batches: (2, 2) batches of 64 rays
    prim = jax.vmap(jax.vmap(lambda oo, dd: intersect_any(bvhs[1], oo, dd, backend="native")))(
        o.reshape(2, 2, 64, 3), d.reshape(2, 2, 64, 3)
    )
    ref = intersect_closest(bvhs[1], o, d, backend="jax").prim >= 0
    np.testing.assert_array_equal(np.asarray(prim).ravel(), np.asarray(ref))


def test_grad_through_a_query_is_zero_and_the_hit_point_carries_the_derivative():
    """The traversal is piecewise constant (stop_gradient); the hit point recomputed from the
    barycentrics has the derivative of the ray-plane intersection: for a ray along +z through
    the plane z = c, dp_z / dc = 1."""
    v = np.array([[-1.0, -1, 1], [1, -1, 1], [0, 1, 1]])
    f = np.array([[0, 1, 2]], np.int32)
    o = np.array([[0.1, -0.2, 0.0]])
    d = np.array([[0.0, 0.0, 1.0]])

    def hit_z(c):
        verts = jnp.asarray(v).at[:, 2].set(c)
        h = intersect_closest(build_bvh(v, f), o, d, backend="native")
        p = verts[f[0]]
        b1, b2 = h.b1[0], h.b2[0]
        point = (1 - b1 - b2) * p[0] + b1 * p[1] + b2 * p[2]
        return point[2], h.t[0]

    (z, t), (dz, dt) = jax.jvp(hit_z, (1.0,), (1.0,))
    assert float(z) == pytest.approx(1.0) and float(t) == pytest.approx(1.0)
    assert float(dz) == pytest.approx(1.0) and float(dt) == 0.0
    g = jax.grad(lambda oo: jnp.sum(intersect_closest(build_bvh(v, f), oo, d).t))(o)
    np.testing.assert_array_equal(np.asarray(g), 0.0)


def test_bad_backend_is_rejected():
    bvh = build_bvh(*icosphere(0))
    with pytest.raises(
        ValueError, match="backend 'embree'; valid values are: 'auto', 'native', 'jax'"
    ):
        intersect_closest(bvh, np.zeros((1, 3)), np.ones((1, 3)), backend="embree")


def test_backends_are_objects_chosen_by_name_or_passed_directly():
    """`TRAVERSAL_BACKENDS` maps names to back ends in order of preference; a back-end object
    gives the hits of its name, and `"auto"` on the CPU is the native kernel where it loads."""
    bvh = build_bvh(*icosphere(1))
    o, d = _rays(128)
    assert list(TRAVERSAL_BACKENDS) == ["native", "jax"]
    assert isinstance(resolve_backend("jax"), JaxTraversal)
    assert resolve_backend(TRAVERSAL_BACKENDS["jax"]) is TRAVERSAL_BACKENDS["jax"]
    hash(JaxTraversal())  # a static jit argument
    for name, backend in TRAVERSAL_BACKENDS.items():
        if not backend.available()[0]:
            continue
        a = intersect_closest(bvh, o, d, backend=name)
        b = intersect_closest(bvh, o, d, backend=backend)
        for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b), strict=True):
            np.testing.assert_array_equal(np.asarray(x), np.asarray(y))
    if jax.default_backend() == "cpu" and native_status()[0]:
        assert isinstance(resolve_backend("auto"), NativeCPUTraversal)


def _run(code: str, **env) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", code],
        env={**os.environ, "JAX_PLATFORMS": "cpu", **env},
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


_PROBE = """
import numpy as np
from radiometria.render import build_bvh, icosphere, intersect_closest, native_status
from radiometria.render._geometry._registry import TRAVERSAL_BACKENDS, resolve_backend
bvh = build_bvh(*icosphere(1))
h = intersect_closest(bvh, np.zeros((2, 3)), np.array([[0, 0, 1.0], [1, 0, 0]]))
name = {b: k for k, b in TRAVERSAL_BACKENDS.items()}[resolve_backend("auto")]
print(native_status(), name, np.asarray(h.prim >= 0).tolist())
"""


def test_disabled_native_falls_back_to_the_jax_traversal():
    out = _run(_PROBE, RADIOMETRIA_NATIVE="0")
    assert "(False, 'disabled by RADIOMETRIA_NATIVE=0') jax [True, True]" in out.stdout, out.stderr
    asked = _run(_PROBE.replace('"auto"', '"native"'), RADIOMETRIA_NATIVE="0")
    assert asked.returncode != 0
    assert "native BVH traversal is unavailable: disabled by RADIOMETRIA_NATIVE=0" in asked.stderr


@pytest.mark.skipif(not _HAS_COMPILER, reason="no C++ compiler")
def test_fresh_cache_compiles_the_kernel_atomically(tmp_path):
    out = _run(_PROBE, RADIOMETRIA_CACHE_DIR=str(tmp_path))
    assert "(True, 'compiled and loaded') native [True, True]" in out.stdout, out.stderr
    # the probe's queries are float32: only that library is built
    files = sorted(p.name for p in tmp_path.iterdir())
    assert len(files) == 1 and files[0].startswith("bvh_traverse-f32-"), files
    assert files[0].endswith(".so")


_PREBUILD_PROBE = (
    """
import threading
from radiometria import _native_build
_native_build.prebuild()
started = [t.name for t in threading.enumerate()].count("radiometria-native-build")
_native_build.prebuild()  # once per process: no second build
again = [t.name for t in threading.enumerate()].count("radiometria-native-build")
"""
    + _PROBE.split("\n", 1)[1]
    + """
print("threads", started, again)
"""
)


@pytest.mark.skipif(not _HAS_COMPILER, reason="no C++ compiler")
def test_prebuild_compiles_the_float32_library_in_the_background_and_load_waits(tmp_path):
    """`prebuild` starts one build thread, of the float32 library (what a render needs);
    `_load` takes it and float32 queries run; a float64 query builds the float64 library then.
    Each library holds its own precision's four handlers."""
    code = _PREBUILD_PROBE + (
        "import jax\n"
        "jax.config.update('jax_enable_x64', True)\n"
        "h64 = intersect_closest(build_bvh(*icosphere(1), dtype=np.float64), np.zeros((2, 3)),\n"
        "                        np.array([[0, 0, 1.0], [1, 0, 0]]), backend='native')\n"
        "print('f64', h64.t.dtype, np.asarray(h64.prim >= 0).tolist())\n"
    )
    out = _run(code, RADIOMETRIA_CACHE_DIR=str(tmp_path))
    assert "(True, 'compiled and loaded') native [True, True]" in out.stdout, out.stderr
    assert "threads 1 " in out.stdout, out.stdout
    assert "f64 float64 [True, True]" in out.stdout, out.stderr
    libs = {p.name.split("-")[1]: p for p in tmp_path.iterdir()}
    assert sorted(libs) == ["f32", "f64"], libs
    nm = shutil.which("nm")
    if nm is not None:
        for bits in ("32", "64"):
            symbols = subprocess.run(
                [nm, "-D", str(libs[f"f{bits}"])], capture_output=True, text=True
            ).stdout
            other = "64" if bits == "32" else "32"
            for kind in ("Bvh", "Brute"):
                for hit in ("Closest", "Any"):
                    assert f"Radiometria{kind}{hit}F{bits}" in symbols
                    assert f"Radiometria{kind}{hit}F{other}" not in symbols


def test_a_failed_background_build_falls_back_with_its_reason(tmp_path):
    """A compiler that fails (`CXX=false`) in `prebuild`'s thread: `_load` reports the failure
    and the JAX traversal answers the queries."""
    out = _run(_PREBUILD_PROBE, RADIOMETRIA_CACHE_DIR=str(tmp_path), CXX="false")
    assert "(False, 'build or load failed:" in out.stdout, out.stderr
    assert "jax [True, True]" in out.stdout and not list(tmp_path.iterdir())
