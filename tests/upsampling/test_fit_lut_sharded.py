"""`fit_lut` sharded over several (virtual CPU) devices gives the one-device table.

Each case runs in a subprocess, because `--xla_force_host_platform_device_count` must be set
before JAX starts. The fit works on blocks of `chunk` table columns; device `d` of a call gets
a contiguous run of blocks. With an explicit `chunk` that divides the 3 res^2 = 192 columns of
a res-8 table by every device count (16 columns: 12 blocks, 6 or 3 per device), every block
holds the same columns whatever the number of devices, and each block is the same compiled
computation on the same inputs (a block's early exit depends only on its own columns). So the
tables are bit-identical, not just close; the same holds if no column needs the retry stage,
whose padding to whole calls depends on the device count (asserted: `columns_retried == 0`).
"""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

_SCRIPT = textwrap.dedent(
    """
    import sys
    import jax
    import numpy as np
    import radiometria.upsampling as up

    n = int(sys.argv[1])
    assert len(jax.devices()) == n, jax.devices()
    kw = dict(chunk=16, blocks_per_call=1)
    default = up.fit_lut("sRGB", 8, **kw)
    one = up.fit_lut("sRGB", 8, devices=jax.devices()[:1], **kw)
    many = up.fit_lut("sRGB", 8, devices=jax.devices(), **kw)
    for fit in (default, one, many):
        s = fit.summary()
        assert s["converged"] == s["entries"], s
        assert fit.settings["columns_retried"] == 0, fit.settings
    for a, b in ((default, one), (one, many)):
        np.testing.assert_array_equal(np.asarray(b.lut.coeffs), np.asarray(a.lut.coeffs))
        np.testing.assert_array_equal(np.asarray(b.residual), np.asarray(a.residual))
        np.testing.assert_array_equal(np.asarray(b.lut.scale), np.asarray(a.lut.scale))
    print("ok", n)
    """
)


@pytest.mark.slow  # LUT fits are slow tests (style.md section 11); about 6 s each
@pytest.mark.parametrize("n_devices", [2, 4])
def test_fit_lut_sharded_matches_one_device(n_devices):
    env = {
        **os.environ,
        "XLA_FLAGS": f"--xla_force_host_platform_device_count={n_devices}",
        "JAX_PLATFORMS": "cpu",
    }
    out = subprocess.run(
        [sys.executable, "-c", _SCRIPT, str(n_devices)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    assert f"ok {n_devices}" in out.stdout
