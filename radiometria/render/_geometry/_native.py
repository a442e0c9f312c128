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

The kernel is compiled on first use with the system's C++ compiler against the FFI headers
that ship with jaxlib, and cached (`radiometria._native_build`, which needs no JAX: the
command line starts the build with `prebuild()` before it imports JAX, so that a first
render's compiler runs beside the imports and the scene's loading). The float32 and float64
kernels are two libraries, each built on first use (a render needs only the float32 one). The
outcome of each build and load is kept for the process (`_load`). Without a compiler, or
with `RADIOMETRIA_NATIVE=0`, `native_status()` says why and the JAX traversal is used.
"""

import ctypes
import functools
from typing import ClassVar, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from ..._native_build import compiler, disabled, library_path
from ._backends import AbstractTraversalBackend
from ._triangle import Hit, _sorted_corners

__all__ = ["NativeCPUTraversal", "native_status"]

_SYMBOLS = {
    (kind, any_hit, dtype): f"Radiometria{kind}{'Any' if any_hit else 'Closest'}F{dtype[-2:]}"
    for kind in ("Bvh", "Brute")
    for any_hit in (False, True)
    for dtype in ("float32", "float64")
}


class _NativeLibrary(NamedTuple):
    """The outcome of building and loading the kernels (`_load`)."""

    ok: bool  # True when the kernels are registered with XLA
    reason: str  # what happened, for `native_status`
    lib: ctypes.CDLL | None  # the loaded library (held so that it stays loaded)


@functools.cache
def _load(bits: int = 32) -> _NativeLibrary:
    """Build, load and register the float`bits` kernels, once per process and precision
    (later calls return the result)."""
    if disabled():
        return _NativeLibrary(False, "disabled by RADIOMETRIA_NATIVE=0", None)
    if (cxx := compiler()) is None:
        return _NativeLibrary(False, "no C++ compiler found ($CXX, c++, g++, clang++)", None)
    try:
        path = library_path(cxx, bits)
        lib = ctypes.cdll.LoadLibrary(str(path))
        for (_, _, dtype), symbol in _SYMBOLS.items():
            if dtype == f"float{bits}":
                jax.ffi.register_ffi_target(
                    symbol, jax.ffi.pycapsule(getattr(lib, symbol)), platform="cpu"
                )
    except Exception as e:  # noqa: BLE001 - any failure means: use the JAX traversal
        return _NativeLibrary(False, f"build or load failed: {e}", None)
    return _NativeLibrary(True, "compiled and loaded", lib)


def _symbol(kind: str, any_hit: bool, dtype) -> str:
    """The handler of a query in `dtype` (float32 or float64), its library loaded first: the
    float64 kernels are built on their first use (`native_status` builds the float32 ones)."""
    dtype = str(dtype)
    lib = _load(64 if dtype == "float64" else 32)
    if not lib.ok:
        raise RuntimeError(f"the native {dtype} ray-casting kernels are unavailable: {lib.reason}")
    return _SYMBOLS[(kind, any_hit, dtype)]


def native_status() -> tuple[bool, str]:
    """Whether the native CPU ray-casting kernels are available, and why (or why not).

    Compiles and loads the float32 kernels, the renderer's, on the first call (a few
    seconds, once per machine: the library is cached; see the module docstring of
    `radiometria.render._geometry._native`); the float64 ones are built on their first query.

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
    symbol = _symbol("Bvh", any_hit, bvh.triangles.dtype)
    fn = _query_fn(symbol, 4, stack_size=int(max(bvh.stack_size, 1)), threads=_threads())
    args = (bvh.node_boxes, bvh.node_children, bvh.triangles, bvh.prim_ids, o, d, tmin, tmax)
    return fn(*(lax.stop_gradient(x) for x in args))


def native_brute_query(rows, tri, o, d, tmin, tmax, *, any_hit: bool):
    """Brute force in native code (`rows`: `(9, f)` sorted corners, `tri`: `(f, 9)` corners);
    returns `(t, prim, b1, b2)` arrays of shape `(n,)`."""
    symbol = _symbol("Brute", any_hit, tri.dtype)
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
