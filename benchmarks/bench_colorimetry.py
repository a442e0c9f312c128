"""Benchmark radiometria.colorimetry against colour-science (a script, not a test).

    python benchmarks/bench_colorimetry.py [--quick]

Times, in the same run, warm and jitted, on the same float64 inputs:

1. spectra -> XYZ: 1e6 spectra x 471 samples (360-830 nm, 1 nm), reflective under D65; colour's
   `sd_to_XYZ_integration` is timed on 1e4 spectra and extrapolated linearly. Also reports the
   effective read bandwidth (bytes of spectra / time) against a measured NumPy copy bandwidth,
   i.e. how close the one-matmul fast path is to the memory bound.
2. Planck's law on 1e7 (wavelength, temperature) points: `radiometria.radiometry.planck` (nm)
   against `colour.colorimetry.planck_law` (metres; same points).
3. XYZ -> Lab -> Delta E 2000 on 1e6 pairs.
4. xy -> CCT (Ohno 2013) on 1e5 points; colour's `uv_to_CCT_Ohno2013` loops in Python, so it is
   timed on 1e3 points and extrapolated.

`--quick` divides every size by 100. Reference figures measured earlier with colour-science
0.4.7 on this machine: spectra->XYZ ~5.7 s, planck 0.080 s, CIEDE2000 0.32 s, CCT ~21 s.
"""

import argparse
import os
import time
import warnings

import jax

jax.config.update("jax_enable_x64", True)  # float64, the same precision as colour-science

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import radiometria.colorimetry as rc  # noqa: E402
from radiometria.radiometry import planck  # noqa: E402


def _best(fn, repeats: int = 3) -> float:
    """Best wall time of `repeats` calls of `fn` (already warm), seconds."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        jax.block_until_ready(out)
        times.append(time.perf_counter() - t0)
    return min(times)


def _row(name: str, ours: float, theirs: float, note: str = "") -> None:
    print(f"{name:<34s} radiometria {ours:8.4f} s  colour {theirs:8.4f} s  x{theirs / ours:6.1f}")
    if note:
        print(f"{'':34s} {note}")


def memcpy_bandwidth(n_bytes: int = 1 << 30) -> float:
    """NumPy copy bandwidth in bytes/s (bytes copied per second, best of 3)."""
    src = np.ones(n_bytes // 8)
    dst = np.empty_like(src)
    np.copyto(dst, src)
    t = _best(lambda: np.copyto(dst, src))
    return src.nbytes / t


def bench_sd_to_XYZ(n: int, n_colour: int) -> None:
    import colour

    wl = np.arange(360.0, 831.0)
    S = np.asarray(rc.daylight_spd(6504.0, jnp.asarray(wl)))
    R = jax.random.uniform(jax.random.key(0), (n, wl.size), dtype=jnp.float64)
    f = jax.jit(lambda r: rc.sd_to_XYZ(r, wl, illuminant=S))
    jax.block_until_ready(f(R))
    t_ours = _best(lambda: f(R))

    shape = colour.SpectralShape(360, 830, 1)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    ill = colour.SpectralDistribution(S, wl)
    R_np = np.asarray(R[:n_colour])
    g = lambda: colour.colorimetry.sd_to_XYZ_integration(R_np, cmfs, ill, shape=shape)  # noqa: E731
    g()
    t_colour = _best(g, 2) * (n / n_colour)
    err = np.abs(np.asarray(f(R[:n_colour])) - g() / 100.0).max()
    bw = memcpy_bandwidth()
    read = R.nbytes / t_ours
    _row(
        f"spectra->XYZ {n:.0e} x {wl.size}",
        t_ours,
        t_colour,
        f"(colour on {n_colour:.0e}, extrapolated; max |dXYZ| {err:.1e})",
    )
    print(
        f"{'':34s} read {read / 1e9:.2f} GB/s = {read / bw:.0%} of NumPy copy bandwidth "
        f"{bw / 1e9:.2f} GB/s ({R.nbytes / 1e9:.2f} GB of float64 spectra)"
    )
    R32 = R.astype(jnp.float32)
    f32 = jax.jit(lambda r: rc.sd_to_XYZ(r, wl.astype(np.float32), illuminant=S.astype(np.float32)))
    jax.block_until_ready(f32(R32))
    t32 = _best(lambda: f32(R32))
    print(f"{'':34s} float32: {t32:.4f} s, read {R32.nbytes / t32 / 1e9:.2f} GB/s")


def bench_planck(n: int) -> None:
    import colour

    # colour's planck_law evaluates the outer product of its wavelength and temperature
    # vectors, so the n points are a (n / 1000) x 1000 grid for both.
    k1, k2 = jax.random.split(jax.random.key(1))
    wl = jax.random.uniform(k1, (n // 1000, 1), minval=300.0, maxval=1000.0, dtype=jnp.float64)
    T = jax.random.uniform(k2, (1, 1000), minval=1000.0, maxval=10000.0, dtype=jnp.float64)
    f = jax.jit(planck)
    jax.block_until_ready(f(wl, T))
    t_ours = _best(lambda: f(wl, T))
    wl_m, T_np = np.asarray(wl)[:, 0] * 1e-9, np.asarray(T)[0]
    g = lambda: colour.colorimetry.planck_law(wl_m, T_np)  # noqa: E731  (W sr^-1 m^-2 m^-1)
    g()
    t_colour = _best(g)
    # colour uses c2 = 1.4388e-2 (CIE) and c1 = 3.741771e-16; we use exact SI constants.
    rel = np.abs(np.asarray(f(wl, T)) * 1e9 / g() - 1.0).max()
    _row(
        f"planck {n:.0e} points", t_ours, t_colour, f"(max rel. diff {rel:.1e}: c1, c2 conventions)"
    )


def bench_delta_E(n: int) -> None:
    import colour

    k1, k2 = jax.random.split(jax.random.key(2))
    a = jax.random.uniform(k1, (n, 3), minval=0.01, maxval=1.0, dtype=jnp.float64)
    b = jnp.clip(a + 0.05 * jax.random.normal(k2, (n, 3), dtype=jnp.float64), 0.001, None)
    f = jax.jit(lambda x, y: rc.delta_E_CIE2000(rc.XYZ_to_Lab(x), rc.XYZ_to_Lab(y)))
    jax.block_until_ready(f(a, b))
    t_ours = _best(lambda: f(a, b))
    a_np, b_np = np.asarray(a), np.asarray(b)

    def g():
        return colour.delta_E(colour.XYZ_to_Lab(a_np), colour.XYZ_to_Lab(b_np), method="CIE 2000")

    g()
    t_colour = _best(g)
    err = np.abs(np.asarray(f(a, b)) - g()).max()
    _row(f"XYZ->Lab->dE2000 {n:.0e} pairs", t_ours, t_colour, f"(max |d dE| {err:.1e})")


def bench_CCT(n: int, n_colour: int) -> None:
    import colour

    rng = np.random.default_rng(3)
    T = rng.uniform(2000.0, 20000.0, n)
    D = rng.uniform(-0.02, 0.02, n)
    xy = jnp.asarray(rc.UCS_uv_to_xy(rc.CCT_to_uv(T, D)))
    f = jax.jit(lambda p: rc.xy_to_CCT(p))
    jax.block_until_ready(f(xy))
    t_ours = _best(lambda: f(xy))
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    uv = np.asarray(colour.xy_to_UCS_uv(np.asarray(xy[:n_colour])))
    g = lambda: colour.temperature.uv_to_CCT_Ohno2013(uv, cmfs=cmfs)  # noqa: E731
    g()
    t_colour = _best(g, 1) * (n / n_colour)
    ours = np.asarray(rc.xy_to_CCT(xy[:n_colour], c2=1.4388e-2))
    err = np.abs(ours[:, 0] / g()[:, 0] - 1.0).max()
    _row(
        f"xy->CCT (Ohno 2013) {n:.0e} points",
        t_ours,
        t_colour,
        f"(colour on {n_colour:.0e}, extrapolated; max rel. dCCT {err:.1e} at equal c2)",
    )


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="divide every size by 100")
    args = parser.parse_args(argv)
    s = 100 if args.quick else 1
    warnings.filterwarnings("ignore")  # colour-science's optional-package and alignment notes
    import colour

    print(
        f"jax {jax.__version__} ({jax.devices()[0].platform}), colour-science "
        f"{colour.__version__}, {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}; "
        "float64; best of 3 (colour: best of 1-2)"
    )
    bench_sd_to_XYZ(1_000_000 // s, max(10_000 // s, 100))
    bench_planck(10_000_000 // s)
    bench_delta_E(1_000_000 // s)
    bench_CCT(100_000 // s, max(1_000 // s, 20))


if __name__ == "__main__":
    main()
