"""Building the native ray-casting kernels' libraries, without importing JAX (thesis ch. 8).

`radiometria.render._geometry._native` loads the libraries and registers their kernels with
XLA; this module only compiles them, so that the command line can start the compiler before
it imports JAX and the renderer (`prebuild`). The float32 kernels (what the renderer runs) and
the float64 ones (the library's float64 users and tests) are two libraries, each built when
first needed: a render compiles only the float32 one (one translation unit, 3.4 s on one core),
while the other core loads the scene, instead of both at once competing with it (3.8-4.2 s on
an idle 2-core machine, longer beside the scene's loading). Each is compiled with the system's
C++ compiler (`$CXX`, else `c++`, `g++` or `clang++`) against the FFI headers that ship with
jaxlib and cached in `$RADIOMETRIA_CACHE_DIR` (default `radiometria._io.cache_root()`:
`$XDG_CACHE_HOME/radiometria`, else `~/.cache/radiometria`) under a name that hashes the
source, the flags, the compiler, jaxlib's version and the host CPU. It is written to a
temporary file and renamed into place (`radiometria._io.atomic_write_path`), so concurrent
processes never load a partial file.
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

__all__ = [
    "FLAGS",
    "PARTS",
    "SOURCE",
    "build",
    "compiler",
    "disabled",
    "library_path",
    "prebuild",
]

# The kernels' source (its own floor is `render._geometry`, which loads the libraries).
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


# The libraries: the float32 kernels and the float64 ones (`-DRADIOMETRIA_PART=32`, `=64`).
PARTS = (32, 64)


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


def build(cxx: str, part: int = 32) -> Path:
    """Compile the float`part` kernels' library (`part` in `PARTS`), or find it in the cache,
    and return its path."""
    if part not in PARTS:
        raise ValueError(f"`part` must be one of {PARTS}, got {part!r}.")
    include = _jaxlib_include_dir()
    version = subprocess.run(
        [cxx, "--version"], capture_output=True, text=True, timeout=60, check=False
    ).stdout
    flags = (*FLAGS, f"-DRADIOMETRIA_PART={part}")
    key = hashlib.sha256(
        b"\0".join(
            s.encode()
            for s in (
                SOURCE.read_text(),
                " ".join(flags),
                version,
                importlib.metadata.version("jaxlib"),
                _cpu_signature(),
            )
        )
    ).hexdigest()[:20]
    cache = _cache_dir()
    target = cache / f"bvh_traverse-f{part}-{key}.so"
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
        cmd = [cxx, *flags, f"-I{include}", str(SOURCE), "-o", tmp]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600, check=False)
        if proc.returncode != 0:
            raise RuntimeError(f"`{' '.join(cmd)}` failed:\n{proc.stderr[-4000:]}")

    # atomic: other processes see the whole library or none
    atomic_write_path(target, compile_to, mode=default_file_mode(executable=True))
    return target


def disabled() -> bool:
    return os.environ.get("RADIOMETRIA_NATIVE", "1").strip().lower() in ("0", "false", "no")


_prebuilt: dict[int, Future] = {}  # each part's library path, from `prebuild`'s threads
_prebuild_lock = threading.Lock()


def prebuild(part: int = 32) -> None:
    """Start building the float`part` kernels' library (or finding it in the cache) in a
    background thread, once per process and part; `library_path` waits for it. The compiler
    then runs while the caller does other work: the command line calls it (float32, what the
    renderer uses) before importing JAX, so that a first render's build (3.4 s) overlaps the
    imports and the scene's loading. Does nothing when the kernels are disabled
    (`RADIOMETRIA_NATIVE=0`), no compiler is found, or `JAX_PLATFORMS` names platforms without
    the CPU (the kernels serve CPU renders only)."""
    with _prebuild_lock:
        if part in _prebuilt or disabled() or (cxx := compiler()) is None:
            return
        platforms = os.environ.get("JAX_PLATFORMS", "").strip()
        if platforms and "cpu" not in platforms.split(","):
            return
        future: Future = Future()

        def run() -> None:
            try:
                future.set_result(build(cxx, part))
            except BaseException as e:  # noqa: BLE001 - re-raised by library_path
                future.set_exception(e)

        threading.Thread(target=run, name="radiometria-native-build", daemon=True).start()
        _prebuilt[part] = future


def library_path(cxx: str, part: int = 32) -> Path:
    """The float`part` kernels' library path: `prebuild`'s (waiting for its thread) if it was
    started, else built (or found in the cache) now. Raises what the build raised."""
    with _prebuild_lock:
        future = _prebuilt.get(part)
    return future.result() if future is not None else build(cxx, part)
