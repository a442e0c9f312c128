"""A render's start-up (issue 15): what `radiometria render` imports, the phase timestamps of
`--timing`, and that compiling the scene in the command renders the same image as `render`."""

import subprocess
import sys

import numpy as np
import pytest

from radiometria import _warmstart
from radiometria.camera import read_exr
from radiometria.cli import main
from radiometria.render import _cache, render
from radiometria.render._registry import SAMPLERS
from radiometria.render._scenes import load_scene, scene_integrator

RENDER = ["render", "cornell-box", "--width", "16", "--height", "16", "--spp", "2"]


@pytest.fixture(autouse=True)
def _compilation_cache_off(monkeypatch, tmp_path):
    """Commands run in this process leave its JAX configuration as it is, and keep their
    step entries in a temporary directory."""
    monkeypatch.setattr(_cache, "enable_compilation_cache", lambda *args, **kwargs: None)
    monkeypatch.setattr(_warmstart, "enable_jax_cache", lambda *args, **kwargs: None)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))


def test_rendering_does_not_import_the_fitter():
    """The table lookup needs no solver: optimistix and lineax stay out of a render's
    imports (about 0.15 s), and come in with the fit when it is asked for."""
    code = (
        "import sys, radiometria.render\n"
        "print(sorted(m for m in ('optimistix', 'lineax') if m in sys.modules))\n"
        "import radiometria.upsampling as up\n"
        "up.fit_lut\n"
        "print(sorted(m for m in ('optimistix', 'lineax') if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split("\n")[:2] == ["[]", "['lineax', 'optimistix']"]


def test_render_help_does_not_import_jax():
    code = "import sys\nimport radiometria.cli as c\nc.build_parser()\nprint('jax' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "False"


@pytest.mark.slow
def test_timing_flag_prints_the_phases_in_order_and_the_image_is_the_same(
    tmp_path, capsys, monkeypatch
):
    # `--timing` sets RADIOMETRIA_TIMING in this process; setenv (unlike delenv of an unset
    # variable) makes the monkeypatch remove it again, so later tests print no timing lines.
    monkeypatch.setenv("RADIOMETRIA_TIMING", "")
    out = tmp_path / "box.exr"
    assert main(["--timing", *RENDER, "--out", str(out)]) == 0
    err = capsys.readouterr().err
    lines = [line for line in err.replace("\r", "\n").split("\n") if "radiometria timing" in line]
    phases = ["arguments parsed", "scene loaded", "scene compiled", "rendered", "image written"]
    found = [next(i for i, line in enumerate(lines) if p in line) for p in phases]
    assert found == sorted(found), lines
    seconds = [float(lines[i].split()[2]) for i in found]
    assert seconds == sorted(seconds) and seconds[0] >= 0.0
    # The command compiles the scene itself (to time the phase): the image is `render`'s.
    description = load_scene("cornell-box")
    expected = render(
        description, spp=2, width=16, height=16, seed=0, progress=False,
        integrator=scene_integrator(description), sampler=SAMPLERS["sobol"](),
    )  # fmt: skip
    np.testing.assert_array_equal(read_exr(out)[0], np.asarray(expected, np.float32))
