"""Test configuration: float64 physics and strict promotion (style.md section 10)."""

import os

# Tests must be deterministic and fail loudly on out-of-domain values, also under jit.
os.environ.setdefault("EQX_ON_ERROR", "raise")
# The command line's persistent compilation cache stays out of the user's cache directory
# (tests/render/test_cache.py turns it on in a temporary one for its subprocesses).
os.environ.setdefault("RADIOMETRIA_NO_CACHE", "1")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_rank_promotion", "raise")
jax.config.update("jax_numpy_dtype_promotion", "strict")
