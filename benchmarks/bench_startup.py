"""Render speed as a user feels it (issue 15): whole processes, start-up, cache and memory.

Every number comes from separate processes started the way a user starts them, on the
Cornell box at its own 256 x 256 film (Mitsuba 3's `cornell_box()`; radiometria's
`cornell-box`), spectral, `max_depth` 8, in one run of this script:

1. **Whole process** (goal 1): `radiometria render cornell-box --spp N --out x.exr`, against a
   Python process that imports Mitsuba 3, loads `cornell_box()` and renders it with
   `scalar_spectral` or `llvm_ad_spectral` (their thread pool: every core) and writes the
   image. Each process's wall time and the relative MSE of its image against a high-spp
   Mitsuba reference (`mean((x - ref)^2 / (ref^2 + 0.01))`) give, by log-log interpolation,
   the time to reach Mitsuba `scalar_spectral`'s error at `--target-spp`. radiometria runs
   with an empty compilation cache (first run: every process compiles) and with a warm one
   (second run); Mitsuba's LLVM kernels are likewise cached by Dr.Jit after its first run.
   The first run is also timed as the first render of a new scene: the compilation cache
   empty, the ray-casting kernels' C++ library (built once per machine) already there.
2. **Start-up** (goal 2): seconds from starting the command to its first render step running
   (the step compiled or loaded from the cache and dispatched), cold and warm, and what
   `radiometria render --help` costs. The warm runs also print where the time went, from
   the command's own timestamps (`RADIOMETRIA_TIMING=1`): imports, the step entry loaded
   (`radiometria._warmstart`: the serialised step and the scene's arrays), the step's load
   from the compilation cache, its first dispatch.
3. **Warm process** (goal 3): `bench_render.py`'s in-process time to equal error, radiometria
   (Owen-Sobol) against `llvm_ad_spectral`.
4. **Memory** (goal 5): peak resident memory of `radiometria demo` and of 1920 x 1080
   renders at two sample counts: the larger of `ru_maxrss` (the largest single process, as
   `/usr/bin/time -v` reports it) and, on Linux, the peak of the process tree's summed
   proportional set size (PSS, sampled every 50 ms): the demo runs its render and each
   figure in a process of its own beside the launching one.

    .venv/bin/python benchmarks/bench_startup.py [--spps 4 16 64] [--skip-demo] [--quick]

Results are printed as ratios (goal: <= 1.0) and written as JSON beside the reference.
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_render import LLVM_CANDIDATES, _time_at_error  # noqa: E402

from radiometria.cli import cpu_xla_flags  # noqa: E402
from tests.render._mitsuba import rel_mse  # noqa: E402

PYTHON = sys.executable
COMMAND = [str(Path(PYTHON).parent / "radiometria")]

# `radiometria ...`, the same `main` the console script runs; with `RADIOMETRIA_TIMING=1` it
# marks "first step dispatched" (after the step's compilation or its load from the cache).
_OURS = "import sys\nfrom radiometria.cli import main\nsys.exit(main(sys.argv[1:]))\n"

# A user's Mitsuba script: import, load the scene, render, write the image.
_MITSUBA = textwrap.dedent(
    """
    import sys
    import numpy as np
    import mitsuba as mi
    variant, spp, seed, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
    mi.set_variant(variant)
    scene = mi.load_dict(mi.cornell_box())
    img = mi.render(scene, spp=spp, seed=seed)
    np.save(out, np.asarray(img, np.float64))
    """
)


def _tree_pss_kib(pid: int) -> int:
    """Summed proportional set size of a process and its descendants [KiB] (Linux /proc; 0
    where it cannot be read)."""
    total, stack = 0, [pid]
    while stack:
        p = stack.pop()
        try:
            rollup = Path(f"/proc/{p}/smaps_rollup").read_text()
            total += int(re.search(r"^Pss:\s+(\d+)", rollup, re.M).group(1))
            for task in os.listdir(f"/proc/{p}/task"):
                stack += map(int, Path(f"/proc/{p}/task/{task}/children").read_text().split())
        except (OSError, AttributeError, ValueError):
            continue
    return total


def _run(argv, env=None):
    """Run a child process; (wall seconds, peak memory in MiB, stderr). Peak memory is the
    larger of the child's `ru_maxrss` and its process tree's peak summed PSS."""
    env = {**os.environ, **(env or {}), "BENCH_T0": repr(time.time())}
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    peak, done = [0], threading.Event()

    def sample():
        while not done.wait(0.05):
            peak[0] = max(peak[0], _tree_pss_kib(proc.pid))

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    err = proc.stderr.read()
    done.set()
    sampler.join()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{argv} failed ({proc.returncode}):\n{err[-3000:]}")
    return seconds, max(usage.ru_maxrss, peak[0]) / 1024, err


def _first_step(err: str) -> float | None:
    """Seconds from the process's start to its first render step dispatched."""
    return _phases(err).get("first step dispatched")


_MARK = re.compile(r"radiometria timing: +([0-9.]+) s +\+ *([0-9.]+) s +(.*)")


def _phases(err: str) -> dict[str, float]:
    """Seconds since the process started at the end of each start-up phase, from the
    command's `RADIOMETRIA_TIMING` lines: imports, step entry loaded (warm start) or missed,
    scene compiled (without an entry), step traced + lowered (for its export, without an
    entry), the exported step lowered, loaded from the cache or compiled, first step
    dispatched."""
    out: dict[str, float] = {}
    for line in err.replace("\r", "\n").splitlines():
        m = _MARK.search(line)
        if not m:
            continue
        t, label = float(m[1]), m[3]
        if label.startswith("imports"):
            out["imports"] = t
        elif label.startswith("step cache"):
            out[label.split("  [")[0]] = t
        elif label.startswith("scene compiled"):
            out["scene compiled"] = t
        elif "lowered jit(flat_step)" in label or "lowered jit(_step)" in label:
            out.setdefault("step traced+lowered", t)
        elif "compiled jit(call)" in label or "compiled jit(_step)" in label:
            out.setdefault("step loaded/compiled", t)  # after a cache load or an XLA compile
        elif label.startswith("first step dispatched"):
            out.setdefault("first step dispatched", t)
    return out


def _ours(spp, seed, work: Path, cache: Path, extra=()):
    out = work / f"ours_{spp}_{seed}.exr"
    argv = [PYTHON, "-c", _OURS, "render", "cornell-box", "--spp", str(spp)]
    argv += ["--seed", str(seed), "--out", str(out), *extra]
    t, rss, err = _run(argv, {"XDG_CACHE_HOME": str(cache), "RADIOMETRIA_TIMING": "1"})
    from radiometria.camera import read_exr

    _ours.phases = _phases(err)
    return t, rss, _first_step(err), np.asarray(read_exr(out)[0], np.float64)


def _mitsuba(variant, spp, seed, work: Path):
    out = work / f"mitsuba_{variant}_{spp}_{seed}.npy"
    t, rss, _ = _run([PYTHON, "-c", _MITSUBA, variant, str(spp), str(seed), str(out)])
    return t, rss, np.load(out)


def _bytecode() -> None:
    """Compile radiometria's modules to bytecode once, as `pip install` does for a wheel and
    Python does on the first import from a source tree (unless `PYTHONDONTWRITEBYTECODE` is
    set, as on some CI machines): without it every process compiles ~180 modules from source,
    0.26 s of `import radiometria.render` on the 2-core machine. JAX's and Mitsuba's own
    modules come from pip with their bytecode."""
    import compileall

    compileall.compile_dir(str(ROOT / "radiometria"), quiet=1)


def _reference(cache: Path, ref_spp: int) -> np.ndarray:
    path = cache / f"mitsuba_ref_256_{ref_spp}.npy"  # the file bench_render.py writes too
    if not path.exists():
        print(f"reference: Mitsuba scalar_spectral, 256^2 px, {ref_spp} spp ...", flush=True)
        t, _, img = _mitsuba("scalar_spectral", ref_spp, 12345, cache)
        np.save(path, img)
        print(f"  {t:.1f} s")
    return np.load(path)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spps", type=int, nargs="+", default=[4, 16, 64])
    parser.add_argument("--target-spp", type=int, default=16, help="Mitsuba spp of the target")
    parser.add_argument("--ref-spp", type=int, default=1024)
    parser.add_argument("--cache", type=Path, default=ROOT / "out" / "bench_render")
    parser.add_argument("--skip-demo", action="store_true", help="no `radiometria demo` run")
    parser.add_argument("--skip-warm", action="store_true", help="no in-process comparison")
    parser.add_argument("--quick", action="store_true", help="spp 4 16, no demo")
    args = parser.parse_args(argv)
    if args.quick:
        args.spps, args.skip_demo = [4, 16], True
    if args.target_spp not in args.spps:
        parser.error(f"--target-spp {args.target_spp} must be one of --spps {args.spps}")
    args.cache.mkdir(parents=True, exist_ok=True)
    llvm = os.environ.get("DRJIT_LIBLLVM_PATH") or next(
        (p for p in LLVM_CANDIDATES if Path(p).exists()), None
    )
    if llvm:
        os.environ["DRJIT_LIBLLVM_PATH"] = llvm
    print(f"cores: {os.cpu_count()}; libLLVM: {llvm or 'not found'}", flush=True)
    _bytecode()
    reference = _reference(args.cache, args.ref_spp)
    record: dict = {"spps": args.spps, "ref_spp": args.ref_spp}

    with tempfile.TemporaryDirectory(prefix="bench-startup-") as tmp:
        work = Path(tmp)
        rows: dict[str, list] = {}
        # radiometria, first run: a fresh, empty compilation cache for every process.
        for spp in args.spps:
            t, rss, first, img = _ours(spp, 100 + spp, work, work / f"cold-{spp}")
            rows.setdefault("radiometria first run", []).append((spp, t, rel_mse(img, reference)))
            record.setdefault("first_step_cold", []).append(first)
            print(f"radiometria cold  spp {spp:4d} {t:7.2f} s  first step {first:5.2f} s "
                  f"rss {rss:6.0f} MiB  relMSE {rows['radiometria first run'][-1][2]:.3e}",
                  flush=True)  # fmt: skip
        # radiometria, first run of a new scene: the compilation cache empty again, but the
        # ray-casting kernels' library (built once per machine, `radiometria._native_build`)
        # in place, as after any earlier render: the C++ build no longer shares the cores.
        built = sorted((work / f"cold-{args.spps[0]}" / "radiometria").glob("*.so"))
        for spp in args.spps:
            fresh = work / f"new-scene-{spp}"
            (fresh / "radiometria").mkdir(parents=True)
            for lib in built:
                shutil.copy2(lib, fresh / "radiometria" / lib.name)
            t, rss, first, img = _ours(spp, 100 + spp, work, fresh)
            rows.setdefault("radiometria new scene", []).append((spp, t, rel_mse(img, reference)))
            record.setdefault("first_step_new_scene", []).append(first)
            print(f"radiometria new scene spp {spp:4d} {t:7.2f} s  first step {first:5.2f} s "
                  f"rss {rss:6.0f} MiB  relMSE {rows['radiometria new scene'][-1][2]:.3e}",
                  flush=True)  # fmt: skip
        # radiometria, second run: one cache, filled by a first render.
        warm = work / "warm"
        _ours(args.spps[0], 1, work, warm)
        for spp in args.spps:
            t, rss, first, img = _ours(spp, 100 + spp, work, warm)
            rows.setdefault("radiometria second run", []).append((spp, t, rel_mse(img, reference)))
            record.setdefault("first_step_warm", []).append(first)
            record.setdefault("phases_warm", []).append(_ours.phases)
            print(f"radiometria warm  spp {spp:4d} {t:7.2f} s  first step {first:5.2f} s "
                  f"rss {rss:6.0f} MiB  relMSE {rows['radiometria second run'][-1][2]:.3e}",
                  flush=True)  # fmt: skip
            print("    " + ", ".join(f"{k} {v:.2f} s" for k, v in _ours.phases.items()))
        variants = ["scalar_spectral"] + (["llvm_ad_spectral"] if llvm else [])
        for variant in variants:
            if variant == "llvm_ad_spectral":  # Dr.Jit compiles and caches its kernels once
                _mitsuba(variant, args.spps[0], 1, work)
            for spp in args.spps:
                t, rss, img = _mitsuba(variant, spp, 100 + spp, work)
                rows.setdefault(f"mitsuba {variant}", []).append((spp, t, rel_mse(img, reference)))
                print(f"mitsuba {variant:17s} spp {spp:4d} {t:7.2f} s  rss {rss:6.0f} MiB  "
                      f"relMSE {rows[f'mitsuba {variant}'][-1][2]:.3e}", flush=True)  # fmt: skip

        target = next(e for s, _, e in rows["mitsuba scalar_spectral"] if s == args.target_spp)
        tte = {
            name: _time_at_error([r[1] for r in rs], [r[2] for r in rs], target)
            for name, rs in rows.items()
        }
        record.update(rows=rows, target=target, time_to_target=tte)

        # Start-up: the help text, and the first step (above).
        help_s = min(_run(COMMAND + ["render", "--help"])[0] for _ in range(3))
        record["render_help_s"] = help_s

        # Memory: the demo (render + figures) and 1920 x 1080 renders.
        hd = {}
        for spp in (1, 4):
            out = work / f"hd_{spp}.exr"
            t, rss, _ = _run(COMMAND + ["render", "cornell-box", "--width", "1920", "--height",
                                        "1080", "--spp", str(spp), "--out", str(out)],
                             {"XDG_CACHE_HOME": str(warm)})  # fmt: skip
            hd[spp] = rss
            print(f"1920x1080 spp {spp}: {t:.1f} s, peak RSS {rss:.0f} MiB", flush=True)
        record["rss_1080p_mib"] = hd
        if not args.skip_demo:
            t, rss, _ = _run(COMMAND + ["demo", "--out", str(work / "demo")],
                             {"XDG_CACHE_HOME": str(warm)})  # fmt: skip
            record["rss_demo_mib"] = rss
            print(f"demo: {t:.1f} s, peak RSS {rss:.0f} MiB", flush=True)

    if not args.skip_warm:
        warm_ratio = _warm_in_process(reference, args)
        record["warm_in_process"] = warm_ratio

    base = tte["mitsuba scalar_spectral"]
    print(f"\ncommon error: relMSE {target:.3e} (Mitsuba scalar_spectral, {args.target_spp} spp)")
    for name, t in tte.items():
        print(f"  {name:32s} {t:7.2f} s to equal error ({t / base:5.2f}x scalar_spectral)")
    print("\ngoals (ratio <= 1 meets the goal):")
    print(f"  1a first run vs scalar_spectral:   "
          f"{tte['radiometria first run'] / base:5.2f}")  # fmt: skip
    print(f"     first run of a new scene (kernels' library built): "
          f"{tte['radiometria new scene'] / base:5.2f}")  # fmt: skip
    if "mitsuba llvm_ad_spectral" in tte:
        llvm_t = tte["mitsuba llvm_ad_spectral"]
        print(f"  1b second run vs llvm_ad_spectral: "
              f"{tte['radiometria second run'] / llvm_t:5.2f}")  # fmt: skip
    first_warm = max(f for f in record["first_step_warm"] if f is not None)
    print(
        f"  2  first step, warm cache / 1.5 s: {first_warm / 1.5:5.2f}  ({first_warm:.2f} s; "
        f"cold {max(record['first_step_cold']):.2f} s; `render --help` {help_s:.2f} s)"
    )
    # Where the warm start-up goes: each phase's share, from the fastest warm run.
    phases = min(record["phases_warm"], key=lambda p: p.get("first step dispatched", 1e9))
    previous = 0.0
    for name, t in phases.items():
        print(f"       {name:24s} at {t:5.2f} s  (+{t - previous:.2f} s)")
        previous = t
    if "warm_in_process" in record and record["warm_in_process"]:
        print(f"  3  warm process vs llvm_ad_spectral: {record['warm_in_process']:5.2f}")
    mem = max([*hd.values(), record.get("rss_demo_mib", 0)])
    print(
        f"  5  peak RSS / 1024 MiB:            {mem / 1024:5.2f}  (1080p {hd}, "
        f"demo {record.get('rss_demo_mib', 'skipped')})"
    )
    out = args.cache / "bench_startup.json"
    out.write_text(json.dumps(record, indent=1))
    print(f"wrote {out}")
    return 0


def _warm_in_process(reference, args) -> float | None:
    """bench_render's comparison in this process: time to equal error, warm, Owen-Sobol
    against llvm_ad_spectral (None without libLLVM)."""
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        return None
    os.environ["XLA_FLAGS"] = cpu_xla_flags(os.environ.get("XLA_FLAGS", ""), os.cpu_count() or 1)
    from bench_render import _mitsuba as mitsuba_run, _ours as ours_run, _timed

    from radiometria.render import OwenSobol

    runs = {"ours": ours_run(256, OwenSobol()), "llvm": mitsuba_run(256, "llvm_ad_spectral")}
    tte = {}
    for name, run in runs.items():
        run(args.spps[0], 1)  # warm-up
        times, errors = [], []
        for spp in args.spps:
            img, t = _timed(lambda run=run, spp=spp: run(spp, 200 + spp))
            times.append(t)
            errors.append(rel_mse(img, reference))
        print(f"warm in-process {name}: {[f'{t:.2f}' for t in times]} s", flush=True)
        target = errors[args.spps.index(args.target_spp)] if name == "llvm" else None
        tte[name] = (times, errors, target)
    target = tte["llvm"][2]
    t_ours = _time_at_error(tte["ours"][0], tte["ours"][1], target)
    t_llvm = _time_at_error(tte["llvm"][0], tte["llvm"][1], target)
    return t_ours / t_llvm


if __name__ == "__main__":
    raise SystemExit(main())
