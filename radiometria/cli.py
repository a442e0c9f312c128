"""The `radiometria` command (also `python -m radiometria`).

Subcommands:

- `figures --out DIR [--only NAME ...] [--smoke]`: write every thesis figure (PNG and PDF).
- `demo [--out DIR] [--spp N]`: render the Cornell box and write the figures into `./out`.
- `lut build --space NAME --res N --out FILE`, `lut check FILE`: RGB-to-spectrum tables.
- `render SCENE --spp N --out FILE [--width W --height H --seed S --max-depth D
  --integrator NAME --sampler NAME --checkpoint FILE --checkpoint-every S --resume
  --preview-every S --spectral]`.
- `cache info`, `cache clear`: the persistent compilation cache.

Every command except `cache` keeps XLA's compiled programs in the persistent compilation cache
(`$XDG_CACHE_HOME/radiometria/jax`, else `~/.cache/radiometria/jax`), so a second render of a
scene of the same shape does not compile again; `radiometria --no-cache ...` or
`RADIOMETRIA_NO_CACHE=1` turns it off.

Each long task shows a progress bar on stderr (tqdm). `radiometria --timing ...` (or
`RADIOMETRIA_TIMING=1`) writes timestamps of the start-up's phases to stderr: imports, scene
load, scene compile, the first step's trace and compile or cache load, render, image written.
"""

import argparse
import os
import sys
from pathlib import Path

from ._timing import TIMING_ENV, mark, timing_enabled

__all__ = ["main"]


def _figures(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    with _Isolated(cache=not args.no_cache) as isolated:
        names = isolated.run(_figure_names, args.only)
        bar = tqdm(total=len(names), desc="figures", unit="fig", file=sys.stderr)
        paths: list[Path] = []
        for name in names:
            bar.set_postfix_str(name)
            paths += isolated.run(_figure, args.out, name, args.smoke)
            bar.update(1)
        bar.close()
    for p in paths:
        print(p)
    return 0


class _Isolated:
    """Runs each unit of work (the demo's render, one figure) in a fresh process of its own,
    one at a time, so that what it held (XLA's compiled programs, its arrays, the heap's
    fragments) goes back to the system when it ends: `radiometria demo` in one process grew
    to 1.18 GB, each figure alone stays under 1 GB, and the launching process imports no JAX.

    The processes are spawned (not forked: JAX's threads do not survive a fork) and inherit
    the environment (`XLA_FLAGS` set by `--cpu-devices`, `RADIOMETRIA_NO_CACHE`), with glibc's
    `MALLOC_ARENA_MAX=1` unless it is set: XLA's compiler threads each grew an arena of their
    own, and the bidirectional figure peaked at 958 MB with them, 815 MB with one (its time
    unchanged). Each process uses the persistent compilation cache unless `cache` is False.
    An exception in the work is raised here unchanged; a process that dies (killed, out of
    memory) raises `RuntimeError` naming the work. Where no process pool can be made (no
    POSIX semaphores), the work runs in the calling process, with a note on stderr.
    """

    _ENV = {"MALLOC_ARENA_MAX": "1"}

    def __init__(self, *, cache: bool):
        self.cache = cache
        self.pool = None
        self.saved_env: dict[str, str | None] = {}

    def __enter__(self) -> "_Isolated":
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        for name, value in self._ENV.items():  # read by each process spawned from here on
            self.saved_env[name] = os.environ.get(name)
            os.environ.setdefault(name, value)
        try:
            self.pool = ProcessPoolExecutor(
                max_workers=1,
                mp_context=multiprocessing.get_context("spawn"),
                max_tasks_per_child=1,
            )
        except (OSError, ImportError, NotImplementedError) as err:
            # No process pool here (no POSIX semaphores, as in some sandboxes): the work runs
            # in this process, as before, with the memory that costs.
            print(f"radiometria: running in one process ({err})", file=sys.stderr)
            self.pool = None
        return self

    def __exit__(self, *exc) -> None:
        if self.pool is not None:
            self.pool.shutdown(wait=True, cancel_futures=True)
        for name, value in self.saved_env.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value

    def run(self, fn, *args):
        from concurrent.futures.process import BrokenProcessPool

        if self.pool is None:
            return _in_child(fn, self.cache, *args)
        try:
            return self.pool.submit(_in_child, fn, self.cache, *args).result()
        except BrokenProcessPool as err:
            raise RuntimeError(
                f"the process running {fn.__name__}{args!r} died before it finished "
                "(killed, or out of memory)"
            ) from err


def _in_child(fn, cache: bool, *args):
    """In a process of `_Isolated`: figures go to files, never to a screen (a non-interactive
    matplotlib backend, chosen by the program: importing `radiometria.figures` leaves it to the
    user); the persistent compilation cache unless turned off; then `fn(*args)`."""
    import matplotlib

    matplotlib.use("Agg")
    if cache:
        from .render import enable_compilation_cache

        enable_compilation_cache()
    return fn(*args)


def _figure_names(only: list[str] | None) -> list[str]:
    """The figures to make: `only` (checked against the registry), else every one, sorted."""
    from ._checks import check_choice
    from .figures import FIGURES

    for name in only or []:
        check_choice(name, "figure", sorted(FIGURES))
    return list(only) if only else sorted(FIGURES)


def _figure(out: Path, name: str, smoke: bool) -> list[Path]:
    from .figures import make_figures

    return make_figures(out, [name], smoke=smoke)


def _demo_render(out: Path, spp: int, smoke: bool) -> list[Path]:
    from .render._cli import demo_render

    return demo_render(out, spp=spp, smoke=smoke)


def _demo(args: argparse.Namespace) -> int:
    with _Isolated(cache=not args.no_cache) as isolated:
        paths = isolated.run(_demo_render, args.out, args.spp, args.smoke)
    for p in paths:
        print(p)
    args.only = None
    return _figures(args)


def _lut_build(args: argparse.Namespace) -> int:
    from .upsampling._cli import lut_build

    return lut_build(args)


def _lut_check(args: argparse.Namespace) -> int:
    from .upsampling._cli import lut_check

    return lut_check(args)


def _render(args: argparse.Namespace) -> int:
    """`radiometria render`: from the step cache when it holds this render (a warm start that
    imports neither the renderer nor its plugins, `radiometria._warmstart`), else through the
    renderer, which writes the entry for the next time."""
    from . import _native_build, _warmstart as warm

    # The ray-casting kernels' library compiles (first run only: else it is found in the
    # cache) while JAX and the renderer are imported and the scene loads.
    _native_build.prebuild()
    step_cache = None
    if not (args.no_cache or warm.cache_disabled() or args.resume or args.preview_every):
        opts = warm.render_settings(args)  # bad arguments fail here, before any lookup
        if not opts.spectral:
            options = {
                "width": opts.width,
                "height": opts.height,
                "integrator": args.integrator,
                "sampler": args.sampler,
                "max_depth": opts.max_depth,
                "defines": sorted(opts.defines.items()),
            }
            if timing_enabled():
                warm.jax_activity.start()
            request = warm.render_request(str(args.scene), options)
            directory = warm.cache_root() / "jax"  # beside JAX's compiled programs
            entry = warm.load_entry(directory, request)
            mark("step cache " + ("entry loaded" if entry else "missed"))
            if entry is not None:
                return _render_from_entry(args, opts, entry)
            step_cache = (directory, request)
    from .render._cli import render_command

    return render_command(args, step_cache=step_cache)


def _render_from_entry(args: argparse.Namespace, opts, entry) -> int:
    """Render from a step entry and write the image as `render_command` does."""
    from . import _warmstart as warm

    opts = warm.with_scene_defaults(opts, entry.meta.get("scene_defaults", {}))
    identity = {**entry.meta["identity"], "seed": opts.seed, "spp": opts.spp}

    def on_checkpoint(xyz_sum, weight_sum, done):
        from .render._cli import save_checkpoint  # costs the renderer's import, once

        save_checkpoint(opts.checkpoint, xyz_sum, weight_sum, done, identity)

    image, reached, stopped = warm.run_entry(
        entry,
        spp=opts.spp,
        seed=opts.seed,
        checkpoint_every=args.checkpoint_every,
        on_checkpoint=on_checkpoint,
    )
    mark("rendered" + warm.jax_activity.summary())
    # NumPy-only writers: radiometria.camera would import JAX's modules (about 0.3 s).
    from ._image_files import write_exr, write_png

    settings = dict(scene=str(args.scene), spp=opts.spp, seed=opts.seed)
    out = opts.out
    if stopped is not None:
        meta = {**settings, "spp_reached": int(reached)}
        write_exr(out, image, meta) if out.suffix.lower() == ".exr" else write_png(out, image)
        print(
            f"radiometria: interrupted by {stopped} at {reached} of {opts.spp} spp; partial "
            f"image {out}; checkpoint {opts.checkpoint} (continue with --resume)",
            file=sys.stderr,
        )
        return 130 if stopped == "SIGINT" else 143
    meta = {**entry.meta["metadata"], **settings, "spp_reached": int(opts.spp)}
    write_exr(out, image, meta) if out.suffix.lower() == ".exr" else write_png(out, image)
    mark("image written")
    if not args.checkpoint and opts.checkpoint.exists():
        opts.checkpoint.unlink()  # the default checkpoint of a finished render is not needed
    print(out)
    return 0


def _cache_info(args: argparse.Namespace) -> int:
    from .render._cli import cache_info_command

    return cache_info_command(args)


def _cache_clear(args: argparse.Namespace) -> int:
    from .render._cli import cache_clear_command

    return cache_clear_command(args)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the `radiometria` command."""
    parser = argparse.ArgumentParser(
        prog="radiometria",
        description="Radiometry, colorimetry and Monte Carlo in JAX, and a spectral path tracer.",
    )
    parser.add_argument(
        "--cpu-devices",
        type=int,
        default=None,
        metavar="N",
        help="XLA CPU devices to shard renders over [one per core; XLA_FLAGS wins if it sets it]",
    )
    parser.add_argument(
        "--no-cache",
        action="store_true",
        help="do not use the persistent compilation cache (also: RADIOMETRIA_NO_CACHE=1)",
    )
    parser.add_argument(
        "--timing",
        action="store_true",
        help="write timestamps of the start-up's phases to stderr (also: RADIOMETRIA_TIMING=1)",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("figures", help="write every thesis figure (PNG and PDF)")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.add_argument("--only", nargs="+", metavar="NAME", help="only these figures")
    p.add_argument("--smoke", action="store_true", help="small sample counts (CI)")
    p.set_defaults(func=_figures, uses_jax=False)  # the figures' own processes use it

    p = sub.add_parser("demo", help="render the Cornell box and write the figures into ./out")
    p.add_argument("--out", type=Path, default=Path("out"), help="output directory [./out]")
    p.add_argument("--spp", type=int, default=64, help="samples per pixel of the render [64]")
    p.add_argument("--smoke", action="store_true", help="small sample counts (CI)")
    p.set_defaults(func=_demo, uses_jax=False)  # the render's and figures' processes use it

    lut = sub.add_parser("lut", help="RGB-to-spectrum coefficient tables")
    lsub = lut.add_subparsers(dest="lut_command", required=True, metavar="ACTION")
    p = lsub.add_parser("build", help="fit a coefficient table")
    p.add_argument("--space", default="sRGB", help="RGB colour space name [sRGB]")
    p.add_argument("--res", type=int, default=64, help="table resolution [64]")
    p.add_argument("--out", type=Path, required=True, help="output file (.npz or .coeff)")
    p.set_defaults(func=_lut_build)
    p = lsub.add_parser("check", help="round-trip error statistics of a table")
    p.add_argument("file", type=Path, help="table file (.npz or .coeff)")
    p.add_argument("--grid", type=int, default=33, help="grid points per axis [33]")
    p.add_argument("--random", type=int, default=100_000, help="random colours [100000]")
    p.set_defaults(func=_lut_check)

    p = sub.add_parser("render", help="render a scene")
    p.add_argument("scene", help="'cornell-box', 'cornell-box-measured' or a scene file")
    p.add_argument(
        "--spp", type=int, default=None,
        help="samples per pixel [the scene file's sample_count, else 64]",
    )  # fmt: skip
    p.add_argument("--out", type=Path, required=True, help="output image (.exr or .png)")
    p.add_argument("--width", type=int, default=None, help="image width [scene's]")
    p.add_argument("--height", type=int, default=None, help="image height [scene's]")
    p.add_argument(
        "--seed", type=int, default=None, help="random seed [the scene file's sampler seed, else 0]"
    )
    p.add_argument("--max-depth", type=int, default=None, help="maximum path depth [scene's]")
    p.add_argument(
        "-D",
        dest="define",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="set a Mitsuba XML <default> parameter ($NAME in the file); repeatable",
    )
    p.add_argument(
        "--integrator",
        default=None,
        help="integrator plugin: 'path' or 'direct' (radiometria.render._registry) [scene's]",
    )
    p.add_argument(
        "--sampler",
        default=None,
        help="sampler plugin: 'sobol' (padded Owen-scrambled Sobol, the lowest error per unit "
        "time) or 'independent' [the scene file's sampler, else sobol]",
    )
    p.add_argument(
        "--checkpoint", default=None, help="checkpoint file [OUT.checkpoint.npz beside the output]"
    )
    p.add_argument(
        "--checkpoint-every", type=float, default=60.0, help="seconds between checkpoints [60]"
    )
    p.add_argument("--resume", action="store_true", help="continue from the checkpoint")
    p.add_argument(
        "--spectral",
        action="store_true",
        help="write the spectral radiance (47 bins of 10 nm, 360-830 nm) as a spectral OpenEXR "
        "(Fichet et al. 2021 layout, with an RGB preview); implied by OUT named *.spectral.exr",
    )
    p.add_argument(
        "--preview-every", type=float, default=None, help="rewrite OUT every S seconds [off]"
    )
    p.set_defaults(func=_render)

    cache = sub.add_parser("cache", help="the persistent compilation cache (info, clear)")
    csub = cache.add_subparsers(dest="cache_command", required=True, metavar="ACTION")
    for name, func, text in (
        ("info", _cache_info, "where the cache is, how many programs, how large"),
        ("clear", _cache_clear, "delete the compiled programs"),
    ):
        p = csub.add_parser(name, help=text)
        p.add_argument(
            "--dir", type=Path, default=None, help="cache directory [~/.cache/radiometria/jax]"
        )
        p.set_defaults(func=func, uses_jax=False)
    return parser


def _configure_cpu_devices(count: int | None) -> None:
    """Give XLA `count` CPU devices (default: one per core), so renders shard over all cores,
    and XLA:CPU's small-loop threshold (`cpu_xla_flags`).

    Sets both in `XLA_FLAGS` unless they are already set there. It takes effect only if JAX
    has not initialised its backends yet (true when the command starts); accelerators, when
    present, are used as they are (the CPU backend's options do not concern them).
    """
    count = count or os.cpu_count() or 1
    os.environ["XLA_FLAGS"] = cpu_xla_flags(os.environ.get("XLA_FLAGS", ""), count)


SMALL_LOOP_OPTION = "xla_cpu_small_while_loop_byte_threshold"
SMALL_LOOP_BYTES = 64 << 20  # `cpu_xla_flags`


def cpu_xla_flags(flags: str, device_count: int | None = None) -> str:
    """`XLA_FLAGS` for a process that renders on the CPU: `flags` plus
    `--xla_force_host_platform_device_count=<device_count>` (when given and not already set)
    and XLA:CPU's small-loop threshold `SMALL_LOOP_BYTES` as a backend extra option (added to
    the backend extra options `flags` may hold; not when `flags` already sets the threshold or
    `RADIOMETRIA_XLA_DEFAULTS` asks for XLA's defaults). Takes effect only if set before JAX
    initialises its backends; the command line and `benchmarks/` set it, a library user sets
    the same `XLA_FLAGS` (FAQ, "Which XLA options does the renderer compile with?").

    Why: XLA:CPU runs a program as a sequence of thunks, one per fusion, and pays a dispatch
    for each on every iteration of a `while` loop. A loop whose buffers are small (below
    `xla_cpu_small_while_loop_byte_threshold` bytes of HLO cost analysis, 1024 by default)
    and that holds no custom call, scatter or sort is compiled instead into one function that
    runs the whole loop. The tracking loops of a heterogeneous medium (loops of 2048, 256 and
    32 paths walking majorant cells, `radiometria.media.GridMedium`) are such loops, above the
    default: `bench_media.py`'s heterogeneous scene (128 x 128, 16 spp, two CPU devices, warm;
    measured when the walks ran in single loops of 256 paths) renders in 0.69 s with a
    threshold of 4 MiB against 1.09 s with the default, the same image. The
    density grid counts in a tracking loop's cost: a 64^3 grid stays below 4 MiB
    (`trilinear_lookup` reads it by one gather), a 128^3 grid needs more (the same scene with
    a 128^3 grid: 1.03 s at 4 MiB, 0.92 s at 32 MiB, 0.88 s at 64 MiB). The Cornell box,
    textured, environment-map and homogeneous-medium scenes of `benchmarks/` render in the
    same time or faster at 64 MiB (0.20, 0.25, 0.33, 0.34 s against 0.20, 0.27, 0.36, 0.37 s
    at 4 MiB); the batch-wide table searches they run are unrolled (`_math.interp_columns`),
    not loops that a larger threshold would hoist.
    The threshold is a backend extra option, which `jax.jit`'s `compiler_options` cannot set,
    so it travels in `XLA_FLAGS`.
    """
    out = flags.strip()
    if device_count is not None and "xla_force_host_platform_device_count" not in out:
        out = f"{out} --xla_force_host_platform_device_count={int(device_count)}"
    # RADIOMETRIA_XLA_DEFAULTS as radiometria._xla reads it (that module imports JAX).
    wants_defaults = os.environ.get("RADIOMETRIA_XLA_DEFAULTS", "").strip().lower()
    if wants_defaults not in ("", "0", "false", "no") or SMALL_LOOP_OPTION in out:
        return out.strip()
    option = f"{SMALL_LOOP_OPTION}={SMALL_LOOP_BYTES}"
    words = out.split()
    for i, word in enumerate(words):  # the user's extra options keep theirs, and get ours
        if word.startswith("--xla_backend_extra_options="):
            words[i] = f"{word},{option}" if word.split("=", 1)[1] else f"{word}{option}"
            return " ".join(words)
    return f"{out} --xla_backend_extra_options={option}".strip()


def entry() -> None:
    """The `radiometria` console command (and `python -m radiometria`): `main`, then the
    process ends at once once its output is flushed.

    Python's normal exit tears down what the render built: XLA's compiled programs, its
    thread pools and clients, the modules of JAX and of the renderer. That took 0.3-0.4 s of
    a 2-2.5 s warm `radiometria render cornell-box --spp 16` (2 cores), time in which the
    user waits for the prompt while nothing is left to do: the image and any checkpoint are
    written (atomically) and the compilation caches are written when programs compile.
    So, after flushing the standard streams and the logging handlers, the command exits
    with `os._exit`. It exits the usual way where JAX is not loaded (nothing to skip) or
    runs several processes (`jax.distributed`, whose shutdown other processes wait for).
    """
    status = main()
    sys.stdout.flush()
    sys.stderr.flush()
    if "logging" in sys.modules:  # its handlers flush and close at a normal exit
        sys.modules["logging"].shutdown()
    if "jax" not in sys.modules or _distributed():
        sys.exit(status)
    os._exit(status)


def _distributed() -> bool:
    """Whether this process joined a `jax.distributed` cluster (True where unknown)."""
    state = getattr(sys.modules.get("jax._src.distributed"), "global_state", None)
    return state is None or getattr(state, "client", True) is not None


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `radiometria` command; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.cpu_devices is not None and args.cpu_devices < 1:
        parser.error(f"--cpu-devices must be a positive integer, got {args.cpu_devices}")
    _configure_cpu_devices(args.cpu_devices)
    if args.timing:
        os.environ[TIMING_ENV] = "1"
    mark("arguments parsed")
    try:
        if getattr(args, "uses_jax", True) and not args.no_cache and args.func is _render:
            from ._warmstart import cache_disabled, cache_root, enable_jax_cache

            if not cache_disabled():  # the renderer is imported only if the step cache misses
                enable_jax_cache(cache_root() / "jax")
            mark("imports (jax) and the compilation cache")
        elif getattr(args, "uses_jax", True) and not args.no_cache:
            from .render import enable_compilation_cache

            enable_compilation_cache()
            mark("imports (jax, radiometria.render) and the compilation cache")
        return int(args.func(args) or 0)
    except (ValueError, TypeError, OSError) as err:
        print(f"radiometria: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        # Ctrl-C: stop without a traceback (128 + SIGINT, the shell's convention).
        print("radiometria: interrupted", file=sys.stderr)
        return 130
