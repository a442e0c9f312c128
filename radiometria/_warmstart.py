"""A warm start of `radiometria render`: the render's step kept on disk, ready to run.

JAX's persistent compilation cache (`radiometria.render.enable_compilation_cache`) removes
XLA's compilation from a second render of a scene, but not what a process does to find the
cache key: import the renderer and its plugins, build the scene's arrays (dozens of small
eager JAX programs) and trace and lower the step in Python. The command line therefore also
keeps, per render configuration, one *step entry*:

- the step serialised with `jax.export` (StableHLO of the traced, lowered step whose inputs
  are the film's, the scene's and the strategies' arrays, flattened), and the film's
  development to RGB serialised the same way;
- the scene's arrays (the leaves of the render kernel: the compiled scene, camera, filter,
  colour-matching functions, integrator and sampler), so the scene is not compiled again;
- what the loop needs (the step layout, the image size, the film's initial arrays) and what
  the output needs (the EXR metadata, the checkpoint identity).

A later `radiometria render` with the same request loads the entry with JAX and NumPy only
(no renderer import, no scene compile, no trace), hands the deserialised step to `jax.jit`,
whose compiled program comes from JAX's persistent cache, and starts sampling. The image is
the one the first process rendered from the same entry, bit for bit, and the same as
`--no-cache` renders (tested).

The entry's name is a SHA-256 of the request: the scene (a built-in name, or a file's path and
the SHA-256 of its content), the `-D` parameters, the image size, integrator, sampler and
depth options, and the environment that changes the program: the Python, JAX and jaxlib
versions, a digest of radiometria's installed files (path, size, modification time), the
platform, device kind and count, the core count, and the variables `XLA_FLAGS`,
`EQX_ON_ERROR`, `RADIOMETRIA_NATIVE`. Files a scene reads besides its own (meshes, textures)
are listed in the entry with their size, modification time and SHA-256, and checked on load.
Entries are written atomically (temporary file, then rename) without pickles; on load the
request, the format, every member, the step's SHA-256 and the listed files are checked, and an
entry that fails is ignored with a logged warning (and rebuilt by that render).

The native ray-casting kernels (`radiometria.render._geometry._native`) are XLA custom calls:
the entry records the library file and its targets, and a warm start registers them before it
calls the step. `jax.export` refuses unknown custom calls unless told; the step is exported
with those targets allowed, which is sound for the jaxlib the library was compiled against,
which the request's versions pin.

This module imports only JAX, NumPy and floor-1 helpers, so that a warm start does not import
the renderer.
"""

import contextlib
import ctypes
import functools
import hashlib
import json
import logging
import os
import platform
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import jax
import jax.monitoring
import jaxlib
import numpy as np
from jax import export as jax_export
from jax._src.export import _export as _jax_export_impl
from jax.experimental.compilation_cache import compilation_cache as _jax_cache
from jax.sharding import Mesh, NamedSharding, PartitionSpec as P
from tqdm import tqdm

from ._io import atomic_write, cache_root
from ._timing import mark
from ._xla import jit_options

__all__ = [
    "NO_CACHE_ENV",
    "StepEntry",
    "cache_disabled",
    "cache_root",
    "check_int",
    "check_output",
    "enable_jax_cache",
    "exported_step_caller",
    "Interrupts",
    "jax_activity",
    "load_entry",
    "paths_of_step",
    "recording_opened_files",
    "render_request",
    "render_settings",
    "run_entry",
    "save_entry",
    "spp_reached",
    "step_cache_clear",
    "step_cache_info",
    "tile_order",
]

NO_CACHE_ENV = "RADIOMETRIA_NO_CACHE"
FORMAT = 1
_PREFIX, _SUFFIX = "step-", ".npz"
_PACKAGE = Path(__file__).resolve().parent
_ENV_KEYS = ("XLA_FLAGS", "EQX_ON_ERROR", "RADIOMETRIA_NATIVE", "JAX_ENABLE_X64")
log = logging.getLogger("radiometria")


def cache_disabled() -> bool:
    """Whether `RADIOMETRIA_NO_CACHE` is set to anything but `""`, `0`, `false` or `no`."""
    return os.environ.get(NO_CACHE_ENV, "").strip().lower() not in ("", "0", "false", "no")


def enable_jax_cache(path: Path, min_compile_time_s: float = 0.0) -> Path:
    """Point JAX's persistent compilation cache at `path` (created with mode 0700)."""
    path = Path(path).expanduser().absolute()
    try:
        path.mkdir(parents=True, exist_ok=True, mode=0o700)
    except OSError as err:
        raise OSError(
            f"Cannot create the compilation cache directory {str(path)!r}: {err.strerror or err}."
        ) from None
    if jax.config.jax_compilation_cache_dir != str(path):
        _jax_cache.reset_cache()  # JAX opens its cache once per process; reopen it at the new path
    jax.config.update("jax_compilation_cache_dir", str(path))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", float(min_compile_time_s))
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    return path


# ---------------------------------------------------------------------------------------------
# The render command's arguments (checked before anything is imported or rendered).

IMAGE_FORMATS = (".exr", ".png")
MAX_IMAGE_SIDE = 16384  # px: the command line refuses larger images (the library checks memory)


def check_output(path: Path) -> Path:
    """The output must be .exr/.png in an existing, writable directory (probed, then removed)."""
    path = Path(path)
    if path.suffix.lower() not in IMAGE_FORMATS:
        got = path.suffix or "no extension"
        raise ValueError(f"Output {str(path)!r} must end in .exr or .png (got {got!r}).")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise OSError(f"Cannot write {str(path)!r}: directory {str(parent)!r} does not exist.")
    if path.is_dir():
        raise OSError(f"Cannot write {str(path)!r}: it is a directory.")
    try:
        fd, probe = tempfile.mkstemp(prefix=".radiometria-probe-", dir=parent)
        os.close(fd)
        os.unlink(probe)
    except OSError as err:
        raise OSError(f"Cannot write {str(path)!r}: {err.strerror or err}.") from None
    if path.exists() and not os.access(path, os.W_OK):
        raise OSError(f"Cannot write {str(path)!r}: the file is not writable.")
    return path


def check_int(value, name: str, low: int, high: int | None = None) -> int | None:
    """`value` (an int in [low, high], or None), else a TypeError / ValueError naming the
    option `--name`."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError(f"--{name.replace('_', '-')} must be an integer, got {value!r}.")
    if value < low or (high is not None and value > high):
        bound = f">= {low}" if high is None else f"in [{low}, {high}]"
        raise ValueError(f"--{name.replace('_', '-')} must be {bound}, got {value}.")
    return value


def is_spectral(path: Path, spectral: bool) -> bool:
    """Whether the output is a spectral EXR (`--spectral` or a name ending `.spectral.exr`)."""
    named = path.name.lower().endswith(".spectral.exr")
    if (spectral or named) and path.suffix.lower() != ".exr":
        raise ValueError(f"--spectral writes OpenEXR: output {str(path)!r} must end in .exr.")
    return spectral or named


def parse_defines(items) -> dict[str, str]:
    """`-D name=value` options as a dict (Mitsuba's flag for `<default>` parameters)."""
    out = {}
    for item in items or ():
        name, sep, value = str(item).partition("=")
        if not sep or not name.strip() or any(c.isspace() or c == "$" for c in name):
            raise ValueError(f"-D expects NAME=VALUE (e.g. -D spp=64), got {item!r}.")
        out[name] = value
    return out


@dataclass(frozen=True)
class RenderSettings:
    """`radiometria render`'s checked arguments (see `render_settings`); `spp` and `seed` are
    `None` where the command line leaves them to the scene (`with_scene_defaults`)."""

    spp: int | None
    width: int | None
    height: int | None
    seed: int | None
    max_depth: int | None
    out: Path
    spectral: bool
    checkpoint: Path
    defines: dict


def render_settings(args) -> RenderSettings:
    """Check `radiometria render`'s arguments (an `argparse.Namespace`); raise a ValueError,
    TypeError or OSError naming the option and the valid range."""
    spp = check_int(args.spp, "spp", 1)
    width = check_int(args.width, "width", 1, MAX_IMAGE_SIDE)
    height = check_int(args.height, "height", 1, MAX_IMAGE_SIDE)
    seed = check_int(args.seed, "seed", 0, 2**31 - 1)
    max_depth = check_int(args.max_depth, "max_depth", 1, 1024)
    out = check_output(args.out)
    spectral = is_spectral(out, bool(getattr(args, "spectral", False)))
    if spectral and (args.checkpoint or args.resume):
        raise ValueError(
            "--spectral cannot be combined with --checkpoint or --resume (checkpoints hold the "
            "RGB film only)."
        )
    for name in ("checkpoint_every", "preview_every"):
        value = getattr(args, name)
        if value is not None and not value >= 0:
            raise ValueError(f"--{name.replace('_', '-')} must be >= 0 [s], got {value}.")
    checkpoint = (
        Path(args.checkpoint) if args.checkpoint else out.with_name(out.name + ".checkpoint.npz")
    )
    defines = parse_defines(getattr(args, "define", None))
    return RenderSettings(spp, width, height, seed, max_depth, out, spectral, checkpoint, defines)


#: Samples per pixel of a scene that names no sampler `sample_count` (the command line's).
DEFAULT_SPP = 64


def with_scene_defaults(opts: RenderSettings, scene: dict) -> RenderSettings:
    """`opts` with the spp and seed the command line left open taken from the scene file's
    sampler (`scene`: `{"spp": ..., "seed": ...}`, values `None` where the file has none),
    else `DEFAULT_SPP` and 0."""
    spp = opts.spp if opts.spp is not None else scene.get("spp") or DEFAULT_SPP
    seed = opts.seed if opts.seed is not None else scene.get("seed") or 0
    return replace(opts, spp=int(spp), seed=int(seed))


# ---------------------------------------------------------------------------------------------
# The request: what an entry must match.


def _sha256_file(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _package_digest() -> str:
    """SHA-256 over radiometria's files: relative path, size and modification time [ns]."""
    digest = hashlib.sha256()
    for root, dirs, files in os.walk(_PACKAGE):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        for name in sorted(files):
            st = os.stat(os.path.join(root, name))
            rel = os.path.relpath(os.path.join(root, name), _PACKAGE)
            digest.update(f"{rel}\0{st.st_size}\0{st.st_mtime_ns}\n".encode())
    return digest.hexdigest()


def render_request(scene: str, options: dict) -> dict:
    """The request a step entry is named by and must match (see the module docstring).

    **Arguments:**

    - `scene`: the command's scene argument (a built-in name or a file path).
    - `options`: the command's options that change the program or the scene's arrays (image
        size, integrator, sampler, depth, `-D` parameters), JSON-serialisable.
    """
    path = Path(scene)
    if path.is_file():
        scene_id = {"file": str(path.resolve()), "sha256": _sha256_file(path)}
    else:
        scene_id = {"name": str(scene)}
    devices = jax.local_devices()
    return {
        "format": FORMAT,
        "scene": scene_id,
        "options": options,
        "python": sys.version,
        "jax": jax.__version__,
        "jaxlib": jaxlib.__version__,
        "radiometria": _package_digest(),
        "platform": [platform.machine(), devices[0].platform, devices[0].device_kind],
        "devices": len(devices),
        "processes": jax.process_count(),
        "cores": os.cpu_count(),
        "x64": bool(jax.config.jax_enable_x64),
        "prng": str(jax.config.jax_default_prng_impl),
        "env": {k: os.environ.get(k) for k in _ENV_KEYS},
    }


def _entry_path(directory: Path, request: dict) -> Path:
    name = hashlib.sha256(json.dumps(request, sort_keys=True).encode()).hexdigest()[:40]
    return Path(directory) / f"{_PREFIX}{name}{_SUFFIX}"


# ---------------------------------------------------------------------------------------------
# Entries on disk.


@dataclass(frozen=True)
class StepEntry:
    """A step entry, loaded and checked.

    **Fields:**

    - `meta`: the entry's description (JSON): layout (`n_pixels`, `tile`, `passes`,
        `n_tiles`, `width`, `height`), `metadata` (for the image file), `identity` (for
        checkpoints, without seed and spp), `native` (library and targets, or `None`).
    - `step`, `develop`: the serialised step and development (`jax.export`).
    - `kernel`: the kernel's leaves (NumPy arrays).
    - `film`: the empty film's leaves (NumPy arrays).
    """

    meta: dict
    step: bytes
    develop: bytes
    kernel: list
    film: list


def _dependency(path: str) -> dict:
    st = os.stat(path)
    return {
        "path": path,
        "size": st.st_size,
        "mtime_ns": st.st_mtime_ns,
        "sha256": _sha256_file(Path(path)),
    }


def save_entry(
    directory: Path,
    request: dict,
    *,
    step: bytes,
    develop: bytes,
    kernel: list,
    film: list,
    meta: dict,
    dependencies=(),
) -> Path | None:
    """Write a step entry atomically; `None` (with a logged warning) when it cannot be.

    **Arguments:**

    - `directory`: the step cache directory.
    - `request`: `render_request(...)`.
    - `step`, `develop`: serialised `jax.export` programs.
    - `kernel`, `film`: leaves (arrays of numeric dtypes).
    - `meta`: JSON-serialisable description (see `StepEntry`).
    - `dependencies`: files the scene read besides its own file (their size, time and
        SHA-256 are recorded).
    """
    path = _entry_path(directory, request)
    try:
        arrays = {}
        for prefix, leaves in (("kernel", kernel), ("film", film)):
            for i, leaf in enumerate(leaves):
                a = np.asarray(leaf)
                if a.dtype.kind not in "biuf" or a.dtype.hasobject:
                    raise TypeError(f"{prefix} leaf {i} has dtype {a.dtype}")
                arrays[f"{prefix}_{i:04d}"] = a
        full = {
            **meta,
            "request": request,
            "n_kernel": len(kernel),
            "n_film": len(film),
            "step_sha256": hashlib.sha256(step).hexdigest(),
            "develop_sha256": hashlib.sha256(develop).hexdigest(),
            "dependencies": [_dependency(p) for p in sorted(set(dependencies))],
        }
        arrays["meta"] = np.asarray(json.dumps(full, sort_keys=True))
        arrays["step"] = np.frombuffer(step, np.uint8)
        arrays["develop"] = np.frombuffer(develop, np.uint8)
        Path(directory).mkdir(parents=True, exist_ok=True, mode=0o700)
        atomic_write(path, lambda f: np.savez(f, **arrays), mode=0o600)
    except (OSError, TypeError, ValueError) as err:
        log.warning("radiometria: step cache: not written (%s): %s", path, err)
        return None
    return path


def _check_entry(path: Path, request: dict) -> StepEntry:
    with open(path, "rb") as f, np.load(f, allow_pickle=False) as z:
        meta = json.loads(str(z["meta"][()]))
        if meta.get("request") != request:
            raise ValueError("its request differs from this render's (hash collision?)")
        step, develop = z["step"].tobytes(), z["develop"].tobytes()
        for name, blob in (("step", step), ("develop", develop)):
            if hashlib.sha256(blob).hexdigest() != meta[f"{name}_sha256"]:
                raise ValueError(f"the {name} program's SHA-256 differs from the recorded one")
        kernel = [z[f"kernel_{i:04d}"] for i in range(meta["n_kernel"])]
        film = [z[f"film_{i:04d}"] for i in range(meta["n_film"])]
    for dep in meta["dependencies"]:
        st = os.stat(dep["path"])  # FileNotFoundError: a file the scene read has gone
        if (st.st_size, st.st_mtime_ns) != (dep["size"], dep["mtime_ns"]) and _sha256_file(
            Path(dep["path"])
        ) != dep["sha256"]:
            raise ValueError(f"{dep['path']} has changed since the entry was written")
    native = meta.get("native")
    if native is not None and not Path(native["library"]).is_file():
        raise ValueError(f"the native kernel library {native['library']} is missing")
    return StepEntry(meta, step, develop, kernel, film)


def load_entry(directory: Path, request: dict) -> StepEntry | None:
    """The step entry for `request`, or `None`: missing, or ignored with a logged warning
    when it is unreadable, corrupt or stale (a file it depends on has changed)."""
    path = _entry_path(directory, request)
    if not path.is_file():
        return None
    try:
        return _check_entry(path, request)
    except Exception as err:  # noqa: BLE001 - any failure: ignore the entry, render anew
        log.warning(
            "radiometria: step cache: ignoring %s (%s: %s); it will be rebuilt",
            path,
            type(err).__name__,
            err,
        )
        return None


def _entries(directory: Path) -> list[Path]:
    directory = Path(directory)
    if not directory.is_dir():
        return []
    return [
        p
        for p in directory.iterdir()
        if p.is_file() and p.name.startswith(_PREFIX) and p.name.endswith(_SUFFIX)
    ]


def step_cache_info(directory: Path) -> tuple[int, int]:
    """`(entries, bytes)` of a step cache directory (0, 0 when missing)."""
    files = _entries(directory)
    return len(files), sum(p.stat().st_size for p in files)


def step_cache_clear(directory: Path) -> int:
    """Delete the step entries (`step-<hash>.npz` only) of a directory; return how many."""
    removed = 0
    for p in _entries(directory):
        try:
            p.unlink()
        except FileNotFoundError:  # another process removed it first
            continue
        removed += 1
    return removed


# ---------------------------------------------------------------------------------------------
# Running an entry.


def register_native(native: dict | None) -> None:
    """Load the native kernel library an entry names and register its FFI targets."""
    if native is None:
        return
    lib = ctypes.cdll.LoadLibrary(native["library"])
    _LOADED.append(lib)  # keep it loaded
    for symbol in native["targets"]:
        jax.ffi.register_ffi_target(symbol, jax.ffi.pycapsule(getattr(lib, symbol)), platform="cpu")


_LOADED: list = []


@contextlib.contextmanager
def _without_lapack_setup():
    """Within `with`: lowering a deserialised program skips JAX's LAPACK set-up.

    JAX lowers every exported program for the CPU after loading its LAPACK kernels, which
    imports `scipy.linalg` (about 0.45 s, more than the rest of a warm start's lowering). A
    step that calls no LAPACK kernel (checked when it is exported: `uses_lapack`) does not
    need them. (`jax._src.export._export._ensure_backends_initialized` is private; without it
    nothing is skipped.)
    """
    original = getattr(_jax_export_impl, "_ensure_backends_initialized", None)
    if original is None:
        yield
        return
    _jax_export_impl._ensure_backends_initialized = lambda platforms: None
    try:
        yield
    finally:
        _jax_export_impl._ensure_backends_initialized = original


def uses_lapack(module_text: str) -> bool:
    """Whether a program's StableHLO text calls a LAPACK kernel (custom calls `lapack_*`)."""
    return "lapack" in module_text.lower()


def exported_caller(
    blob: bytes, *, donate: int = 0, lapack: bool = True, platform: str | None = None
) -> Callable:
    """The deserialised `jax.export` program `blob` under `jax.jit`, donating its first
    `donate` arguments and compiled with the renderer's XLA options for `platform` (default:
    JAX's default backend; `radiometria._xla`); with `lapack=False` its lowering skips JAX's
    LAPACK set-up."""
    options = jit_options(platform or jax.default_backend())
    call = jax.jit(
        jax_export.deserialize(bytearray(blob)).call, donate_argnums=range(donate), **options
    )
    if lapack:
        return call

    def call_without_lapack(*args):
        with _without_lapack_setup():
            return call(*args)

    return call_without_lapack


def exported_step_caller(
    blob: bytes, n_film: int, *, lapack: bool = True, platform: str | None = None
) -> Callable:
    """`call(*film, *kernel, key_data, spp, pass_start, pixel) -> film` for a serialised step:
    the deserialised program under `jax.jit` (`exported_caller`), donating the film's arrays."""
    return exported_caller(blob, donate=n_film, lapack=lapack, platform=platform)


@functools.lru_cache(maxsize=8)
def tile_order(tile: int, n_devices: int) -> np.ndarray:
    """The order of a tile's pixels `0 .. tile - 1` in a step's `pixel` array, which the
    `n_devices` devices split into contiguous shares: device `d` gets pixels `d, d + n,
    d + 2 n, ...` (increasing), so that every device's share spreads over the whole tile and
    the devices get equal work (with contiguous shares one device got the sky and the other
    the floor of the textured benchmark scene, and in a profile the first waited at the
    film's reduction for a third of the render), and each share is one regular lattice, on
    which the step adds its samples' filter footprints into the film with dense shifted adds
    (`render._driver._band`).
    `tile` is a multiple of `n_devices`."""
    if tile % n_devices:
        raise ValueError(f"a tile of {tile} pixels does not split over {n_devices} devices.")
    order = np.arange(tile, dtype=np.int32).reshape(tile // n_devices, n_devices).T.ravel()
    order.flags.writeable = False
    return order


def paths_of_step(n_pixels: int, tile: int, passes: int, n_tiles: int, i: int, spp: int) -> int:
    """Paths traced by step `i`: its pixels in the image x its passes below spp."""
    group, t = divmod(i, n_tiles)
    pixels = min(tile, n_pixels - t * tile)
    return pixels * max(0, min(passes, spp - group * passes))


def spp_reached(passes: int, n_tiles: int, steps_done: int, spp: int) -> int:
    """Samples per pixel every pixel has after `steps_done` steps (whole pass groups)."""
    return min(spp, (steps_done // n_tiles) * passes)


class Interrupts:
    """Within `with`: SIGINT and SIGTERM set `received` instead of stopping the process at
    once, so a render ends after the step in flight (main thread only; else a no-op)."""

    def __init__(self):
        self.received = None
        self._old = {}

    def _handle(self, signum, frame):
        self.received = signal.Signals(signum).name

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._old[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)
        return False


def run_entry(
    entry: StepEntry,
    *,
    spp: int,
    seed: int,
    progress: bool = True,
    checkpoint_every: float | None = None,
    on_checkpoint: Callable | None = None,
):
    """Render from a step entry: the loop of `radiometria.render.render` (same steps, same
    order, same programs) without the renderer.

    **Arguments:**

    - `entry`: a loaded `StepEntry`.
    - `spp`, `seed`: samples per pixel and the seed, as `render`'s.
    - `progress`: show a tqdm progress bar on stderr.
    - `checkpoint_every`, `on_checkpoint`: every `checkpoint_every` seconds [s], and when
        interrupted before the end, `on_checkpoint(xyz_sum, weight_sum, steps_done)`.

    **Returns:**

    `(image, spp_reached, signal_name)`: the developed image (NumPy), the samples per pixel
    every pixel has, and `"SIGINT"` / `"SIGTERM"` when a signal stopped the render early
    (else `None`).
    """
    meta = entry.meta
    register_native(meta["native"])
    devices = jax.local_devices()
    if len(devices) != meta["request"]["devices"]:
        raise ValueError(f"the entry is for {meta['request']['devices']} devices")
    replicated = NamedSharding(Mesh(np.asarray(devices), ("pixels",)), P())
    kernel = [jax.device_put(x) for x in entry.kernel]
    film = [jax.device_put(x, replicated) for x in entry.film]
    key_data = jax.random.key_data(jax.random.key(int(seed)))
    platform = devices[0].platform
    step = exported_step_caller(entry.step, len(film), lapack=meta["lapack"], platform=platform)
    develop = exported_caller(entry.develop, lapack=meta["lapack"], platform=platform)
    n_pixels, tile, passes, n_tiles = (meta[k] for k in ("n_pixels", "tile", "passes", "n_tiles"))
    n_steps = n_tiles * -(-spp // passes)
    spp_arr = np.int32(spp)
    serialise = len(devices) > 1 and devices[0].platform == "cpu"  # as `render` (deadlock)
    bar = (
        tqdm(total=n_pixels * spp, desc="render", unit="path", unit_scale=True, file=sys.stderr)
        if progress
        else None
    )
    xyz_i, weight_i = meta["film_xyz_sum"], meta["film_weight_sum"]
    last_checkpoint = time.monotonic()
    done = 0
    with Interrupts() as signals:
        for i in range(n_steps):
            group, t = divmod(i, n_tiles)
            pixel = tile_order(tile, len(devices)) + np.int32(t * tile)
            film = step(*film, *kernel, key_data, spp_arr, np.int32(group * passes), pixel)
            if i == 0:
                mark("first step dispatched" + jax_activity.summary())
            if serialise or on_checkpoint is not None:
                film = jax.block_until_ready(film)
            done = i + 1
            if bar is not None:
                bar.update(paths_of_step(n_pixels, tile, passes, n_tiles, i, spp))
            now = time.monotonic()
            stop = signals.received is not None
            if on_checkpoint is not None and (stop or now - last_checkpoint >= checkpoint_every):
                if done < n_steps:
                    on_checkpoint(film[xyz_i], film[weight_i], done)
                last_checkpoint = now
            if stop:
                break
    if bar is not None:
        bar.close()
    image = np.asarray(develop(*film))
    stopped = signals.received if done < n_steps else None
    return image, spp_reached(passes, n_tiles, done, spp), stopped


_RECORDING: list[tuple[int, set]] = []  # (thread, files) of each open recording
_HOOKED: list[bool] = []


def _audit(event: str, args) -> None:
    if event == "open" and _RECORDING and isinstance(args[0], str | bytes | os.PathLike):
        thread, files = _RECORDING[-1]
        if threading.get_ident() == thread:
            files.add(os.path.abspath(os.fsdecode(args[0])))


@contextlib.contextmanager
def recording_opened_files():
    """Within `with`: the set it yields collects every file opened (Python's `open` audit
    event) by the thread that entered it, less radiometria's own and the Python installation's
    files (the request's versions cover those); what a scene reads besides its own file
    (meshes, textures). Other threads' files are not the scene's: the native kernel's
    background build (`prebuild`) reads `/proc/cpuinfo`, whose clock readings change."""
    if not _HOOKED:
        sys.addaudithook(_audit)
        _HOOKED.append(True)
    files: set = set()
    _RECORDING.append((threading.get_ident(), files))
    try:
        yield files
    finally:
        _RECORDING.pop()
        skip = {os.path.abspath(p) for p in (sys.prefix, sys.base_prefix, _PACKAGE)}
        kept = {
            f
            for f in files
            if os.path.isfile(f)
            and not f.endswith((".py", ".pyc"))  # code: imports, tracebacks, test tools
            and not any(f.startswith(d + os.sep) for d in skip)
        }
        files.clear()
        files.update(kept)


# ---------------------------------------------------------------------------------------------
# What JAX did (for `--timing`).

# JAX's monitoring events (jax._src.dispatch, jax._src.compiler): Python tracing of a jitted
# function, its lowering to StableHLO, XLA's compilation, and a load from the persistent cache.
_TRACE_EVENT = "/jax/core/compile/jaxpr_trace_duration"
_LOWER_EVENT = "/jax/core/compile/jaxpr_to_mlir_module_duration"
_COMPILE_EVENT = "/jax/core/compile/backend_compile_duration"
_CACHE_LOAD_EVENT = "/jax/compilation_cache/cache_retrieval_time_sec"
_KINDS = {_TRACE_EVENT: "traced", _LOWER_EVENT: "lowered", _COMPILE_EVENT: "compiled",
          _CACHE_LOAD_EVENT: "loaded from the cache"}  # fmt: skip


class _JaxActivity:
    """Counts and seconds of JAX's tracing, lowering, compiling and cache loads since the last
    `summary()`; events longer than `loud_s` are marked (`radiometria._timing.mark`) as they
    end, so the first render step's trace and compile or load show with timestamps."""

    loud_s = 0.05  # s

    def __init__(self):
        self._lock = threading.Lock()
        self._counts: dict[str, list] = {}
        self._registered = False

    def start(self) -> None:
        with self._lock:
            if not self._registered:
                jax.monitoring.register_event_duration_secs_listener(self._on_duration)
                self._registered = True

    def _on_duration(self, event: str, duration: float, **kwargs) -> None:
        kind = _KINDS.get(event)
        if kind is None:
            return
        with self._lock:
            count = self._counts.setdefault(kind, [0, 0.0])
            count[0] += 1
            count[1] += duration
        if duration >= self.loud_s:
            name = kwargs.get("fun_name")
            mark(f"  jax: {kind} {name + ' ' if name else ''}in {duration:.3f} s")

    def summary(self) -> str:
        """`"jax: 12 traced 0.210 s, ..."` since the last summary (empty if nothing ran)."""
        with self._lock:
            counts, self._counts = self._counts, {}
        parts = [f"{n} {kind} {s:.3f} s" for kind, (n, s) in counts.items()]
        return f"  [jax: {', '.join(parts)}]" if parts else ""


jax_activity = _JaxActivity()
"""The process's `_JaxActivity` recorder (`start()` registers it with `jax.monitoring`)."""
