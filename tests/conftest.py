"""Test configuration: float64 physics and strict promotion (style.md section 10)."""

import gc
import os
from pathlib import Path

# Tests must be deterministic and fail loudly on out-of-domain values, also under jit.
os.environ.setdefault("EQX_ON_ERROR", "raise")
# The command line's persistent compilation cache stays out of the user's cache directory
# (tests/render/test_cache.py turns it on in a temporary one for its subprocesses).
os.environ.setdefault("RADIOMETRIA_NO_CACHE", "1")

import jax  # noqa: E402
import pytest  # noqa: E402

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_rank_promotion", "raise")
jax.config.update("jax_numpy_dtype_promotion", "strict")


# A test worker compiles thousands of XLA programs and JAX keeps every one. XLA:CPU maps each
# program's machine code into its own memory regions, and Linux refuses a process more than
# vm.max_map_count of them (65 530 by default): near that limit the next compile crashes the
# worker inside XLA (a segfault or an abort, in whichever test comes next; seen in full runs at
# ~80 % of the suite). Between modules the compiled programs are therefore dropped once the
# worker holds more than a third of its allowance of regions or 6 GB of memory; a later module
# that needs one of them compiles it again.
_MAX_MAP_COUNT = Path("/proc/sys/vm/max_map_count")
_SELF_MAPS = Path("/proc/self/maps")
_SELF_STATUS = Path("/proc/self/status")


def _region_allowance() -> int:
    try:
        return int(_MAX_MAP_COUNT.read_text().strip())
    except (OSError, ValueError):
        return 65_530


def _mapped_regions() -> int:
    try:
        with _SELF_MAPS.open("rb") as f:
            return sum(1 for _ in f)
    except OSError:  # not Linux: no such limit to stay under
        return 0


def _resident_bytes() -> int:
    try:
        for line in _SELF_STATUS.read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return 0


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    yield
    if _mapped_regions() > _region_allowance() // 3 or _resident_bytes() > 6 * 2**30:
        jax.clear_caches()
        gc.collect()
