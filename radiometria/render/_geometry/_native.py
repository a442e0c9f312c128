"""Native CPU ray casting: C++ kernels called through XLA's FFI (`jax.ffi`) (thesis ch. 8).

XLA:CPU runs the lockstep JAX traversal (`_traversal._traverse`) as a `while_loop` of many
small kernels over a batch of lanes; on incoherent rays its per-iteration overhead and the
lanes that idle in lockstep cost most of the time. On the CPU the same queries therefore run,
by default, in `_csrc/bvh_traverse.cc`: one ray at a time, the same arithmetic operation for
operation (no fused multiply-adds), the same tie rules, the same BVH arrays. The brute-force
queries of tiny scenes run there too, vectorised across blocks of rays. It is an ordinary
XLA custom call: it works under `jit`, inside `while_loop` and `shard_map`, under `vmap`
(a batch of ray batches becomes one flat call, see `_query_fn`) and under `grad` (its inputs
pass through `stop_gradient`: hits are piecewise constant in the inputs, and derivatives are
taken through the hit point recomputed from `prim` and the barycentrics). On other platforms
(GPU, TPU) the JAX traversal runs. `NativeCPUTraversal` is the back end (see `_backends.py`)
that runs these kernels.

The kernel is compiled on first use with the system's C++ compiler (`$CXX`, else `c++`,
`g++` or `clang++`) against the FFI headers that ship with jaxlib (`jax.ffi.include_dir()`),
and cached in `$RADIOMETRIA_CACHE_DIR` (default `$XDG_CACHE_HOME/radiometria`, else
`~/.cache/radiometria`) under a name that hashes the source, the flags, the compiler, jaxlib
and the host CPU. The float32 and float64 kernels are compiled as two translation units at
once (2.3 s instead of 4.2 s on 2 cores), and `prebuild()` starts the build in a background
thread so that the compiler runs while a scene loads (the command line calls it). The
library is written to a temporary file and renamed into place
(`radiometria._io.atomic_write_path`), so concurrent processes never load a partial file. The
outcome of the first build and load is kept for the process (`_load`). Without a compiler, or
with `RADIOMETRIA_NATIVE=0`, `native_status()` says why and the JAX traversal is used.
"""

import ctypes
import functools
import hashlib
import os
import platform
import shutil
import subprocess
import tempfile
import threading
from concurrent.futures import Future
from pathlib import Path
from typing import ClassVar, NamedTuple

import jax
import jax.numpy as jnp
import jaxlib
import numpy as np
from jax import lax

from ..._io import atomic_write_path, default_file_mode
from ._backends import AbstractTraversalBackend
from ._triangle import Hit, _sorted_corners

__all__ = ["NativeCPUTraversal", "native_status"]

_SOURCE = Path(__file__).with_name("_csrc") / "bvh_traverse.cc"
# -ffp-contract=off: no fused multiply-adds, every operation rounds as written (the results do
# not depend on the compiler); -fno-trapping-math lets the brute force's branch-free loop be
# vectorised (it changes no result, only what may be assumed about floating-point traps).
_FLAGS = (
    "-O3",
    "-std=c++17",
    "-shared",
    "-fPIC",
    "-ffp-contract=off",
    "-fno-trapping-math",
    "-march=native",
)
_SYMBOLS = {
    (kind, any_hit, dtype): f"Radiometria{kind}{'Any' if any_hit else 'Closest'}F{dtype[-2:]}"
    for kind in ("Bvh", "Brute")
    for any_hit in (False, True)
    for dtype in ("float32", "float64")
}


def _compiler() -> str | None:
    for name in (os.environ.get("CXX"), "c++", "g++", "clang++"):
        if name and (path := shutil.which(name)):
            return path
    return None


def _cache_dir() -> Path:
    if os.environ.get("RADIOMETRIA_CACHE_DIR"):
        return Path(os.environ["RADIOMETRIA_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "radiometria"


def _cpu_signature() -> str:
    """The host CPU's model and feature flags (the library is built with -march=native)."""
    try:
        with open("/proc/cpuinfo") as fh:
            lines = [ln for ln in fh if ln.startswith(("model name", "flags"))]
        return "".join(sorted(set(lines)))
    except OSError:
        return platform.processor() + platform.machine()


def _build(cxx: str) -> Path:
    """Compile the kernel (or find it in the cache) and return the shared library's path."""
    include = jax.ffi.include_dir()
    version = subprocess.run(
        [cxx, "--version"], capture_output=True, text=True, timeout=60, check=False
    ).stdout
    key = hashlib.sha256(
        b"\0".join(
            s.encode()
            for s in (
                _SOURCE.read_text(),
                " ".join(_FLAGS),
                version,
                jaxlib.__version__,
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
        flags = [f for f in _FLAGS if f != "-shared"]
        with tempfile.TemporaryDirectory() as work:
            objects = [os.path.join(work, f"part{part}.o") for part in (32, 64)]
            cmds = [
                [cxx, *flags, f"-DRADIOMETRIA_PART={part}", f"-I{include}", "-c", str(_SOURCE),
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


class _NativeLibrary(NamedTuple):
    """The outcome of building and loading the kernels (`_load`)."""

    ok: bool  # True when the kernels are registered with XLA
    reason: str  # what happened, for `native_status`
    lib: ctypes.CDLL | None  # the loaded library (held so that it stays loaded)


def _disabled() -> bool:
    return os.environ.get("RADIOMETRIA_NATIVE", "1").strip().lower() in ("0", "false", "no")


_prebuilt: Future | None = None  # the library's path, from `prebuild`'s thread
_prebuild_lock = threading.Lock()


def prebuild() -> None:
    """Start building the kernel library (or finding it in the cache) in a background thread,
    once per process; the first `_load` waits for it. The compiler then runs while the caller
    does other work (the command line: loading and compiling the scene, about 1 s of a first
    run's 4 s of compiling). Does nothing when the kernels are disabled or no compiler is
    found (`_load` says why), and when JAX's default backend is not the CPU (the kernels
    serve CPU renders only)."""
    global _prebuilt
    with _prebuild_lock:
        if _prebuilt is not None or _disabled() or (cxx := _compiler()) is None:
            return
        if jax.default_backend() != "cpu":
            return
        future: Future = Future()

        def build() -> None:
            try:
                future.set_result(_build(cxx))
            except BaseException as e:  # noqa: BLE001 - re-raised by `_load`
                future.set_exception(e)

        threading.Thread(target=build, name="radiometria-native-build", daemon=True).start()
        _prebuilt = future


@functools.cache
def _load() -> _NativeLibrary:
    """Build, load and register the kernels, once per process (later calls return the result)."""
    if _disabled():
        return _NativeLibrary(False, "disabled by RADIOMETRIA_NATIVE=0", None)
    if (cxx := _compiler()) is None:
        return _NativeLibrary(False, "no C++ compiler found ($CXX, c++, g++, clang++)", None)
    try:
        path = _prebuilt.result() if _prebuilt is not None else _build(cxx)
        lib = ctypes.cdll.LoadLibrary(str(path))
        for symbol in _SYMBOLS.values():
            jax.ffi.register_ffi_target(
                symbol, jax.ffi.pycapsule(getattr(lib, symbol)), platform="cpu"
            )
    except Exception as e:  # noqa: BLE001 - any failure means: use the JAX traversal
        return _NativeLibrary(False, f"build or load failed: {e}", None)
    return _NativeLibrary(True, "compiled and loaded", lib)


def native_status() -> tuple[bool, str]:
    """Whether the native CPU ray-casting kernels are available, and why (or why not).

    Compiles and loads the kernel on the first call (a few seconds, once per machine: the
    library is cached; see the module docstring of `radiometria.render._geometry._native`).

    **Returns:**

    `(available, reason)`: `available` is True when `intersect_closest`, `intersect_any` and
    the two brute-force queries run the native kernels on the CPU by default; `reason` says
    what happened (for example `"no C++ compiler found ..."` or
    `"disabled by RADIOMETRIA_NATIVE=0"`).

    !!! note "Thesis"
        Ch. 8 (ray casting); the traversal of `Pharr2023` §7.3.5 and the tests of `Woop2013`
        and `Ize2013`, as in `intersect_closest`.
    """
    lib = _load()
    return lib.ok, lib.reason


def _threads() -> int:
    """Threads per call: XLA's intra-op pool (0) with one CPU device; 1 when the CPU is split
    into several devices (the render driver then runs one call per device and core)."""
    return 0 if jax.local_device_count("cpu") <= 1 else 1


@functools.cache
def _query_fn(symbol: str, n_geometry: int, **attrs):
    """The FFI call `symbol` as a `custom_vmap` function of `n_geometry` geometry arrays and the
    four ray arrays `(o, d, tmin, tmax)`; it returns `(t, prim, b1, b2)`.

    Under `vmap`, batched rays with unbatched geometry become one flat call of `batch * n`
    rays (nested `vmap` flattens level by level); batched geometry (one BVH per batch
    element) becomes one call per element (`lax.map`)."""
    attrs = {k: np.int64(v) for k, v in attrs.items()}

    def call(*args):
        n = args[-2].shape[0]
        dt = args[-1].dtype
        out = (
            jax.ShapeDtypeStruct((n,), dt),
            jax.ShapeDtypeStruct((n,), jnp.int32),
            jax.ShapeDtypeStruct((n,), dt),
            jax.ShapeDtypeStruct((n,), dt),
        )
        return jax.ffi.ffi_call(symbol, out)(*args, **attrs)

    fn = jax.custom_batching.custom_vmap(call)

    def batched(axis_size, x, b):
        return x if b else jnp.broadcast_to(x, (axis_size, *x.shape))

    @fn.def_vmap
    def _rule(axis_size, in_batched, *args):
        if any(in_batched[:n_geometry]):  # one geometry per batch element: one call each
            args = tuple(batched(axis_size, x, b) for x, b in zip(args, in_batched, strict=True))
            return lax.map(lambda a: fn(*a), args), (True,) * 4
        rays = [
            batched(axis_size, x, b)
            for x, b in zip(args[n_geometry:], in_batched[n_geometry:], strict=True)
        ]
        flat = [x.reshape(-1, *x.shape[2:]) for x in rays]  # (batch * n, ...)
        outs = fn(*args[:n_geometry], *flat)
        return tuple(y.reshape(axis_size, -1) for y in outs), (True,) * 4

    return fn


def native_query(bvh, o, d, tmin, tmax, *, any_hit: bool):
    """BVH traversal in native code; returns `(t, prim, b1, b2)` arrays of shape `(n,)`."""
    symbol = _SYMBOLS[("Bvh", any_hit, str(bvh.triangles.dtype))]
    fn = _query_fn(symbol, 4, stack_size=int(max(bvh.stack_size, 1)), threads=_threads())
    args = (bvh.node_boxes, bvh.node_children, bvh.triangles, bvh.prim_ids, o, d, tmin, tmax)
    return fn(*(lax.stop_gradient(x) for x in args))


def native_brute_query(rows, tri, o, d, tmin, tmax, *, any_hit: bool):
    """Brute force in native code (`rows`: `(9, f)` sorted corners, `tri`: `(f, 9)` corners);
    returns `(t, prim, b1, b2)` arrays of shape `(n,)`."""
    symbol = _SYMBOLS[("Brute", any_hit, str(tri.dtype))]
    fn = _query_fn(symbol, 2, threads=_threads())
    return fn(*(lax.stop_gradient(x) for x in (rows, tri, o, d, tmin, tmax)))


class NativeCPUTraversal(AbstractTraversalBackend):
    """The queries in native C++ on the CPU (`_csrc/bvh_traverse.cc`), through XLA's FFI.

    The BVH traversal runs one ray at a time with a per-ray stack; the brute force runs over
    blocks of 256 rays held in cache, vectorised across rays. The arithmetic is that of the
    JAX back end operation for operation (no fused multiply-adds), so both give the same hits;
    only coplanar overlapping triangles (z-fighting) may resolve differently in the brute
    force, where XLA contracts some products into fused multiply-adds. Available when the
    kernel compiles and loads (`native_status`); `"auto"` picks it on the CPU.

    !!! note "Thesis"
        Ch. 8 (ray casting).

    ??? cite "References"
        `Pharr2023` §7.3.5 (BVH traversal); `Woop2013`; `Ize2013`.
    """

    platforms: ClassVar[tuple[str, ...]] = ("cpu",)

    def available(self) -> tuple[bool, str]:
        return native_status()

    def bvh_closest(self, bvh, o, d, tmin, tmax):
        t, prim, b1, b2 = native_query(bvh, o, d, tmin, tmax, any_hit=False)
        return Hit(t=t, prim=prim, b1=b1, b2=b2)

    def bvh_any(self, bvh, o, d, tmin, tmax):
        return native_query(bvh, o, d, tmin, tmax, any_hit=True)[1] >= 0

    def brute_closest(self, tri, o, d, tmin, tmax):
        t, prim, b1, b2 = native_brute_query(
            _sorted_corners(tri), tri, o, d, tmin, tmax, any_hit=False
        )
        return Hit(t=t, prim=prim, b1=b1, b2=b2)

    def brute_any(self, tri, o, d, tmin, tmax):
        hit = native_brute_query(_sorted_corners(tri), tri, o, d, tmin, tmax, any_hit=True)
        return hit[1] >= 0
