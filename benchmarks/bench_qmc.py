"""Benchmark radiometria.montecarlo against SciPy and NumPy (a script, not a test).

    python benchmarks/bench_qmc.py [--quick] [--repeats R]

Times, in the same run, warm (compile excluded, reported separately), best of R repeats:

1. Owen-scrambled Sobol, 2^20 points x 32 dimensions, float32 and float64 output, against
   `scipy.stats.qmc.Sobol(32, scramble=True).random(2^20)` (SciPy scrambles with a *linear*
   matrix scramble plus digital shift, `"lms"` here, and returns float64). Goal: full (nested,
   hash-based) Owen scrambling at least as fast as SciPy's linear scramble. The generator is
   uint32 bit arithmetic throughout: a direct Gray-code evaluation split into two sqrt(n)-row
   XOR tables (no sequential recursion), the Laine-Karras/Burley hash on bit-reversed values,
   and one conversion to float at the end; float32 output halves the bytes written.
2. Halton, 2^20 x 32, random digit permutations (`scramble="permutation"`, Owen 2017) against
   `scipy.stats.qmc.Halton(32, scramble=True)` (the same scramble). Goal: >= 10x faster.
3. A 1e7-sample plain Monte Carlo integration of exp(-|x|^2) over [0, 1)^3 with
   `radiometria.montecarlo.integrate(..., method="mc")` (jitted, float32) against NumPy
   (`default_rng().random((n, 3))`, float64, and float32).

Reference figures measured earlier on this machine: SciPy Sobol scrambled 0.066 s, SciPy Halton
scrambled 1.66 s. `--quick` divides the sizes by 16; `--single-thread` runs XLA on one thread
for a per-core comparison (SciPy and NumPy are single-threaded here). Prints a ratio per
comparison (> 1 means radiometria is faster).
"""

import argparse
import math
import os
import sys
import time

if "--single-thread" in sys.argv:  # must be set before JAX starts its CPU client
    os.environ["XLA_FLAGS"] = (
        os.environ.get("XLA_FLAGS", "")
        + " --xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
    )

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)  # so that float64 output can be timed as well

import radiometria.montecarlo as mc  # noqa: E402


def best_of(fn, repeats):
    fn()  # warm-up: compile and caches
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def first_call(fn):
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def report(name, ours, ref, ref_name):
    print(
        f"  {name:<44s} {ours * 1e3:9.1f} ms   {ref_name} {ref * 1e3:9.1f} ms"
        f"   ratio {ref / ours:6.2f}x"
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="sizes / 16")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument(
        "--single-thread",
        action="store_true",
        help="one XLA CPU thread (SciPy and NumPy use one): a per-core comparison that is also "
        "robust on a busy machine",
    )
    args = parser.parse_args()
    from scipy.stats import qmc

    n = 2**20 // (16 if args.quick else 1)
    d = 32
    r = args.repeats
    key = jax.random.key(0)
    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, n = {n}, d = {d}, best of {r}")

    print("1. Sobol")
    scipy_lms = best_of(lambda: qmc.Sobol(d, scramble=True, rng=1).random(n), r)
    scipy_plain = best_of(lambda: qmc.Sobol(d, scramble=False).random(n), r)
    for scramble, dtype in [
        ("owen", jnp.float32),
        ("owen", jnp.float64),
        ("lms", jnp.float32),
        (None, jnp.float32),
    ]:
        kk = None if scramble is None else key

        def run(scramble=scramble, dtype=dtype, kk=kk):
            return mc.sobol(n, d, scramble=scramble, key=kk, dtype=dtype).block_until_ready()

        compile_s = first_call(run)
        ours = best_of(run, r)
        ref, ref_name = (
            (scipy_plain, "scipy plain") if scramble is None else (scipy_lms, "scipy lms")
        )
        report(
            f"sobol scramble={scramble} {jnp.dtype(dtype).name} (compile {compile_s:.2f} s)",
            ours,
            ref,
            ref_name,
        )

    print("2. Halton")
    scipy_h = best_of(lambda: qmc.Halton(d, scramble=True, rng=1).random(n), max(1, r // 2))
    for dtype in (jnp.float32, jnp.float64):

        def run_h(dtype=dtype):
            return mc.halton(n, d, scramble="permutation", key=key, dtype=dtype).block_until_ready()

        compile_s = first_call(run_h)
        ours = best_of(run_h, r)
        report(
            f"halton permutation {jnp.dtype(dtype).name} (compile {compile_s:.2f} s)",
            ours,
            scipy_h,
            "scipy",
        )

    print("3. Monte Carlo integration")
    n_mc = 10_000_000 // (16 if args.quick else 1)

    def f(x):
        return jnp.exp(-jnp.sum(x * x, axis=-1))

    exact = (math.sqrt(math.pi) / 2 * math.erf(1.0)) ** 3

    @jax.jit
    def ours_mc(k):
        return mc.integrate(f, "unit_cube", n_mc, dim=3, method="mc", key=k).mean

    def run_mc():
        return float(ours_mc(key))

    compile_s = first_call(run_mc)
    ours = best_of(run_mc, r)
    rng = np.random.default_rng(0)
    np64 = best_of(lambda: np.exp(-np.sum(rng.random((n_mc, 3)) ** 2, axis=-1)).mean(), r)
    np32 = best_of(
        lambda: np.exp(-np.sum(rng.random((n_mc, 3), dtype=np.float32) ** 2, axis=-1)).mean(), r
    )
    print(
        f"  estimate {run_mc():.6f} (exact {exact:.6f}); jax default float {jnp.result_type(float)}"
    )
    report(f"integrate mc 1e7 (compile {compile_s:.2f} s)", ours, np64, "numpy f64")
    report("integrate mc 1e7", ours, np32, "numpy f32")


if __name__ == "__main__":
    main()
