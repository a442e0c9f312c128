"""Benchmark: fit the sRGB res-64 coefficient table, and compare with colour-science.

    python benchmarks/bench_lut.py [--res 64] [--devices N] [--colour-size 3] [--check]

Reports, as JSON on stdout:

- `fit_lut`: wall time of the first build in this process (compilation included), of a second
  build (compiled code cached: the steady-state cost) and of one without the infrared-tail
  stage (`infrared_tails=False`, the table pbrt's `rgb2spec_opt` makes), the stage's report,
  the peak resident memory of the
  process, the convergence summary (every table point, its residual distribution) and, with
  `--check`, the round-trip CIEDE2000 statistics;
- `colour_LUT3D_Jakob2019`: wall time of `colour.recovery.LUT3D_Jakob2019.generate` at a small
  size (res 3 by default; the issue calls it `colour.volume.LUT3D_Jakob2019`, but colour 0.4.7
  has it in `colour.recovery`), extrapolated to res 64 by the number of table entries
  (3 res^3 Gauss-Newton solves, so time ~ res^3).

For reference on the issue's 2-core machine: pbrt-v4's `rgb2spec_opt` takes 16.2-17.3 s wall
for res 64; colour needs 306 s for res 16. The goal for `fit_lut` is <= 3.5 s wall.

`--devices N` (default: the number of CPU cores) runs the CPU as N JAX devices, so the table's
column blocks are fitted in parallel (`fit_lut(devices=...)`, `jax.shard_map`); XLA's own
threading is not used by this workload. `--devices 1` measures the single-device path.
"""

import argparse
import json
import os
import resource
import sys
import time


def _peak_rss_mb() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux, bytes on macOS
    return r / 1024.0 if sys.platform != "darwin" else r / 2**20


def bench_fit_lut(res: int, n_devices: int, check: bool) -> dict:
    import jax

    jax.config.update("jax_num_cpu_devices", n_devices)
    from radiometria.upsampling import fit_lut

    devices = jax.devices() if len(jax.devices()) > 1 else None
    t0 = time.perf_counter()
    c0 = time.process_time()
    first = fit_lut("sRGB", res, devices=devices)
    t_first = time.perf_counter() - t0
    cpu_first = time.process_time() - c0
    t0 = time.perf_counter()
    c0 = time.process_time()
    second = fit_lut("sRGB", res, devices=devices)
    t_second = time.perf_counter() - t0
    cpu_second = time.process_time() - c0
    # The same fit without stage (4), the infrared-tail refit (pbrt's colour-only table).
    t0 = time.perf_counter()
    fit_lut("sRGB", res, devices=devices, infrared_tails=False)
    t_no_tails = time.perf_counter() - t0
    out = {
        "resolution": res,
        "devices": len(jax.devices()),
        "cpu_count": os.cpu_count(),
        "wall_s_first_call_incl_compile": round(t_first, 3),
        "wall_s_second_call": round(t_second, 3),
        "wall_s_second_call_without_tail_stage": round(t_no_tails, 3),
        "infrared_tails": second.settings["infrared_tails"],
        "cpu_s_first_call": round(cpu_first, 3),
        "cpu_s_second_call": round(cpu_second, 3),
        "peak_rss_mb": round(_peak_rss_mb(), 1),
        "fit_summary": second.summary(),
        "lm_iterations_per_block": second.settings["lm_iterations_per_block"],
    }
    del first
    if check:
        from radiometria.upsampling import (
            roundtrip_delta_E,
            roundtrip_grid_rgb,
            roundtrip_random_rgb,
            roundtrip_statistics,
        )

        with jax.enable_x64(True):
            for name, rgb in [
                ("grid33_encoded", roundtrip_grid_rgb(33)),
                ("random_1e5_linear", roundtrip_random_rgb(100_000)),
            ]:
                de, _ = roundtrip_delta_E(second.lut, rgb)
                out[f"roundtrip_{name}"] = roundtrip_statistics(de, rgb)
    return out


def bench_colour(size: int, target: int) -> dict:
    import colour
    from colour.recovery import LUT3D_Jakob2019

    cs = colour.RGB_COLOURSPACES["sRGB"]
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    illuminant = colour.SDS_ILLUMINANTS["D65"]
    lut = LUT3D_Jakob2019()
    t0 = time.perf_counter()
    c0 = time.process_time()
    lut.generate(cs, cmfs, illuminant, size, print_callable=lambda *a, **k: None)
    t = time.perf_counter() - t0
    cpu = time.process_time() - c0
    return {
        "size": size,
        "wall_s": round(t, 3),
        "cpu_s": round(cpu, 3),
        f"extrapolated_wall_s_res{target}": round(t * (target / size) ** 3, 1),
    }


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--res", type=int, default=64)
    p.add_argument("--devices", type=int, default=os.cpu_count() or 1)
    p.add_argument("--colour-size", type=int, default=3, help="0 skips colour-science")
    p.add_argument("--check", action="store_true", help="also measure round-trip accuracy")
    args = p.parse_args()
    result = {"fit_lut": bench_fit_lut(args.res, args.devices, args.check)}
    if args.colour_size:
        result["colour_LUT3D_Jakob2019"] = bench_colour(args.colour_size, args.res)
    result["reference"] = {
        "pbrt_rgb2spec_opt_res64_wall_s": "16.2-17.3 (issue, 2 cores)",
        "colour_res16_wall_s": "306 (issue)",
        "goal_wall_s": 3.5,
    }
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
