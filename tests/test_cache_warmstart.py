"""The command line's warm start (issue 15, `radiometria._warmstart`): a second
`radiometria render` of the same request loads the serialised step and the scene's arrays
instead of importing the renderer, compiling the scene and tracing the step; the image is the
same, bit for bit, as an uncached render; bad entries are ignored with a warning."""

import json
import logging
import os
import subprocess
import sys

import numpy as np
import pytest

from radiometria import _warmstart as warm
from radiometria.camera import read_exr
from radiometria.cli import main
from radiometria.render._cache import clear_compilation_cache, compilation_cache_info

RENDER = ["render", "cornell-box", "--width", "8", "--height", "8", "--spp", "2"]


def _run(tmp_path, *argv):
    env = {k: v for k, v in os.environ.items() if k not in ("RADIOMETRIA_NO_CACHE",)}
    env["XDG_CACHE_HOME"] = str(tmp_path / "xdg")
    env["RADIOMETRIA_TIMING"] = "1"
    done = subprocess.run(
        [sys.executable, "-m", "radiometria", *argv],
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
    )
    assert done.returncode == 0, done.stderr
    return done.stderr.replace("\r", "\n")


@pytest.mark.slow
def test_second_render_uses_the_step_cache_and_renders_the_same_image(tmp_path):
    """First process: the step entry is missed and written. Second: loaded; the renderer is
    not imported, the scene not compiled, the step neither traced nor compiled (JAX's
    cache gives the program). Both images equal a `--no-cache` render exactly, which uses no
    cache of either kind (no entry added)."""
    cache = tmp_path / "xdg" / "radiometria" / "jax"
    first = _run(tmp_path, *RENDER, "--out", str(tmp_path / "a.exr"))
    assert "step cache missed" in first and "scene compiled" in first
    assert compilation_cache_info(cache).steps == 1
    probe = "import radiometria.cli as c, sys; c.main(sys.argv[1:]); "
    probe += "print('RENDERER', 'radiometria.render' in sys.modules, file=sys.stderr)"
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "xdg"), "RADIOMETRIA_TIMING": "1"}
    env.pop("RADIOMETRIA_NO_CACHE", None)
    done = subprocess.run(
        [sys.executable, "-c", probe, *RENDER, "--seed", "0", "--out", str(tmp_path / "b.exr")],
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
    )
    assert done.returncode == 0, done.stderr
    second = done.stderr.replace("\r", "\n")
    assert "step cache entry loaded" in second
    assert "scene compiled" not in second and "traced _step" not in second
    assert "RENDERER False" in second  # nor imported: the warm start needs JAX and NumPy only
    assert " compiled jit(call)" in second and "loaded from the cache" in second
    plain = _run(tmp_path, "--no-cache", *RENDER, "--out", str(tmp_path / "c.exr"))
    assert "step cache" not in plain
    assert compilation_cache_info(cache).steps == 1
    a, b, c = (read_exr(tmp_path / f"{n}.exr")[0] for n in "abc")
    assert np.isfinite(c).all() and c.mean() > 0
    np.testing.assert_array_equal(a, c)
    np.testing.assert_array_equal(b, c)
    # Another seed and spp reuse the entry (they are arguments of the step).
    other = _run(tmp_path, *RENDER[:-1], "3", "--seed", "4", "--out", str(tmp_path / "d.exr"))
    assert "step cache entry loaded" in other
    assert compilation_cache_info(cache).steps == 1


SEEDED = """<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/>
    </transform>
    <sampler type="independent"><integer name="sample_count" value="2"/>
      <integer name="seed" value="3"/></sampler>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>
    </film></sensor>
  <shape type="rectangle"><transform name="to_world"><translate z="-1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.6, 0.7"/></bsdf></shape>
  <shape type="sphere"><float name="radius" value="0.4"/><point name="center" x="0" y="1"
    z="0.5"/><emitter type="area"><rgb name="radiance" value="4, 4, 4"/></emitter></shape>
</scene>
"""


@pytest.mark.slow
def test_the_scene_files_sample_count_and_seed_survive_the_warm_start(tmp_path):
    """Without --spp and --seed the scene's sampler sets them, in the first (cache-writing)
    process and in the second, which renders from the step entry without loading the scene:
    both images equal `--spp 2 --seed 3` rendered without any cache, and say so in their
    metadata."""
    scene = tmp_path / "seeded.xml"
    scene.write_text(SEEDED)
    first = _run(tmp_path, "render", str(scene), "--out", str(tmp_path / "a.exr"))
    assert "step cache missed" in first
    second = _run(tmp_path, "render", str(scene), "--out", str(tmp_path / "b.exr"))
    assert "step cache entry loaded" in second
    plain = ["--no-cache", "render", str(scene), "--spp", "2", "--seed", "3"]
    _run(tmp_path, *plain, "--out", str(tmp_path / "c.exr"))
    _run(tmp_path, *plain[:-1], "0", "--out", str(tmp_path / "d.exr"))
    (a, meta_a), (b, meta_b), (c, _), (d, _) = (read_exr(tmp_path / f"{n}.exr") for n in "abcd")
    np.testing.assert_array_equal(a, c)
    np.testing.assert_array_equal(b, c)
    assert not np.array_equal(c, d)  # the seed took effect
    for meta in (meta_a, meta_b):
        assert (int(meta["spp"]), int(meta["seed"]), int(meta["spp_reached"])) == (2, 3, 2)


def _fake_entry(tmp_path, dependency=None):
    request = {"format": warm.FORMAT, "scene": {"name": "x"}, "options": {}}
    meta = {"tile": 4, "native": None}
    kernel = [np.arange(3, dtype=np.float32), np.int32(7)]
    film = [np.zeros((2, 2), np.float32)]
    deps = [str(dependency)] if dependency else []
    path = warm.save_entry(
        tmp_path, request, step=b"step", develop=b"dev", kernel=kernel, film=film, meta=meta,
        dependencies=deps,
    )  # fmt: skip
    return request, path


def test_entry_round_trip(tmp_path):
    request, path = _fake_entry(tmp_path)
    assert path.name.startswith("step-") and path.stat().st_mode & 0o077 == 0
    entry = warm.load_entry(tmp_path, request)
    assert entry.step == b"step" and entry.develop == b"dev"
    np.testing.assert_array_equal(entry.kernel[0], np.arange(3, dtype=np.float32))
    assert entry.kernel[1].dtype == np.int32 and entry.film[0].shape == (2, 2)
    assert entry.meta["tile"] == 4
    assert warm.load_entry(tmp_path, {**request, "options": {"width": 9}}) is None  # no file
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary left


@pytest.mark.parametrize("damage", ["truncate", "flip", "meta"])
def test_a_corrupt_entry_is_ignored_with_a_warning(tmp_path, caplog, damage):
    request, path = _fake_entry(tmp_path)
    data = bytearray(path.read_bytes())
    if damage == "truncate":
        data = data[: len(data) // 2]
    elif damage == "flip":  # inside the stored step program: its SHA-256 no longer matches
        at = data.find(b"step", data.find(b"step.npy") + 10)
        data[at] ^= 0xFF
    else:
        meta = json.dumps({"request": {"other": 1}})
        np.savez(path, meta=np.asarray(meta), step=np.zeros(1, np.uint8))
        data = bytearray(path.read_bytes())
    path.write_bytes(bytes(data))
    with caplog.at_level(logging.WARNING, logger="radiometria"):
        assert warm.load_entry(tmp_path, request) is None
    assert "ignoring" in caplog.text and path.name in caplog.text


def test_an_entry_whose_scene_files_changed_is_stale(tmp_path, caplog):
    texture = tmp_path / "texture.bin"
    texture.write_bytes(b"0123")
    request, _ = _fake_entry(tmp_path, dependency=texture)
    assert warm.load_entry(tmp_path, request) is not None
    os.utime(texture, ns=(0, 0))  # touched, same content: still valid (checked by SHA-256)
    assert warm.load_entry(tmp_path, request) is not None
    texture.write_bytes(b"0124")
    with caplog.at_level(logging.WARNING, logger="radiometria"):
        assert warm.load_entry(tmp_path, request) is None
    assert "has changed" in caplog.text
    texture.unlink()
    assert warm.load_entry(tmp_path, request) is None


def test_the_request_follows_the_scene_file_and_the_options(tmp_path):
    scene = tmp_path / "s.xml"
    scene.write_text("<scene version='3.0.0'/>")
    a = warm.render_request(str(scene), {"width": 8})
    assert a == warm.render_request(str(scene), {"width": 8})
    assert a != warm.render_request(str(scene), {"width": 9})
    scene.write_text("<scene version='3.0.0'></scene>")
    assert a["scene"] != warm.render_request(str(scene), {"width": 8})["scene"]
    assert warm.render_request("cornell-box", {})["scene"] == {"name": "cornell-box"}


def test_recorded_files_are_the_scenes_not_the_packages(tmp_path):
    mesh = tmp_path / "mesh.obj"
    mesh.write_text("v 0 0 0\n")
    with warm.recording_opened_files() as files:
        mesh.read_text()
        (warm._PACKAGE / "_warmstart.py").read_text()
    assert files == {str(mesh)}


def test_cache_info_and_clear_cover_the_step_entries(tmp_path, capsys):
    _fake_entry(tmp_path)
    (tmp_path / "notes.txt").write_text("mine")
    info = compilation_cache_info(tmp_path)
    assert info.steps == 1 and info.entries == 0 and info.size_bytes > 0
    assert main(["cache", "info", "--dir", str(tmp_path)]) == 0
    assert "render steps: 1" in capsys.readouterr().out
    assert main(["cache", "clear", "--dir", str(tmp_path)]) == 0
    assert "1 render steps" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]
    assert clear_compilation_cache(tmp_path) == 0


def test_the_scene_files_recorded_are_those_its_own_thread_opens(tmp_path):
    """A step entry depends on the files the scene read; a file another thread opens meanwhile
    (the native kernel's background build reads /proc/cpuinfo) is not one of them."""
    import threading

    mine, theirs = tmp_path / "mesh.ply", tmp_path / "other.txt"
    mine.write_bytes(b"ply")
    theirs.write_text("x")
    with warm.recording_opened_files() as read:
        mine.read_bytes()
        reader = threading.Thread(target=theirs.read_text)
        reader.start()
        reader.join()
    assert read == {str(mine)}
