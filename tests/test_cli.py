"""The `radiometria` command: help, `render` to EXR and PNG, and bad arguments (exit 2)."""

import logging
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import jax
import numpy as np
import pytest

import radiometria.cli as cli
from radiometria import _warmstart
from radiometria.camera import read_exr
from radiometria.cli import SMALL_LOOP_BYTES, SMALL_LOOP_OPTION, cpu_xla_flags, main
from radiometria.render import _cache
from radiometria.render._scenes._volume_files import write_vol

RENDER = ["render", "cornell-box", "--width", "16", "--height", "16", "--spp", "2"]


@pytest.fixture(autouse=True)
def _compilation_cache_in_tmp(monkeypatch, tmp_path_factory):
    """Commands run as subprocesses share one compilation cache in a temporary directory (never
    the user's); commands run in this process leave its JAX configuration as it is."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.getbasetemp() / "xdg-cache"))
    monkeypatch.delenv("RADIOMETRIA_NO_CACHE", raising=False)
    monkeypatch.setattr(_cache, "enable_compilation_cache", lambda *args, **kwargs: None)
    monkeypatch.setattr(_warmstart, "enable_jax_cache", lambda *args, **kwargs: None)
    # In this process no step entry is written or loaded: loading one registers the native
    # kernels again and patches JAX's lowering, state that outlives the command (a worker
    # that ran it crashed later in unrelated tests). Subprocesses use the cache as users do.
    monkeypatch.setattr(_warmstart, "cache_disabled", lambda: True)


def _command() -> list[str]:
    exe = Path(sys.executable).parent / "radiometria"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "radiometria"]


@pytest.mark.parametrize("argv", [_command(), [sys.executable, "-m", "radiometria"]])
def test_help_lists_the_commands(argv):
    out = subprocess.run(argv + ["--help"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    for command in ("render", "figures", "demo", "lut"):
        assert command in out.stdout


def test_render_help():
    out = subprocess.run(
        _command() + ["render", "--help"], capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0
    assert "--spp" in out.stdout and "--out" in out.stdout


@pytest.mark.slow
def test_render_writes_exr_and_png(tmp_path, capsys):
    exr, png = tmp_path / "box.exr", tmp_path / "box.png"
    assert main(RENDER + ["--out", str(exr)]) == 0
    assert main(RENDER + ["--out", str(png), "--seed", "1"]) == 0
    rgb, meta = read_exr(exr)
    assert rgb.shape == (16, 16, 3) and rgb.dtype == np.float32
    assert np.all(np.isfinite(rgb)) and rgb.mean() > 0.01
    assert meta["sampler"] == "sobol"  # the default: the lowest error per unit time
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "render" in capsys.readouterr().err  # the progress bar


@pytest.mark.slow
def test_render_sampler_and_integrator_flags(tmp_path):
    """`--sampler independent --integrator direct` renders with those plugins (recorded in the
    EXR)."""
    exr = tmp_path / "direct.exr"
    argv = ["render", "cornell-box", "--width", "8", "--height", "8", "--spp", "1"]
    argv += ["--sampler", "independent", "--integrator", "direct", "--out", str(exr)]
    assert main(argv) == 0
    rgb, meta = read_exr(exr)
    assert rgb.shape == (8, 8, 3) and np.all(np.isfinite(rgb)) and rgb.mean() > 0
    assert meta["sampler"] == "independent" and meta["integrator"] == "direct"


@pytest.mark.parametrize(
    ("extra", "message"),
    [(["--sampler", "halton"], "--sampler"), (["--integrator", "erpt"], "--integrator")],
)
def test_render_rejects_unknown_plugin_names(tmp_path, capsys, extra, message):
    out = tmp_path / "x.exr"
    assert main(["render", "cornell-box", "--spp", "1", "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert "error" in err and message in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--spp", "0"], "spp"),
        (["--spp", "-3"], "spp"),
        (["--width", "0"], "width"),
        (["--width", "100000", "--height", "100000"], "width"),
        (["--max-depth", "0"], "max-depth"),
        (["--seed", "-1"], "seed"),
    ],
)
def test_render_rejects_bad_numbers(tmp_path, capsys, extra, message):
    out = tmp_path / "x.exr"
    assert main(["render", "cornell-box", "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert "error" in err and message in err
    assert not out.exists()


def test_render_rejects_bad_outputs(tmp_path, capsys):
    assert main(["render", "cornell-box", "--spp", "1", "--out", str(tmp_path / "x.jpg")]) == 2
    assert ".exr or .png" in capsys.readouterr().err
    missing = tmp_path / "no" / "such" / "dir" / "x.exr"
    assert main(["render", "cornell-box", "--spp", "1", "--out", str(missing)]) == 2
    assert "does not exist" in capsys.readouterr().err
    if os.geteuid() != 0:  # root may write anywhere
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        assert main(["render", "cornell-box", "--spp", "1", "--out", str(locked / "x.exr")]) == 2
        assert "Cannot write" in capsys.readouterr().err


def test_render_rejects_unknown_scene(tmp_path, capsys):
    assert main(["render", "no-such-scene", "--spp", "1", "--out", str(tmp_path / "x.exr")]) == 2
    assert "cornell-box" in capsys.readouterr().err


def test_render_argparse_errors_exit_2():
    out = subprocess.run(
        _command() + ["render", "cornell-box", "--spp", "many", "--out", "x.exr"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 2 and "invalid int value" in out.stderr


@pytest.mark.slow
def test_demo_render_smoke(tmp_path):
    from radiometria.render._cli import demo_render

    paths = demo_render(tmp_path, spp=64, smoke=True)
    assert [p.name for p in paths] == ["cornell_box.exr", "cornell_box.png"]
    rgb, _ = read_exr(paths[0])
    assert rgb.shape == (32, 32, 3) and np.all(np.isfinite(rgb))


def test_figures_command_writes_figures_from_processes_of_their_own(tmp_path, capsys):
    """`figures` makes each figure in a fresh process (memory goes back when it ends) and
    prints what they wrote; an unknown name is one error line and exit 2, nothing written."""
    assert main(["figures", "--only", "fig_1_planck", "--smoke", "--out", str(tmp_path)]) == 0
    printed = capsys.readouterr().out.split()
    assert sorted(Path(p).name for p in printed) == ["fig_1_planck.pdf", "fig_1_planck.png"]
    assert all(Path(p).stat().st_size > 0 for p in printed)
    assert main(["figures", "--only", "fig_nope", "--out", str(tmp_path / "none")]) == 2
    err = capsys.readouterr().err
    assert "fig_nope" in err and "fig_1_planck" in err and not (tmp_path / "none").exists()


def test_isolated_work_runs_in_fresh_processes_and_restores_the_environment(monkeypatch):
    from radiometria.cli import _Isolated

    monkeypatch.delenv("MALLOC_ARENA_MAX", raising=False)
    with _Isolated(cache=False) as isolated:
        first, second = isolated.run(os.getpid), isolated.run(os.getpid)
        assert len({first, second, os.getpid()}) == 3  # a new process for each unit of work
        assert isolated.run(_environment_variable, "MALLOC_ARENA_MAX") == "1"
        with pytest.raises(ValueError, match="figure"):  # the work's own error, unchanged
            isolated.run(_unknown_figure)
    assert "MALLOC_ARENA_MAX" not in os.environ


def test_isolated_work_runs_here_where_no_process_pool_can_be_made(monkeypatch, capsys):
    import concurrent.futures

    from radiometria.cli import _Isolated

    def no_pool(*args, **kwargs):
        raise OSError("no POSIX semaphores")

    monkeypatch.setattr(concurrent.futures, "ProcessPoolExecutor", no_pool)
    with _Isolated(cache=False) as isolated:
        assert isolated.run(os.getpid) == os.getpid()
    assert "running in one process (no POSIX semaphores)" in capsys.readouterr().err


def _environment_variable(name):
    return os.environ.get(name)


def _unknown_figure():
    from radiometria.cli import _figure_names

    return _figure_names(["fig_nope"])


def test_cpu_devices_flag_sets_xla_count_once(monkeypatch):
    from radiometria.cli import _configure_cpu_devices

    monkeypatch.delenv("RADIOMETRIA_XLA_DEFAULTS", raising=False)
    monkeypatch.setenv("XLA_FLAGS", "--xla_dump_to=/tmp/none")
    _configure_cpu_devices(3)
    assert os.environ["XLA_FLAGS"].split() == [
        "--xla_dump_to=/tmp/none",
        "--xla_force_host_platform_device_count=3",
        f"--xla_backend_extra_options={SMALL_LOOP_OPTION}={SMALL_LOOP_BYTES}",
    ]
    _configure_cpu_devices(5)  # a count and extra options already in XLA_FLAGS win
    assert os.environ["XLA_FLAGS"].count("device_count") == 1
    assert os.environ["XLA_FLAGS"].count("extra_options") == 1
    assert cpu_xla_flags("--xla_backend_extra_options=a=1") == (
        f"--xla_backend_extra_options=a=1,{SMALL_LOOP_OPTION}={SMALL_LOOP_BYTES}"
    )
    assert cpu_xla_flags(f"--xla_backend_extra_options={SMALL_LOOP_OPTION}=8") == (
        f"--xla_backend_extra_options={SMALL_LOOP_OPTION}=8"
    )
    monkeypatch.setenv("RADIOMETRIA_XLA_DEFAULTS", "1")
    assert cpu_xla_flags("", 2) == "--xla_force_host_platform_device_count=2"


_GRID_SCENE = """<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="35"/>
    <transform name="to_world"><lookat origin="0, 0, 6" target="0, 0, 0" up="0, 1, 0"/>
    </transform><film type="hdrfilm"><integer name="width" value="16"/>
    <integer name="height" value="16"/></film></sensor>
  <integrator type="volpath"><integer name="max_depth" value="4"/></integrator>
  <shape type="rectangle"><transform name="to_world"><scale value="8"/><translate z="-3"/>
    </transform><emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter></shape>
  <medium type="heterogeneous" id="grid"><volume name="sigma_t" type="gridvolume">
    <string name="filename" value="{vol}"/><transform name="to_world"><scale value="2.4"/>
    <translate value="-1.2, -1.2, -1.2"/></transform></volume></medium>
  <shape type="cube"><transform name="to_world"><scale value="1.2"/></transform>
    <bsdf type="null"/><ref name="interior" id="grid"/></shape>
</scene>
"""


def test_command_line_compiles_the_grid_tracking_loops_into_single_functions(tmp_path):
    """`cpu_xla_flags`' small-loop threshold reaches XLA: in the render step of a
    heterogeneous medium, the tracking loops (a chunk of 256 paths, each with its int32 cell
    `s32[256,3]`) are hoisted into XLA:CPU's single-function calls. With XLA's default
    threshold (1024 bytes) no loop carrying that cell can be. Skipped on a jaxlib whose XLA:CPU
    hoists no loop at all (older than the pass, or without it)."""
    z, y, x = np.meshgrid(*[(np.arange(8) + 0.5) / 8] * 3, indexing="ij")
    write_vol(tmp_path / "ramp.vol", 0.1 + 2.0 * x * (1.2 - y) * (0.5 + z))
    scene = tmp_path / "grid.xml"
    scene.write_text(_GRID_SCENE.format(vol=tmp_path / "ramp.vol"))
    dump = tmp_path / "dump"
    env = dict(
        os.environ, XLA_FLAGS=f"--xla_dump_to={dump}", RADIOMETRIA_NO_CACHE="1", JAX_PLATFORMS="cpu"
    )
    env.pop("RADIOMETRIA_XLA_DEFAULTS", None)
    out = subprocess.run(
        _command() + ["--cpu-devices", "1", "render", str(scene), "--spp", "1", "--out",
                      str(tmp_path / "x.exr")],
        capture_output=True, text=True, timeout=600, env=env,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    steps = [p.read_text() for p in dump.glob("*jit__step.cpu_after_optimizations.txt")]
    calls = [
        line for text in steps for line in text.splitlines() if 'xla_cpu_small_call="true"' in line
    ]
    if steps and not calls:  # even the sampler's tiny seed loop runs as thunks
        pytest.skip("this jaxlib's XLA:CPU hoists no small loops")
    hoisted = [line for line in calls if "s32[256,3]" in line]
    assert steps and len(hoisted) >= 2, f"{len(steps)} step programs, {len(hoisted)} hoisted"


def test_cpu_devices_must_be_positive(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--cpu-devices", "0", "figures", "--out", "unused"])
    assert exc.value.code == 2
    assert "--cpu-devices" in capsys.readouterr().err


def _render_cli(tmp_path, *extra, out="x.exr"):
    return [sys.executable, "-m", "radiometria", "render", "cornell-box", "--width", "16",
            "--height", "16", "--out", str(tmp_path / out), *extra]  # fmt: skip


def _uninterrupted(tmp_path, spp):
    """The same command, run to the end without interruption."""
    cmd = _render_cli(tmp_path, "--spp", str(spp), out="reference.exr")
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return read_exr(tmp_path / "reference.exr")[0]


def _wait_for(path, proc, timeout=240.0):
    t0 = time.monotonic()
    while not path.exists():
        assert proc.poll() is None, proc.communicate()[1]
        assert time.monotonic() - t0 < timeout, "no checkpoint appeared"
        time.sleep(0.05)


@pytest.mark.slow
def test_ctrl_c_writes_checkpoint_and_partial_image_then_resume_is_bit_identical(tmp_path):
    """SIGINT mid-render: exit 130 with a one-line message (no traceback), a partial image
    whose EXR metadata records the spp reached, and a checkpoint; resuming from it gives the
    uninterrupted image bit for bit."""
    spp = 8192
    ck = tmp_path / "x.exr.checkpoint.npz"
    proc = subprocess.Popen(
        _render_cli(tmp_path, "--spp", str(spp), "--checkpoint-every", "0"),
        stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    _wait_for(ck, proc)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "interrupted by SIGINT" in err and "--resume" in err
    _, meta = read_exr(tmp_path / "x.exr")
    assert 0 < int(meta["spp_reached"]) < spp and ck.exists()
    done = subprocess.run(_render_cli(tmp_path, "--spp", str(spp), "--resume"),
                          capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr
    image, meta = read_exr(tmp_path / "x.exr")
    assert int(meta["spp_reached"]) == spp and not ck.exists()
    np.testing.assert_array_equal(image, _uninterrupted(tmp_path, spp))


@pytest.mark.slow
def test_sigkill_then_resume_is_bit_identical(tmp_path):
    """A render killed with SIGKILL (no chance to clean up) resumes from its last atomic
    checkpoint to the uninterrupted image, bit for bit; another spp is refused."""
    spp = 8192
    ck = tmp_path / "run.npz"
    args = ("--spp", str(spp), "--checkpoint", str(ck), "--checkpoint-every", "0")
    proc = subprocess.Popen(_render_cli(tmp_path, *args), stderr=subprocess.PIPE, text=True)
    _wait_for(ck, proc)
    proc.kill()
    proc.communicate(timeout=60)
    cmd = _render_cli(tmp_path, "--spp", "16", "--checkpoint", str(ck), "--resume")
    wrong = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert wrong.returncode == 2 and "belongs to another render" in wrong.stderr
    assert "spp: 8192 in the file, 16 now" in wrong.stderr
    done = subprocess.run(_render_cli(tmp_path, *args, "--resume"),
                          capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr
    image, _ = read_exr(tmp_path / "x.exr")
    np.testing.assert_array_equal(image, _uninterrupted(tmp_path, spp))


@pytest.mark.parametrize(
    "sampler_xml, flag, expected",
    [
        ('<sampler type="independent"/>', None, "independent"),  # the file's sampler
        ('<sampler type="ldsampler"/>', None, "sobol"),  # Mitsuba's name, mapped
        ("", None, "sobol"),  # none in the file: the lowest-error sampler
        ('<sampler type="independent"/>', "sobol", "sobol"),  # --sampler wins
    ],
)
def test_render_command_picks_flag_then_file_then_sobol(
    tmp_path, monkeypatch, sampler_xml, flag, expected
):
    from radiometria.render import _cli

    seen = {}

    def fake_render(description, **kwargs):
        seen["sampler"] = kwargs["sampler"]
        return np.zeros((2, 2, 3))

    monkeypatch.setattr(_cli, "render", fake_render)
    scene = tmp_path / "s.xml"
    scene.write_text(
        '<scene version="3.0.0"><sensor type="perspective">'
        f'<float name="fov" value="40"/>{sampler_xml}</sensor>'
        '<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/>'
        "</emitter></shape></scene>"
    )
    _, meta = _cli._render_to(
        str(scene), spp=1, width=2, height=2, seed=0, max_depth=None, sampler=flag
    )
    assert seen["sampler"].NAME == expected and meta["sampler"] == expected


def test_the_console_command_flushes_then_exits_at_once(monkeypatch, capsys):
    """`entry` (the console script and `python -m radiometria`) hands `main`'s status to
    `os._exit` after flushing stdout, stderr and the logging handlers, once JAX is loaded
    and no `jax.distributed` cluster is joined; else it exits the usual way."""
    events = []
    monkeypatch.setattr(cli, "main", lambda: print("rendered") or 3)
    monkeypatch.setattr(logging, "shutdown", lambda: events.append("logging"))

    def fast_exit(status):
        events.append(("os._exit", status, capsys.readouterr().out))
        raise SystemExit(status)  # the test process goes on

    monkeypatch.setattr(cli.os, "_exit", fast_exit)
    monkeypatch.setattr(cli, "_distributed", lambda: False)
    with pytest.raises(SystemExit):
        cli.entry()
    assert events == ["logging", ("os._exit", 3, "rendered\n")]

    events.clear()
    monkeypatch.setattr(cli, "_distributed", lambda: True)
    with pytest.raises(SystemExit) as exit_info:
        cli.entry()
    assert exit_info.value.code == 3 and events == ["logging"]  # sys.exit, not os._exit


def test_distributed_is_false_in_a_single_process():
    jax.devices()
    assert cli._distributed() is False
