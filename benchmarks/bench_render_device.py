"""Render throughput of radiometria on the default JAX device (CPU or GPU), as a user feels it.

Times, in one process: the first `render` of the Cornell box (scene loading, XLA compilation
and the render: what a new process pays), then warm renders of the same shape at several
sample counts (the compiled step is reused), for each sampler. Prints paths per second and
writes JSON. No peer runs here: `bench_render.py` compares with Mitsuba 3 on the CPU; this
script reports what the same code does on an accelerator (or on the CPU with `--cpu`).

    python benchmarks/bench_render_device.py [--size 256] [--spp 16 64 256] [--out FILE]
"""

import argparse
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=256, help="image side [px] (256)")
    parser.add_argument("--spp", type=int, nargs="+", default=[16, 64, 256])
    parser.add_argument("--cpu", action="store_true", help="force the CPU back end")
    parser.add_argument("--out", type=Path, default=None, help="JSON results file")
    args = parser.parse_args()
    if args.cpu:
        os.environ["JAX_PLATFORMS"] = "cpu"
    t_start = time.perf_counter()
    import jax

    import radiometria.render as rr

    device = jax.devices()[0]
    print(f"device: {device.platform} {device.device_kind} x{jax.device_count()}", flush=True)
    description = rr.load_scene("cornell-box")
    results = {"device": f"{device.platform} {device.device_kind}", "size": args.size, "runs": []}
    for sampler in (rr.Independent(), rr.OwenSobol()):
        kw = dict(width=args.size, height=args.size, sampler=sampler, progress=False)
        t0 = time.perf_counter()
        jax.block_until_ready(rr.render(description, spp=1, **kw))
        first = time.perf_counter() - t0
        print(f"{sampler.NAME}: first render (load + compile + 1 spp) {first:.2f} s", flush=True)
        for spp in args.spp:
            t0 = time.perf_counter()
            jax.block_until_ready(rr.render(description, spp=spp, seed=spp, **kw))
            dt = time.perf_counter() - t0
            rate = args.size**2 * spp / dt
            print(f"  {spp:5d} spp: {dt:7.3f} s warm, {rate / 1e6:7.2f} M paths/s", flush=True)
            results["runs"].append(
                {"sampler": sampler.NAME, "spp": spp, "seconds": dt, "paths_per_s": rate}
            )
        results[f"first_render_s_{sampler.NAME}"] = first
    results["process_s"] = time.perf_counter() - t_start
    print(f"whole process: {results['process_s']:.1f} s")
    if args.out:
        args.out.write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
