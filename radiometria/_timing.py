"""Start-up timestamps of a command (`RADIOMETRIA_TIMING=1` or `radiometria --timing`).

With the variable set, `mark(label)` writes one line to stderr,

    radiometria timing:   1.234 s  +0.456 s  label

seconds since the process started (read from `/proc/self/stat` on Linux; elsewhere since this
module was imported) and since the previous mark. Without it, `mark` does nothing. The command
line marks the phases of a render's start-up (imports, scene load, scene compile, the first
step's trace / compile or cache load, the render, the image written); `radiometria.render`'s
command module adds what JAX reports about its programs between two marks. The variable is
for people measuring start-up; nothing else depends on it.
"""

import os
import sys
import time

__all__ = ["TIMING_ENV", "mark", "timing_enabled"]

TIMING_ENV = "RADIOMETRIA_TIMING"


def _process_start() -> float:
    """`time.perf_counter()` at the process's start (Linux, 10 ms resolution), else now."""
    now = time.perf_counter()
    try:
        with open("/proc/self/stat") as f:
            # Field 22 (starttime, clock ticks since boot); the command name (field 2) may
            # hold spaces, so count from its closing parenthesis.
            start_ticks = int(f.read().rpartition(")")[2].split()[19])
        with open("/proc/uptime") as f:
            uptime = float(f.read().split()[0])
        age = uptime - start_ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return now
    return now - max(age, 0.0)


_T0 = _process_start()
_last = _T0


def timing_enabled() -> bool:
    """Whether `RADIOMETRIA_TIMING` is set to anything but `""`, `0`, `false` or `no`."""
    return os.environ.get(TIMING_ENV, "").strip().lower() not in ("", "0", "false", "no")


def mark(label: str) -> float:
    """Write `label` with the seconds since the process started and since the last mark to
    stderr, when timing is on; return the seconds since the process started. [s]"""
    global _last
    now = time.perf_counter()
    if timing_enabled():
        print(
            f"radiometria timing: {now - _T0:7.3f} s  +{now - _last:6.3f} s  {label}",
            file=sys.stderr,
            flush=True,
        )
    _last = now
    return now - _T0
