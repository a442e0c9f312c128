"""XLA compile options for the renderer's programs (floor 1: imports nothing from radiometria).

**Why.** XLA:CPU (jaxlib 0.7 and later) hands some operations to YNNPACK, a library of
kernels for large tensors: dot products, reductions over an axis, and the elementwise work
around them. A path tracer's arrays are the opposite: a batch of paths by 3 coordinates or by
the 4 hero wavelengths. There each YNNPACK call is a custom call of its own, outside XLA's
loop fusion, and costs several microseconds however little it computes. Measured on the 2-core
CI machine: a `(256, 3) @ (3, 3)` product in a loop took 3.9 us with YNNPACK and 0.17 us in
XLA's own code; a warm Cornell box render (256 x 256, 16 spp, 2 devices) took 0.58 s with it
and 0.49 s without; the heterogeneous-medium scene of `benchmarks/bench_media.py` 1.13 s and
1.05 s (64 x 64, 64 spp).

**What.** `compiler_options(platform)` gives the options the renderer compiles its programs
with: on the CPU, `xla_cpu_experimental_ynn_fusion_type` set to the empty list (no YNNPACK
fusions; XLA's own emitters and Eigen take over), where the installed jaxlib knows the option
(`supported`, probed once by compiling a one-operation program) and the user's `XLA_FLAGS` does
not already set it. Elsewhere, or with `RADIOMETRIA_XLA_DEFAULTS=1`, no options: XLA's
defaults. The options are part of JAX's persistent-cache key, so a program compiled with them
is never served to a compile without them.
"""

import functools
import os

import jax
import numpy as np

__all__ = ["DEFAULTS_ENV", "YNN_OPTION", "compiler_options", "jit_options", "supported"]

YNN_OPTION = "xla_cpu_experimental_ynn_fusion_type"
DEFAULTS_ENV = "RADIOMETRIA_XLA_DEFAULTS"  # "1": compile with XLA's defaults


def _wants_defaults() -> bool:
    return os.environ.get(DEFAULTS_ENV, "").strip().lower() not in ("", "0", "false", "no")


@functools.cache
def supported(option: str = YNN_OPTION, value: str = "") -> bool:
    """Whether the installed jax and jaxlib compile a program with the option `option=value`
    (`jax.jit(..., compiler_options=...)`; older jax has no such argument, other jaxlib versions
    may not know the option). Probed once per process: about 10 ms."""
    try:
        jax.jit(lambda x: x + 1, compiler_options={option: value}).lower(np.float32(0)).compile()
    except Exception:  # noqa: BLE001 (TypeError from an old jax, XlaRuntimeError from jaxlib)
        return False
    return True


def compiler_options(platform: str) -> dict[str, str]:
    """The XLA options the renderer compiles with on `platform` ("cpu", "gpu", ...; module
    docstring): `{YNN_OPTION: ""}` on a CPU whose jaxlib knows it, unless `XLA_FLAGS` sets
    that option or `RADIOMETRIA_XLA_DEFAULTS` is set; else `{}`."""
    if platform != "cpu" or _wants_defaults() or YNN_OPTION in os.environ.get("XLA_FLAGS", ""):
        return {}
    return {YNN_OPTION: ""} if supported() else {}


def jit_options(platform: str) -> dict:
    """Keyword arguments for `jax.jit` with `compiler_options(platform)`: `{}` when there are
    none, so that a jax without the argument is never given it."""
    options = compiler_options(platform)
    return {"compiler_options": options} if options else {}
