"""BVH closest hits against an independent ray caster: Mitsuba 3's `Scene.ray_intersect`.

`test_bvh.py` checks `intersect_closest` against our own brute force; here the reference is
Mitsuba 3 (Embree or its own kd-tree, float32), on random triangle soups and icospheres of
about 1e2 to 1e5 triangles and random rays (half aimed into the mesh's box, half isotropic).

Mitsuba runs in a subprocess: its `llvm_ad_rgb` variant vectorises over all rays but needs a
libLLVM >= 16 (`DRJIT_LIBLLVM_PATH`, or the Debian paths `benchmarks/bench_render.py` tries);
Dr.Jit rejects older ones or aborts the process in code generation, which a subprocess
survives. Without a usable libLLVM the test falls back to `scalar_rgb` on `N_RAYS_SCALAR`
rays (a Python loop).

Agreement, with both sides in float32:

- the same primitive and `t` to relative `RTOL_T` = 1e-5 (about 170 float32 ulp: the two
  implementations compute `t` with different but stable formulas, Woop's watertight test here
  and Embree's or Mitsuba's own triangle test there, each a few ulp from the exact `t`) plus an
  absolute `ATOL_ULPS` = 8 ulp of the largest coordinate `L` of the scene: `t` is a difference
  of positions, so its rounding error is absolute, a few ulp(L), which dominates for rays that
  start within ~1e-3 of a triangle (seen: 3e-8 at t = 2e-3, L ~ 2, ulp(L) = 2.4e-7);
- a different primitive only where the two hits tie in `t` (to that tolerance: shared edges and
  vertices of a closed mesh, touching soup triangles), or where the nearer hit is within
  `EDGE` (relative barycentric, computed in float64) of its triangle's boundary, where two
  float32 inside tests may legitimately disagree; such grazing cases must stay rare
  (at most `MAX_EDGE_FRACTION` of the rays).
"""

import functools
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from radiometria.render import build_bvh, icosphere, intersect_closest

pytest.importorskip("mitsuba")

ROOT = Path(__file__).resolve().parents[2]
LLVM_CANDIDATES = ("/lib/x86_64-linux-gnu/libLLVM.so.19.1", "/usr/lib/llvm-19/lib/libLLVM.so")
N_RAYS_LLVM = 20_000
N_RAYS_SCALAR = 256
RTOL_T = 1e-5
ATOL_ULPS = 8
EDGE = 1e-4
MAX_EDGE_FRACTION = 1e-3

_MITSUBA = textwrap.dedent(
    """
    import sys
    import numpy as np
    import mitsuba as mi

    variant, path = sys.argv[1], sys.argv[2]
    mi.set_variant(variant)
    data = np.load(path)
    v, f, o, d = data["v"], data["f"], data["o"], data["d"]
    mesh = mi.Mesh("m", len(v), len(f), has_vertex_normals=False, has_vertex_texcoords=False)
    params = mi.traverse(mesh)
    params["vertex_positions"] = type(params["vertex_positions"])(v.ravel())
    params["faces"] = type(params["faces"])(f.ravel())
    params.update()
    scene = mi.load_dict({"type": "scene", "mesh": mesh})
    if variant.startswith("llvm"):
        ray = mi.Ray3f(
            mi.Point3f(*[mi.Float(c) for c in o.T]), mi.Vector3f(*[mi.Float(c) for c in d.T])
        )
        si = scene.ray_intersect(ray)
        t = np.array(si.t, np.float32)
        prim = np.array(si.prim_index, np.int64)
        hit = np.array(si.is_valid(), bool)
    else:
        t, prim, hit = [], [], []
        for oi, di in zip(o.tolist(), d.tolist()):
            si = scene.ray_intersect(mi.Ray3f(mi.Point3f(oi), mi.Vector3f(di)))
            t.append(si.t)
            prim.append(si.prim_index)
            hit.append(bool(si.is_valid()))
        t, prim, hit = np.float32(t), np.int64(prim), np.bool_(hit)
    np.savez(path.replace(".npz", "_out.npz"), t=t, prim=np.where(hit, prim, -1))
    """
)


def _run_mitsuba(variant: str, path: Path, env: dict) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", _MITSUBA, variant, str(path)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )


@functools.cache
def _llvm_env() -> dict | None:
    """An environment in which Mitsuba's `llvm_ad_rgb` variant casts rays, or None."""
    given = os.environ.get("DRJIT_LIBLLVM_PATH")
    candidates = [given] if given else [p for p in LLVM_CANDIDATES if Path(p).exists()]
    v, f = icosphere(1)
    rays = np.array([[0, 0, -3.0], [0, 0, 1]]), np.array([[0, 0, 1.0], [0, 0, 1]])
    for lib in candidates:
        env = {**os.environ, "DRJIT_LIBLLVM_PATH": lib}
        path = Path(os.environ.get("TMPDIR", "/tmp")) / f"radiometria_llvm_probe_{os.getpid()}.npz"
        np.savez(path, v=v.astype(np.float32), f=f.astype(np.uint32), o=rays[0], d=rays[1])
        try:
            ok = _run_mitsuba("llvm_ad_rgb", path, env).returncode == 0
        finally:
            path.unlink(missing_ok=True)
            Path(str(path).replace(".npz", "_out.npz")).unlink(missing_ok=True)
        if ok:
            return env
    return None


def _mesh(kind: str, size: int) -> tuple[np.ndarray, np.ndarray]:
    """float32 vertices and faces: a soup of `size` random triangles, or `icosphere(size)`."""
    if kind == "icosphere":
        v, f = icosphere(size)
        return v.astype(np.float32), f.astype(np.int32)
    rng = np.random.default_rng(size)
    centres = rng.uniform(-1.0, 1.0, (size, 1, 3))
    # triangles of about the mean spacing: a ray crosses a few before leaving the box
    v = centres + rng.normal(0.0, size ** (-1 / 3), (size, 3, 3))
    return v.reshape(-1, 3).astype(np.float32), np.arange(3 * size, dtype=np.int32).reshape(-1, 3)


def _rays(v: np.ndarray, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Origins in the mesh's box grown by half; half aimed into the box, half isotropic."""
    rng = np.random.default_rng(seed)
    lo, hi = v.min(0).astype(np.float64), v.max(0).astype(np.float64)
    mid, half = (lo + hi) / 2, (hi - lo) / 2
    o = mid + rng.uniform(-1.5, 1.5, (n, 3)) * half
    aim = mid + rng.uniform(-1.0, 1.0, (n, 3)) * half - o
    iso = rng.normal(size=(n, 3))
    d = np.where(np.arange(n)[:, None] < n // 2, aim, iso)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return o.astype(np.float32), d.astype(np.float32)


@functools.cache
def _reference(kind: str, size: int):
    """Mesh, rays and Mitsuba's closest hits `(t, prim)` (prim -1 for a miss)."""
    import tempfile

    v, f = _mesh(kind, size)
    env = _llvm_env()
    variant = "llvm_ad_rgb" if env is not None else "scalar_rgb"
    n = N_RAYS_LLVM if env is not None else N_RAYS_SCALAR
    o, d = _rays(v, n, seed=size + 1)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "rays.npz"
        np.savez(path, v=v, f=f.astype(np.uint32), o=o, d=d)
        out = _run_mitsuba(variant, path, env if env is not None else dict(os.environ))
        assert out.returncode == 0, out.stdout + out.stderr
        res = np.load(Path(tmp) / "rays_out.npz")
        t, prim = res["t"], res["prim"]
    return v, f, o, d, t, prim, variant


def _hit64(o, d, tri):
    """Exact-ish (float64) ray-plane `t` and barycentrics `(b0, b1, b2)` for one triangle."""
    o, d = o.astype(np.float64), d.astype(np.float64)
    a, b, c = tri.astype(np.float64)
    e1, e2 = b - a, c - a
    p = np.cross(d, e2)
    det = e1 @ p
    s = o - a
    u = (s @ p) / det
    q = np.cross(s, e1)
    w = (d @ q) / det
    return (e2 @ q) / det, np.array([1 - u - w, u, w])


MESHES = [
    ("soup", 100),
    ("soup", 1_000),
    ("soup", 10_000),
    ("soup", 100_000),  # each case takes 1-3 s, Mitsuba included: none is marked slow
    ("icosphere", 2),  # 320 triangles
    ("icosphere", 4),  # 5120
    ("icosphere", 6),  # 81920
]


@pytest.mark.parametrize("backend", ["native", "jax"])
@pytest.mark.parametrize(("kind", "size"), MESHES)
def test_intersect_closest_matches_mitsuba(kind, size, backend):
    v, f, o, d, t_mi, prim_mi, variant = _reference(kind, size)
    hit = intersect_closest(build_bvh(v, f, dtype=np.float32), o, d, backend=backend)
    t, prim = np.asarray(hit.t), np.asarray(hit.prim).astype(np.int64)
    n = len(o)
    ours, theirs = prim >= 0, prim_mi >= 0
    assert 0.2 < theirs.mean() < 0.98, (variant, theirs.mean())  # the rays test something

    atol = ATOL_ULPS * float(np.spacing(np.float32(max(np.abs(v).max(), np.abs(o).max()))))
    same = ours & theirs & (prim == prim_mi)
    np.testing.assert_allclose(t[same], t_mi[same], rtol=RTOL_T, atol=atol)
    n_edge = 0
    for i in np.flatnonzero(~same & (ours | theirs)):
        tie = abs(t[i] - t_mi[i]) <= RTOL_T * max(t[i], t_mi[i]) + atol
        if ours[i] and theirs[i] and tie:
            continue  # a tie: shared edge or vertex, or touching triangles
        # one side missed the nearer hit the other found: it must graze that triangle's edge
        near = prim[i] if ours[i] and (not theirs[i] or t[i] < t_mi[i]) else prim_mi[i]
        t64, bary = _hit64(o[i], d[i], v[f[near]])
        assert bary.min() < EDGE, (i, near, t[i], t_mi[i], prim[i], prim_mi[i], t64, bary)
        n_edge += 1
    assert n_edge <= max(2, MAX_EDGE_FRACTION * n), (n_edge, n)
