"""Building the native ray-casting kernels' library, without importing JAX (thesis ch. 8).

`radiometria.render._geometry._native` loads the library and registers its kernels with
XLA; this module only compiles it, so that the command line can start the compiler before it
imports JAX and the renderer (`prebuild`). The library is compiled with the system's C++
compiler (`$CXX`, else `c++`, `g++` or `clang++`) against the FFI headers that ship with
jaxlib, as two translation units at once (the float32 and the float64 kernels: 2.3 s instead
of 4.2 s on 2 cores), linked into one, and cached in `$RADIOMETRIA_CACHE_DIR` (default
`radiometria._io.cache_root()`: `$XDG_CACHE_HOME/radiometria`, else `~/.cache/radiometria`)
under a name that hashes the source, the flags, the compiler, jaxlib's version and the host
CPU. It is written to a temporary file and renamed into place
(`radiometria._io.atomic_write_path`), so concurrent processes never load a partial file.
"""

import hashlib
import importlib.metadata
import importlib.util
import os
import platform
import shutil
import subprocess
import tempfile
import threading
from concurrent.futures import Future
from pathlib import Path

from ._io import atomic_write_path, cache_root, default_file_mode

__all__ = ["FLAGS", "SOURCE", "build", "compiler", "disabled", "library_path", "prebuild"]

# The kernels' source (its own floor is `render._geometry`, which loads the library).
SOURCE = Path(__file__).parent / "render" / "_geometry" / "_csrc" / "bvh_traverse.cc"
# -ffp-contract=off: no fused multiply-adds, every operation rounds as written (the results do
# not depend on the compiler); -fno-trapping-math lets the brute force's branch-free loop be
# vectorised (it changes no result, only what may be assumed about floating-point traps).
FLAGS = (
    "-O3",
    "-std=c++17",
    "-shared",
    "-fPIC",
    "-ffp-contract=off",
    "-fno-trapping-math",
    "-march=native",
) + (
    # x86: GCC and Clang default to 256-bit vectors even where AVX-512 is there; the brute
    # force's loops are sized for 16 lanes (any-hit queries on the Cornell box, one core:
    # 53.7 -> 46.5 ns per ray). No effect on CPUs without AVX-512.
    ("-mprefer-vector-width=512",) if platform.machine().lower() in ("x86_64", "amd64") else ()
)


def compiler() -> str | None:
    for name in (os.environ.get("CXX"), "c++", "g++", "clang++"):
        if name and (path := shutil.which(name)):
            return path
    return None


def _jaxlib_include_dir() -> str:
    """The FFI headers bundled with jaxlib (`jax.ffi.include_dir()`), found without importing
    jaxlib."""
    spec = importlib.util.find_spec("jaxlib")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("jaxlib is not installed: no FFI headers to compile against")
    return os.path.join(list(spec.submodule_search_locations)[0], "include")


def _cache_dir() -> Path:
    if os.environ.get("RADIOMETRIA_CACHE_DIR"):
        return Path(os.environ["RADIOMETRIA_CACHE_DIR"])
    return cache_root()


def _cpu_signature() -> str:
    """The host CPU's model and feature flags (the library is built with -march=native)."""
    try:
        with open("/proc/cpuinfo") as fh:
            lines = [ln for ln in fh if ln.startswith(("model name", "flags"))]
        return "".join(sorted(set(lines)))
    except OSError:
        return platform.processor() + platform.machine()


def build(cxx: str) -> Path:
    """Compile the kernel (or find it in the cache) and return the shared library's path."""
    include = _jaxlib_include_dir()
    version = subprocess.run(
        [cxx, "--version"], capture_output=True, text=True, timeout=60, check=False
    ).stdout
    key = hashlib.sha256(
        b"\0".join(
            s.encode()
            for s in (
                SOURCE.read_text(),
                " ".join(FLAGS),
                version,
                importlib.metadata.version("jaxlib"),
                _cpu_signature(),
            )
        )
    ).hexdigest()[:20]
    cache = _cache_dir()
    target = cache / f"bvh_traverse-{key}.so"
    if target.exists():
        return target
    try:
        cache.mkdir(parents=True, exist_ok=True)
    except OSError:
        cache = Path(tempfile.gettempdir()) / "radiometria"
        cache.mkdir(parents=True, exist_ok=True)
        target = cache / target.name
        if target.exists():
            return target

    def compile_to(tmp: str) -> None:
        # The two halves of the kernels (float32, float64) as two translation units compiled
        # at once, then linked: the FFI headers' parsing and the code generation take most of
        # the time, and each half needs half of the latter.
        flags = [f for f in FLAGS if f != "-shared"]
        with tempfile.TemporaryDirectory() as work:
            objects = [os.path.join(work, f"part{part}.o") for part in (32, 64)]
            cmds = [
                [cxx, *flags, f"-DRADIOMETRIA_PART={part}", f"-I{include}", "-c", str(SOURCE),
                 "-o", obj]
                for part, obj in zip((32, 64), objects, strict=True)
            ]  # fmt: skip
            procs = [
                subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
                for cmd in cmds
            ]
            errors = [proc.communicate(timeout=600)[1] for proc in procs]
            for cmd, proc, err in zip(cmds, procs, errors, strict=True):
                if proc.returncode != 0:
                    raise RuntimeError(f"`{' '.join(cmd)}` failed:\n{err[-4000:]}")
            cmd = [cxx, "-shared", "-fPIC", *objects, "-o", tmp]
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600, check=False)
            if proc.returncode != 0:
                raise RuntimeError(f"`{' '.join(cmd)}` failed:\n{proc.stderr[-4000:]}")

    # atomic: other processes see the whole library or none
    atomic_write_path(target, compile_to, mode=default_file_mode(executable=True))
    return target


def disabled() -> bool:
    return os.environ.get("RADIOMETRIA_NATIVE", "1").strip().lower() in ("0", "false", "no")


_prebuilt: Future | None = None  # the library's path, from `prebuild`'s thread
_prebuild_lock = threading.Lock()


def prebuild() -> None:
    """Start building the kernel library (or finding it in the cache) in a background thread,
    once per process; `library_path` waits for it. The compiler then runs while the caller
    does other work: the command line calls it before importing JAX, so that a first render's
    build (about 3 s) overlaps the imports and the scene's loading. Does nothing when the
    kernels are disabled (`RADIOMETRIA_NATIVE=0`), no compiler is found, or `JAX_PLATFORMS`
    names platforms without the CPU (the kernels serve CPU renders only)."""
    global _prebuilt
    with _prebuild_lock:
        if _prebuilt is not None or disabled() or (cxx := compiler()) is None:
            return
        platforms = os.environ.get("JAX_PLATFORMS", "").strip()
        if platforms and "cpu" not in platforms.split(","):
            return
        future: Future = Future()

        def run() -> None:
            try:
                future.set_result(build(cxx))
            except BaseException as e:  # noqa: BLE001 - re-raised by library_path
                future.set_exception(e)

        threading.Thread(target=run, name="radiometria-native-build", daemon=True).start()
        _prebuilt = future


def library_path(cxx: str) -> Path:
    """The kernel library's path: `prebuild`'s (waiting for its thread) if it was started,
    else built (or found in the cache) now. Raises what the build raised."""
    with _prebuild_lock:
        future = _prebuilt
    return future.result() if future is not None else build(cxx)
