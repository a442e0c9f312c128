"""Rays per second of radiometria's BVH against Embree and brute force, on icospheres.

Incoherent closest-hit rays: origins uniform in [-1.5, 1.5]^3 around a unit icosphere of
1280 to 1.3 M triangles, directions uniform on the sphere (about 27 % of the rays hit). The same
rays go through `radiometria.render.intersect_closest` (float32, after a warm-up call that
compiles) with both traversals: the native CPU kernel (`backend="native"`, the default on the
CPU) and the lockstep JAX traversal (`backend="jax"`, what runs on a GPU), then through
Embree (`embreex`, `pip install embreex`, a benchmark-only dependency; its
`run` traces one ray at a time on one thread) and, for small meshes, through
`intersect_brute_force_closest`. The process is pinned to one core by default, as Embree is
single-threaded here; `--all-cores` lets XLA use every core. The best of `--repeats` runs is
reported.

`--cornell` first times the brute-force queries with every available traversal back end (native
and JAX) on the 36-triangle Cornell box (what the renderer uses for scenes of <= 64 triangles):
rays with origins uniform in the room's box and uniform directions, closest-hit and any-hit,
under `jax.jit` (no eager padding), warm.

    .venv/bin/python benchmarks/bench_rays.py [--subdivisions 3 5 6 8] [--rays 262144]
    .venv/bin/python benchmarks/bench_rays.py --cornell --all-cores --subdivisions
"""

import argparse
import os
import sys
import time

import numpy as np


def _best_time(fn, repeats: int) -> float:
    fn()  # warm-up (compiles)
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _cornell(args, n: int, cores: str) -> None:
    import jax
    import jax.numpy as jnp

    from radiometria.render import (
        TriangleMesh,
        intersect_brute_force_any,
        intersect_brute_force_closest,
        load_scene,
    )
    from radiometria.render._geometry import TRAVERSAL_BACKENDS

    scene = load_scene("cornell-box")
    v = scene.vertices.astype(np.float32)
    mesh = TriangleMesh(jnp.asarray(v), scene.faces)
    rng = np.random.default_rng(1)
    o = jnp.asarray(rng.uniform(v.min(0), v.max(0), (n, 3)).astype(np.float32))
    d = jnp.asarray(rng.normal(size=(n, 3)).astype(np.float32))
    tmax = jnp.full(n, jnp.inf, jnp.float32)
    for backend, impl in TRAVERSAL_BACKENDS.items():  # every registered back end
        if not (ok := impl.available())[0]:
            print(f"Cornell box, brute force ({backend}): unavailable, {ok[1]}")
            continue
        closest = jax.jit(lambda *a, b=backend: intersect_brute_force_closest(*a, backend=b))
        any_hit = jax.jit(lambda *a, b=backend: intersect_brute_force_any(*a, backend=b))
        t_c = _best_time(lambda c=closest: c(mesh, o, d, tmax).t.block_until_ready(), args.repeats)
        t_a = _best_time(lambda a=any_hit: a(mesh, o, d, tmax).block_until_ready(), args.repeats)
        print(
            f"Cornell box, {len(scene.faces)} triangles, brute force ({backend}), {n} rays, "
            f"float32, {cores}: closest {n / t_c / 1e6:.2f} Mray/s, any {n / t_a / 1e6:.2f} Mray/s"
        )


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subdivisions", type=int, nargs="*", default=[3, 5, 6, 8])
    parser.add_argument("--rays", type=int, default=1 << 18)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--brute-max", type=int, default=20480, help="largest mesh for brute force")
    parser.add_argument("--all-cores", action="store_true", help="do not pin to one core")
    parser.add_argument(
        "--cornell", action="store_true", help="time brute force on the Cornell box"
    )
    args = parser.parse_args(argv)
    if not args.all_cores and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})  # before JAX starts threads

    import jax
    import jax.numpy as jnp

    from radiometria.render import (
        TriangleMesh,
        build_bvh,
        icosphere,
        intersect_any,
        intersect_brute_force_closest,
        intersect_closest,
        native_status,
    )

    try:
        import embreex.rtcore_scene as rtcs
        from embreex.mesh_construction import TriangleMesh as EmbreeMesh
    except ImportError:
        rtcs = None
        print(
            "embreex is not installed: `pip install embreex` to compare with Embree",
            file=sys.stderr,
        )

    rng = np.random.default_rng(0)
    n = args.rays
    o = rng.uniform(-1.5, 1.5, (n, 3)).astype(np.float32)
    d = rng.normal(size=(n, 3)).astype(np.float32)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    oj, dj = jnp.asarray(o), jnp.asarray(d)
    tmax = jnp.full(n, jnp.inf, jnp.float32)
    cores = "all cores" if args.all_cores else "1 core"
    platform = jax.devices()[0].platform
    print(f"{n} incoherent rays, float32, {cores}, jax {jax.__version__} on {platform}")
    if args.cornell:
        _cornell(args, n, cores)
    ok, reason = native_status()
    print(f"native traversal: {reason}")
    backend = "native" if ok else "jax"
    header = (
        f"{'triangles':>10} {'build s':>8} {'depth':>5} {'closest Mray/s':>14} {'any Mray/s':>10} "
        f"{'JAX Mray/s':>10} {'Embree Mray/s':>13} {'ours/Embree':>11} {'JAX/Embree':>10} "
        f"{'brute Mray/s':>12} {'hit %':>6}"
    )
    print(header)
    print("-" * len(header))
    for sub in args.subdivisions:
        v, f = icosphere(sub)
        t0 = time.perf_counter()
        bvh = build_bvh(v.astype(np.float32), f)
        build_s = time.perf_counter() - t0
        hit = intersect_closest(bvh, oj, dj, tmax, backend=backend)

        def rate(fn):
            return n / _best_time(lambda: jax.block_until_ready(fn()), args.repeats) / 1e6

        ours = rate(lambda bvh=bvh: intersect_closest(bvh, oj, dj, tmax, backend=backend).t)
        any_rate = rate(lambda bvh=bvh: intersect_any(bvh, oj, dj, tmax, backend=backend))
        jax_rate = rate(lambda bvh=bvh: intersect_closest(bvh, oj, dj, tmax, backend="jax").t)
        emb = ratio = jax_ratio = brute = float("nan")
        if rtcs is not None:
            scene = rtcs.EmbreeScene()
            EmbreeMesh(scene, v.astype(np.float32)[f])
            ids = scene.run(o, d)
            agree = np.mean(ids == np.asarray(hit.prim))
            if agree < 0.999:
                print(
                    f"warning: Embree and radiometria disagree on {100 * (1 - agree):.3f} % of rays"
                )
            emb = n / _best_time(lambda scene=scene: scene.run(o, d), args.repeats) / 1e6
            ratio, jax_ratio = ours / emb, jax_rate / emb
        if len(f) <= args.brute_max:
            mesh = TriangleMesh(jnp.asarray(v, jnp.float32), f)
            m = min(n, max(4096, int(2e8 / len(f))))  # bound the work
            ob, db, tb = oj[:m], dj[:m], tmax[:m]
            t_b = _best_time(
                lambda a=(mesh, ob, db, tb): intersect_brute_force_closest(
                    *a
                ).t.block_until_ready(),
                1,
            )
            brute = m / t_b / 1e6
        hit_pct = 100 * float(np.mean(np.asarray(hit.prim) >= 0))
        print(
            f"{len(f):>10} {build_s:>8.2f} {bvh.stack_size:>5} {ours:>14.3f} {any_rate:>10.3f} "
            f"{jax_rate:>10.3f} {emb:>13.3f} {ratio:>11.3f} {jax_ratio:>10.3f} {brute:>12.3f} "
            f"{hit_pct:>6.1f}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
