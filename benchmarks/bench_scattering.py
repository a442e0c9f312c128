"""BxDF throughput: radiometria.scattering (JAX, jit, warm) vs Mitsuba 3 (`llvm_ad_rgb`).

Per direction, one renderer-style BSDF query: importance-sample a direction from `wo`
(`sample_f` / Mitsuba `BSDF.sample`) and evaluate value and pdf for a second, light-sampled
direction (`f` + `pdf` / Mitsuba `BSDF.eval_pdf`). 1e7 directions in batches of 1e6, float32,
inputs generated before timing; the best of `--repeats` timed passes is reported (after a warm-up
pass that compiles). Our BxDFs carry 4 wavelengths (hero-wavelength rendering), Mitsuba's RGB
variant 3 channels. Microfacet models use the separable Smith masking on both sides, so both
compute the same model.

Mitsuba's LLVM variants need libLLVM >= 16 (Debian: `apt-get install libllvm19`; without root,
`apt-get download libllvm19 && dpkg -x libllvm19_*.deb DIR` and point `DRJIT_LIBLLVM_PATH` at
`DIR/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1`). Without `DRJIT_LIBLLVM_PATH` the newest system
libLLVM >= 16 is used (Dr.Jit rejects 14, and 15 aborts the process in code generation); if none
loads, the benchmark falls back to `scalar_rgb` on a small subset and says so.

`--tuned-malloc` re-runs the benchmark with glibc's allocator told to keep freed memory
(`MALLOC_MMAP_THRESHOLD_`, `MALLOC_TRIM_THRESHOLD_`, `MALLOC_TOP_PAD_`). XLA's CPU client
allocates every output and temporary buffer afresh, and by default glibc maps large blocks
from the OS and unmaps them on free, so each batch page-faults some 80 MB of new memory;
Dr.Jit reuses memory through its own caching allocator. The option removes that harness cost
from our side; the BxDF code is the same either way.

Run: `python benchmarks/bench_scattering.py [--n 10000000] [--batch 1000000] [--repeats 3]
[--tuned-malloc]`.
"""

import argparse
import glob
import os
import re
import sys
import time

import numpy as np

_MALLOC_ENV = {
    "MALLOC_MMAP_THRESHOLD_": str(1 << 32),
    "MALLOC_TRIM_THRESHOLD_": str(1 << 34),
    "MALLOC_TOP_PAD_": str(1 << 30),
}


def _find_libllvm() -> str | None:
    """The newest system libLLVM Dr.Jit can use (major version >= 16), or None."""
    if os.environ.get("DRJIT_LIBLLVM_PATH"):
        return os.environ["DRJIT_LIBLLVM_PATH"]
    found = {}
    for pattern in (
        "/usr/lib/x86_64-linux-gnu/libLLVM*.so*",
        "/usr/lib/llvm-*/lib/libLLVM*.so*",
    ):
        for path in glob.glob(pattern):
            m = re.search(r"libLLVM[-.](?:so\.)?(\d+)", os.path.basename(path))
            if m and int(m.group(1)) >= 16:
                found.setdefault(int(m.group(1)), path)
    return found[max(found)] if found else None


def _inputs(n: int, seed: int):
    rng = np.random.default_rng(seed)

    def dirs(upper: bool):
        v = rng.normal(size=(n, 3))
        v /= np.linalg.norm(v, axis=1, keepdims=True)
        if upper:
            v[:, 2] = np.abs(v[:, 2])
        return v.astype(np.float32)

    return dirs(True), dirs(True), rng.random((n, 3), dtype=np.float32)


CASES = ["diffuse", "roughconductor", "roughdielectric", "dielectric"]


def bench_ours(case: str, batches, repeats: int) -> float:
    import jax
    import jax.numpy as jnp

    import radiometria.scattering as sc

    f32 = jnp.float32
    lam4 = jnp.ones(4, f32)
    bxdf = {
        "diffuse": lambda: sc.DiffuseBxDF(0.5 * lam4),
        "roughconductor": lambda: sc.RoughConductorBxDF(
            f32(0.3), 0.2 * lam4, 3.0 * lam4, masking="separable"
        ),
        "roughdielectric": lambda: sc.RoughDielectricBxDF(
            f32(0.3), 1.5 * lam4, masking="separable"
        ),
        "dielectric": lambda: sc.DielectricBxDF(1.5 * lam4),
    }[case]()

    @jax.jit
    def query(b, wo, wl, u):
        s = b.sample_f(wo, u[:, 0], u[:, 1:])
        return s.f, s.wi, s.pdf, b.f(wo, wl), b.pdf(wo, wl)

    dev = [tuple(jax.device_put(x) for x in batch) for batch in batches]
    jax.block_until_ready(query(bxdf, *dev[0]))  # compile + warm
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        outs = [query(bxdf, *b) for b in dev]
        jax.block_until_ready(outs)
        best = min(best, time.perf_counter() - t0)
    return best


def bench_mitsuba(case: str, batches, repeats: int, variant: str) -> float:
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(variant)
    desc = {
        "diffuse": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}},
        "roughconductor": {
            "type": "roughconductor", "distribution": "ggx", "alpha": 0.3, "eta": 0.2, "k": 3.0,
        },
        "roughdielectric": {
            "type": "roughdielectric", "distribution": "ggx", "alpha": 0.3, "int_ior": 1.5,
            "ext_ior": 1.0,
        },
        "dielectric": {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0},
    }[case]  # fmt: skip
    bsdf = mi.load_dict(desc)
    ctx = mi.BSDFContext()
    scalar = variant.startswith("scalar")
    prepared = []
    for wo, wl, u in batches:
        if scalar:
            prepared.append((wo, wl, u))
            continue
        n = wo.shape[0]
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(wo.T)
        si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
        prepared.append((si, mi.Vector3f(wl.T), mi.Float(u[:, 0]), mi.Point2f(u[:, 1], u[:, 2])))
        dr.eval(prepared[-1])

    def run_all():
        for item in prepared:
            if scalar:
                wo, wl, u = item
                for k in range(wo.shape[0]):
                    si = dr.zeros(mi.SurfaceInteraction3f)
                    si.wi = mi.Vector3f(*map(float, wo[k]))
                    si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
                    bsdf.sample(ctx, si, float(u[k, 0]), mi.Point2f(float(u[k, 1]), float(u[k, 2])))
                    bsdf.eval_pdf(ctx, si, mi.Vector3f(*map(float, wl[k])))
            else:
                si, wl, u0, u12 = item
                bs, w = bsdf.sample(ctx, si, u0, u12)
                val, pdf = bsdf.eval_pdf(ctx, si, wl)
                dr.eval(bs.wo, bs.pdf, w, val, pdf)
        if not scalar:
            dr.sync_thread()

    run_all()  # warm-up: JIT compilation and kernel cache
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        run_all()
        best = min(best, time.perf_counter() - t0)
    return best


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=10_000_000, help="directions per BxDF")
    p.add_argument("--batch", type=int, default=1_000_000, help="directions per batch")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--cases", nargs="*", default=CASES, choices=CASES)
    p.add_argument(
        "--tuned-malloc",
        action="store_true",
        help="re-run with glibc's allocator keeping freed memory (see the module docstring)",
    )
    args = p.parse_args(argv)
    if args.tuned_malloc and any(os.environ.get(k) != v for k, v in _MALLOC_ENV.items()):
        # The allocator reads these at start-up only: re-run this script with them set.
        os.environ.update(_MALLOC_ENV)
        rest = sys.argv[1:] if argv is None else list(argv)
        os.execv(sys.executable, [sys.executable, os.path.abspath(__file__), *rest])

    n_batches = max(1, args.n // args.batch)
    n = n_batches * args.batch
    batches = [_inputs(args.batch, seed) for seed in range(n_batches)]

    lib = _find_libllvm()
    if lib:
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", lib)
    variant = "llvm_ad_rgb"
    try:
        import mitsuba as mi

        mi.set_variant(variant)
    except Exception as e:  # noqa: BLE001 - any failure to load LLVM means: fall back
        print(f"# Mitsuba {variant} unavailable ({e}); falling back to scalar_rgb on 20k dirs")
        variant = "scalar_rgb"

    import jax

    platform = jax.devices()[0].platform
    print(
        f"# radiometria.scattering vs Mitsuba 3 ({variant}); jax {jax.__version__} on {platform},"
        f" float32; {n:.0e} directions in batches of {args.batch:.0e}; best of {args.repeats};"
        f" libLLVM: {os.environ.get('DRJIT_LIBLLVM_PATH')};"
        f" tuned malloc: {all(os.environ.get(k) == v for k, v in _MALLOC_ENV.items())}"
    )
    print(f"{'bxdf':<16} {'ours [M/s]':>11} {'mitsuba [M/s]':>14} {'ours/mitsuba':>13}")
    for case in args.cases:
        t_ours = bench_ours(case, batches, args.repeats)
        if variant.startswith("scalar"):
            sub = [tuple(x[:20_000] for x in batches[0])]
            t_mi = bench_mitsuba(case, sub, 1, variant) * n / 20_000
        else:
            t_mi = bench_mitsuba(case, batches, args.repeats, variant)
        r_ours, r_mi = n / t_ours / 1e6, n / t_mi / 1e6
        print(f"{case:<16} {r_ours:>11.2f} {r_mi:>14.2f} {r_ours / r_mi:>13.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
