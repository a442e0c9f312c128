"""Shared test helpers: tree comparison, convergence slopes, per-dtype tolerances, byte
mutations of files for the fuzz tests."""

import os
import re
import struct

import jax
import jax.numpy as jnp
import numpy as np
from hypothesis import HealthCheck, settings


def tree_allclose(a, b, *, rtol: float = 1e-10, atol: float = 0.0) -> bool:
    """True when two pytrees have the same structure and all leaves are close."""
    la, ta = jax.tree_util.tree_flatten(a)
    lb, tb = jax.tree_util.tree_flatten(b)
    if ta != tb:
        return False
    return all(
        np.allclose(np.asarray(x), np.asarray(y), rtol=rtol, atol=atol)
        for x, y in zip(la, lb, strict=True)
    )


def convergence_slope(ns, errors) -> float:
    """Least-squares slope of log(error) against log(n)."""
    x = np.log(np.asarray(ns, dtype=float))
    y = np.log(np.asarray(errors, dtype=float))
    return float(np.polyfit(x, y, 1)[0])


def dtype_rtol(dtype) -> float:
    """A relative tolerance for comparing a computation in `dtype` against a float64 reference."""
    return {jnp.dtype(jnp.float32): 1e-5, jnp.dtype(jnp.float64): 1e-12}[jnp.dtype(dtype)]


def mutate_bytes(data: bytes, mutations) -> bytes:
    """Apply fuzz mutations `(kind, i, n, token)` to a file's bytes: `delete` n bytes at i,
    `duplicate` them, `insert` token, `flip` bits of one byte, `truncate` at i, or
    `swap_tokens` (replace one whitespace-separated token by `token`)."""
    for kind, i, n, token in mutations:
        i = i % (len(data) + 1)
        if kind == "delete":
            data = data[:i] + data[i + n :]
        elif kind == "duplicate":
            data = data[:i] + data[i : i + n] + data[i:]
        elif kind == "insert":
            data = data[:i] + token + data[i:]
        elif kind == "flip" and data:
            j = i % len(data)
            data = data[:j] + bytes([data[j] ^ (1 + n % 255)]) + data[j + 1 :]
        elif kind == "truncate":
            data = data[:i]
        elif kind == "swap_tokens":
            parts = re.split(rb"(\s+)", data)
            words = [k for k, p in enumerate(parts) if p and not p.isspace()]
            if words:
                parts[words[i % len(words)]] = token
                data = b"".join(parts)
    return data


def garble_bytes(data: bytes, edits) -> bytes:
    """Apply fuzz edits `(kind, i, token[, number])` to a file's bytes: `flip` byte i by
    `token[0]`, `delete` `len(token)` bytes at i, `insert` token, `truncate` at i, or `int32`
    (overwrite 4 bytes at i with the little-endian int32 `number`: sizes, windows)."""
    for kind, i, token, *number in edits:
        i %= len(data) + 1
        if kind == "flip" and i < len(data):
            data = data[:i] + bytes([data[i] ^ token[0] or 1]) + data[i + 1 :]
        elif kind == "delete":
            data = data[:i] + data[i + len(token) :]
        elif kind == "insert":
            data = data[:i] + token + data[i:]
        elif kind == "truncate":
            data = data[:i]
        elif kind == "int32":
            data = data[:i] + struct.pack("<i", number[0]) + data[i + 4 :]
    return data


def fuzz_settings(examples: int):
    """Hypothesis settings of the file readers' fuzz tests: `examples` cases in CI, or
    `RADIOMETRIA_FUZZ_EXAMPLES` for a longer run (`pytest -m fuzz`); no deadline (file IO
    times vary) and no health checks on slow or large inputs or function-scoped fixtures."""
    return settings(
        max_examples=int(os.environ.get("RADIOMETRIA_FUZZ_EXAMPLES", str(examples))),
        deadline=None,
        suppress_health_check=[
            HealthCheck.too_slow,
            HealthCheck.data_too_large,
            HealthCheck.function_scoped_fixture,
        ],
    )
