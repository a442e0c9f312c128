"""The persistent compilation cache: compile a render's step once, reuse it in later processes.

XLA compiles the render step of a scene of a given shape in a few seconds; JAX's persistent
compilation cache keeps the compiled programs on disk, keyed by the program's StableHLO, the
devices, the compile options and the JAX / jaxlib versions, so a later process that builds the
same program loads it instead of compiling it. The command line turns it on (unless
`--no-cache` or `RADIOMETRIA_NO_CACHE=1`); a library user calls
`radiometria.render.enable_compilation_cache()` once, before the first render.

A program that calls back into Python (a host callback, e.g. an `equinox.error_if` check with
`EQX_ON_ERROR=raise`) is never written to the cache; the render driver therefore builds its
step with runtime checks turned into NaNs (`radiometria.render._driver`), so the step is
cacheable.
"""

import contextlib
from dataclasses import dataclass
from pathlib import Path

import equinox as eqx
import equinox._errors as _eqx_errors

from .._warmstart import (
    NO_CACHE_ENV as NO_CACHE_ENV,
    cache_disabled,
    cache_root,
    enable_jax_cache,
    jax_activity as jax_activity,
    step_cache_clear,
    step_cache_info,
)

__all__ = [
    "CompilationCacheInfo",
    "checks_without_callbacks",
    "clear_compilation_cache",
    "compilation_cache_dir",
    "compilation_cache_info",
    "compilation_cache_disabled",
    "enable_compilation_cache",
    "jax_activity",
]

# Files of JAX's file-system cache: "<module>-<sha256>-cache" (and "-atime" with eviction).
_ENTRY_SUFFIXES = ("-cache", "-atime")


def compilation_cache_dir() -> Path:
    """The default cache directory: `$XDG_CACHE_HOME/radiometria/jax`, else
    `~/.cache/radiometria/jax` (the XDG base directory specification).

    **Returns:**

    The directory (it need not exist yet).

    ??? cite "References"
        `Jakob2022` (Mitsuba 3 keeps Dr.Jit's compiled kernels on disk in the same way).
    """
    return cache_root() / "jax"


def compilation_cache_disabled() -> bool:
    """Whether the environment turns the cache off: `RADIOMETRIA_NO_CACHE` set to anything but
    `""`, `0`, `false` or `no`."""
    return cache_disabled()


def enable_compilation_cache(path=None, *, min_compile_time_s: float = 0.0) -> Path | None:
    """Turn on JAX's persistent compilation cache for this process.

    Compiled programs (the render step, the scene compiler's kernels) are written to `path` and
    loaded from there by later processes that build the same program, which skips XLA's
    compilation. Call it once, before the first render; calling it again with another
    directory switches to that directory. The command line calls it for every command.

    The cache is trusted code: keep it in a directory only you can write to (it is created
    with mode 0700). It grows with every new program shape (tens of MB for a few scenes);
    `clear_compilation_cache` (or `radiometria cache clear`) empties it.

    **Arguments:**

    - `path`: the cache directory; default `compilation_cache_dir()`. [directory]
    - `min_compile_time_s`: programs that compiled faster than this are not written. [s]

    **Returns:**

    The directory in use, or `None` when `RADIOMETRIA_NO_CACHE` turns the cache off.

    ??? cite "References"
        JAX's persistent compilation cache
        (`jax.experimental.compilation_cache.compilation_cache.set_cache_dir`); `Jakob2022`
        (Dr.Jit's on-disk kernel cache, the same idea in Mitsuba 3).
    """
    if compilation_cache_disabled():
        return None
    if not min_compile_time_s >= 0:
        raise ValueError(f"`min_compile_time_s` must be >= 0 [s], got {min_compile_time_s}.")
    return enable_jax_cache(compilation_cache_dir() if path is None else path, min_compile_time_s)


@dataclass(frozen=True)
class CompilationCacheInfo:
    """What a compilation cache directory holds.

    **Fields:**

    - `path`: the directory.
    - `entries`: compiled programs stored. [1]
    - `size_bytes`: their total size, step entries included. [B]
    - `steps`: step entries of the command line's warm start (`radiometria._warmstart`:
        a render's serialised step and scene arrays). [1]

    ??? cite "References"
        `Jakob2022` (Dr.Jit's on-disk kernel cache).
    """

    path: Path
    entries: int
    size_bytes: int
    steps: int = 0


def _entries(path: Path) -> list[Path]:
    if not path.is_dir():
        return []
    return [p for p in path.iterdir() if p.is_file() and p.name.endswith(_ENTRY_SUFFIXES)]


def compilation_cache_info(path=None) -> CompilationCacheInfo:
    """Count the compiled programs in a cache directory.

    **Arguments:**

    - `path`: the cache directory; default `compilation_cache_dir()`. [directory]

    **Returns:**

    A `CompilationCacheInfo` (a missing directory holds 0 entries).

    ??? cite "References"
        `Jakob2022` (Dr.Jit's on-disk kernel cache).
    """
    path = Path(compilation_cache_dir() if path is None else path).expanduser()
    files = _entries(path)
    programs = [p for p in files if p.name.endswith("-cache")]
    steps, step_bytes = step_cache_info(path)
    size = sum(p.stat().st_size for p in files) + step_bytes
    return CompilationCacheInfo(path, len(programs), size, steps)


def clear_compilation_cache(path=None) -> int:
    """Delete the compiled programs of a cache directory.

    Only JAX's cache files (`<name>-<hash>-cache` and `-atime`) and the command line's step
    entries (`step-<hash>.npz`, `radiometria._warmstart`) are removed, so pointing `path` at
    the wrong directory deletes nothing else; the directory itself stays.

    **Arguments:**

    - `path`: the cache directory; default `compilation_cache_dir()`. [directory]

    **Returns:**

    The number of compiled programs removed.

    ??? cite "References"
        `Jakob2022` (Dr.Jit's on-disk kernel cache).
    """
    path = Path(compilation_cache_dir() if path is None else path).expanduser()
    removed = 0
    for p in _entries(path):
        try:
            p.unlink()
        except FileNotFoundError:  # another process removed it first
            continue
        removed += p.name.endswith("-cache")
    step_cache_clear(path)
    return removed


def _error_if_as_nan(x, pred, index, msgs, *, on_error):
    on_error = "nan" if on_error == "default" else on_error
    return _eqx_errors.branched_error_if_impl(x, pred, index, msgs, on_error=on_error)


# A jitted check of its own (Equinox caches the traces of its checks per function), so that
# checks traced in NaN mode never serve a check traced outside the block, nor the reverse.
_ERROR_IF_AS_NAN_JIT = eqx.filter_jit(_error_if_as_nan)


@contextlib.contextmanager
def checks_without_callbacks():
    """Within `with`: programs traced turn failed `equinox.error_if` checks into NaNs instead
    of calling back into Python to raise.

    A host callback keeps a program out of the persistent cache (JAX cannot serialise the
    Python function it calls) and costs a host round trip per check. The render step's checks
    (e.g. a BxDF's reflectance in [0, 1]) see values that the scene loader has already
    validated, so in the step a failed check only marks the sample as NaN, and the driver
    drops non-finite samples. A user's `EQX_ON_ERROR` other than `raise` is kept, and checks
    with an explicit `on_error` are left alone. (Equinox has no public switch: the block
    routes `equinox.error_if` through a jitted check with `on_error="nan"`; the switch is
    process-wide while the block runs, and a jitted function first traced inside it keeps
    NaN checks.)
    """
    if getattr(_eqx_errors, "EQX_ON_ERROR", None) != "raise" or not hasattr(
        _eqx_errors, "branched_error_if_impl_jit"
    ):
        yield
        return
    default = _eqx_errors.branched_error_if_impl_jit
    _eqx_errors.branched_error_if_impl_jit = _ERROR_IF_AS_NAN_JIT
    try:
        yield
    finally:
        _eqx_errors.branched_error_if_impl_jit = default
