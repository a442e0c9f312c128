"""The persistent compilation cache: where it lives, turning it off, clearing it, and a second
render process that loads the compiled step instead of compiling it."""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import pytest

from radiometria.cli import main
from radiometria.render._cache import (
    checks_without_callbacks,
    clear_compilation_cache,
    compilation_cache_dir,
    compilation_cache_disabled,
    compilation_cache_info,
    enable_compilation_cache,
    jax_activity,
)

# A render through the command's `main`, counting JAX's persistent-cache events.
_RENDER_COUNTING_CACHE_EVENTS = textwrap.dedent(
    """
    import json, sys
    import jax.monitoring
    counts = {}
    def listen(event, **kwargs):
        counts[event] = counts.get(event, 0) + 1
    jax.monitoring.register_event_listener(listen)
    from radiometria.cli import main
    status = main(sys.argv[1:])
    hits = counts.get("/jax/compilation_cache/cache_hits", 0)
    misses = counts.get("/jax/compilation_cache/cache_misses", 0)
    print(json.dumps({"status": status, "hits": hits, "misses": misses}))
    """
)


def test_compilation_cache_dir_follows_xdg(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert compilation_cache_dir() == tmp_path / "radiometria" / "jax"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/dir")  # invalid by the XDG spec: ignored
    assert compilation_cache_dir() == Path.home() / ".cache" / "radiometria" / "jax"
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert compilation_cache_dir() == Path.home() / ".cache" / "radiometria" / "jax"


@pytest.mark.parametrize(("value", "off"), [("1", True), ("yes", True), ("0", False), ("", False)])
def test_no_cache_environment_variable(monkeypatch, tmp_path, value, off):
    monkeypatch.setenv("RADIOMETRIA_NO_CACHE", value)
    assert compilation_cache_disabled() is off
    if off:  # nothing is enabled, nothing created
        assert enable_compilation_cache(tmp_path / "c") is None
        assert not (tmp_path / "c").exists()


def test_enable_rejects_negative_min_compile_time(monkeypatch, tmp_path):
    monkeypatch.delenv("RADIOMETRIA_NO_CACHE", raising=False)
    with pytest.raises(ValueError, match="min_compile_time_s"):
        enable_compilation_cache(tmp_path, min_compile_time_s=-1.0)


def test_clear_removes_only_cache_entries(tmp_path, capsys):
    names = ["jit_f-" + "a" * 64 + "-cache", "jit_g-" + "b" * 64 + "-cache"]
    for name in names:
        (tmp_path / name).write_bytes(b"x" * 10)
    (tmp_path / ("jit_f-" + "a" * 64 + "-atime")).write_bytes(b"1")
    (tmp_path / "notes.txt").write_text("keep me")
    info = compilation_cache_info(tmp_path)
    assert (info.entries, info.size_bytes) == (2, 21)
    assert main(["cache", "info", "--dir", str(tmp_path)]) == 0
    assert "programs: 2" in capsys.readouterr().out
    assert main(["cache", "clear", "--dir", str(tmp_path)]) == 0
    assert "removed 2" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]
    assert clear_compilation_cache(tmp_path) == 0
    assert compilation_cache_info(tmp_path / "missing").entries == 0


def test_checks_without_callbacks_leave_no_host_callback():
    """`eqx.error_if` traced inside the block is a NaN select, not a Python callback (which
    would keep the program out of the persistent cache)."""

    def checked():  # a new function each time: JAX caches traces per function
        return jax.jit(lambda x: eqx.error_if(x, x < 0, "x must be >= 0"))

    x = jnp.ones(3)
    assert "callback" in checked().lower(x).as_text()
    with checks_without_callbacks():
        text = checked().lower(x).as_text()
        y = checked()(-x)
    assert "callback" not in text
    assert bool(jnp.all(jnp.isnan(y)))
    assert "callback" in checked().lower(x).as_text()  # the mode is restored


def _render_counting(tmp_path, spp, seed):
    env = {k: v for k, v in os.environ.items() if k != "RADIOMETRIA_NO_CACHE"}
    env["XDG_CACHE_HOME"] = str(tmp_path / "xdg")
    argv = ["render", "cornell-box", "--width", "8", "--height", "8", "--spp", str(spp)]
    argv += ["--seed", str(seed), "--out", str(tmp_path / "x.exr")]
    done = subprocess.run(
        [sys.executable, "-c", _RENDER_COUNTING_CACHE_EVENTS, *argv],
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_second_render_process_loads_every_program_from_the_cache(tmp_path):
    """A first `radiometria render` compiles and writes its programs (the render step among
    them) to the cache; a second process with another spp and seed compiles nothing: every
    program, the step included, is a cache hit (spp and seed are not part of the program)."""
    first = _render_counting(tmp_path, spp=2, seed=0)
    assert first["status"] == 0 and first["misses"] > 0
    cache = tmp_path / "xdg" / "radiometria" / "jax"
    # the step, as the command line's step entry exports it (`radiometria._warmstart`)
    assert any(p.name.startswith("jit_call-") for p in cache.iterdir())
    assert compilation_cache_info(cache).steps == 1
    stored = compilation_cache_info(cache).entries
    second = _render_counting(tmp_path, spp=3, seed=5)
    assert second["status"] == 0
    assert second["misses"] == 0 and second["hits"] >= 1
    assert compilation_cache_info(cache).entries == stored


def test_jax_activity_counts_traces_and_compiles(monkeypatch, capsys):
    """`RADIOMETRIA_TIMING`'s JAX summary: a new jitted function is traced, lowered and
    compiled once (whether XLA compiles it or the cache has it), a second call adds nothing;
    events of 50 ms or more are marked as they end."""
    monkeypatch.setenv("RADIOMETRIA_TIMING", "1")
    jax_activity.start()
    jax_activity.start()  # registered once
    x = jnp.ones(7).block_until_ready()
    jax_activity.summary()  # drop what came before

    @jax.jit
    def fresh(x):
        return jnp.sin(x) * 3.0 + jnp.arange(7.0)

    fresh(x).block_until_ready()
    summary = jax_activity.summary()
    for kind in ("1 traced", "1 lowered", "1 compiled"):
        assert kind in summary, summary
    fresh(x).block_until_ready()
    assert jax_activity.summary() == ""
    monkeypatch.setattr(type(jax_activity), "loud_s", 0.0)
    jax.jit(lambda y: y - 1.0)(x).block_until_ready()
    assert "jax: traced" in capsys.readouterr().err
