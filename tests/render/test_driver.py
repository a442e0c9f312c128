"""The render driver: determinism, batching, sharding over devices, memory and input checks."""

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from radiometria._warmstart import tile_order
from radiometria.camera import Film, PinholeCamera
from radiometria.render import Path as PathIntegrator, _driver, render

from ._synthetic import lit_box_camera, lit_box_scene

ROOT = Path(__file__).resolve().parents[2]
SPP, DEPTH = 8, 3  # one configuration for every test here: one compilation


@pytest.fixture(scope="module")
def box():
    return lit_box_scene(), lit_box_camera()


def _render(box, **kw):
    scene, cam = box
    kw = {"spp": SPP, "integrator": PathIntegrator(max_depth=DEPTH), "progress": False, **kw}
    return np.asarray(render(scene, camera=cam, **kw))


@pytest.mark.slow
def test_render_same_seed_same_image(box):
    a = _render(box, seed=7)
    b = _render(box, seed=7)
    c = _render(box, seed=8)
    assert a.shape == (12, 16, 3) and a.dtype == np.float32
    assert np.all(np.isfinite(a)) and a.mean() > 0
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.slow
def test_render_image_does_not_depend_on_batch(box):
    """Samples are a function of (seed, pass, pixel): another batching gives the same image."""
    a = _render(box, seed=3)
    b = _render(box, seed=3, batch=64)  # 64-pixel tiles, 1 pass per step
    np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-6)


@pytest.mark.slow
def test_render_max_depth_one_sees_only_emitters(box):
    img = _render(box, integrator=PathIntegrator(max_depth=1))
    lit = img.sum(axis=-1) > 0
    assert 0 < lit.sum() < lit.size  # the ceiling light is in view, the walls are black


@pytest.mark.slow
def test_render_sharded_over_four_devices_matches_one():
    """--xla_force_host_platform_device_count=4 (set before jax is imported): same image."""
    script = textwrap.dedent(
        """
        import jax, numpy as np
        from radiometria.render import Path, render
        from tests.render._synthetic import lit_box_camera, lit_box_scene
        assert len(jax.devices()) == 4, jax.devices()
        scene, cam = lit_box_scene(), lit_box_camera()
        kw = dict(camera=cam, spp=4, integrator=Path(max_depth=3), seed=5, progress=False)
        one = np.asarray(render(scene, devices=jax.devices()[:1], **kw))
        four = np.asarray(render(scene, devices=jax.devices(), **kw))
        print("maxdiff", float(np.abs(one - four).max()), float(one.mean()))
        np.testing.assert_allclose(four, one, rtol=1e-6, atol=1e-7)
        """
    )
    env = {
        **os.environ,
        "XLA_FLAGS": "--xla_force_host_platform_device_count=4",
        "JAX_PLATFORMS": "cpu",
    }
    out = subprocess.run(
        [sys.executable, "-c", script],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stdout + out.stderr


def test_render_rejects_bad_arguments(box):
    scene, cam = box
    with pytest.raises(ValueError, match="spp"):
        render(scene, camera=cam, spp=0, progress=False)
    with pytest.raises(TypeError, match="spp"):
        render(scene, camera=cam, spp=2.5, progress=False)
    with pytest.raises(TypeError, match="integrator"):
        render(scene, camera=cam, spp=1, integrator="bdpt", progress=False)
    with pytest.raises(TypeError, match="integrator"):
        render(scene, camera=cam, spp=1, integrator="path", progress=False)
    with pytest.raises(TypeError, match="sampler"):
        render(scene, camera=cam, spp=1, sampler="halton", progress=False)
    with pytest.raises(TypeError, match="sampler"):
        render(scene, camera=cam, spp=1, sampler="sobol", progress=False)
    with pytest.raises(ValueError, match="max_depth"):
        render(scene, camera=cam, spp=1, integrator=PathIntegrator(max_depth=0), progress=False)
    with pytest.raises(ValueError, match="camera"):
        render(scene, spp=1, progress=False)
    with pytest.raises(ValueError, match="width"):
        render(scene, camera=cam, spp=1, width=32, progress=False)
    with pytest.raises(TypeError, match="scene"):
        render(42, spp=1, progress=False)


def test_render_refuses_absurd_resolution_before_allocating(box):
    scene, _ = box
    huge = PinholeCamera.from_look_at(
        np.zeros(3), np.array([0.0, 0, 1]), np.array([0.0, 1, 0]), 60.0, 200_000, 200_000
    )
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match="GiB|too large"):
        render(scene, camera=huge, spp=1, progress=False)
    assert time.perf_counter() - t0 < 5.0  # refused up front, nothing rendered or allocated


def test_render_refuses_a_film_larger_than_memory_before_allocating(box, monkeypatch):
    """With 1 GiB available, an 8192 x 8192 film (three float32 sums, the image and its host
    copy: 48 B per pixel, 3 GiB) is refused with the size it needs, before any film exists."""

    def no_film(*args, **kwargs):
        raise AssertionError("the film was allocated")

    monkeypatch.setattr(_driver, "_available_host_memory", lambda: 2**30)
    monkeypatch.setattr(_driver, "Film", no_film)
    scene, _ = box
    cam = PinholeCamera.from_look_at(
        np.zeros(3), np.array([0.0, 0, 1]), np.array([0.0, 1, 0]), 60.0, 8192, 8192
    )
    with pytest.raises(ValueError, match=r"8192 x 8192 film needs about 3\.0 GiB.*1\.0 GiB"):
        render(scene, camera=cam, spp=1, progress=False)


def test_available_host_memory_reads_linux(monkeypatch):
    """Linux: `MemAvailable` of /proc/meminfo (what the kernel can give without swapping),
    not the smaller count of free pages."""
    if not os.path.exists("/proc/meminfo"):
        pytest.skip("not Linux")
    with open("/proc/meminfo") as f:
        fields = dict(line.split(":", 1) for line in f)
    expected = int(fields["MemAvailable"].split()[0]) * 1024
    got = _driver._available_host_memory()
    limit = _driver._read_int("/sys/fs/cgroup/memory.max")
    if limit is None:
        assert abs(got - expected) < 0.05 * expected + 2**28  # the kernel's count moves
    else:
        assert got <= max(expected, limit)


@pytest.mark.slow
def test_render_measured_cornell_box_fully_spectral():
    """`cornell-box-measured`: measured reflectance and light spectra, no RGB upsampling."""
    from radiometria.radiometry import PiecewiseLinearSpectrum
    from radiometria.render import Diffuse, compile_scene, load_scene, wavelength_grid_nm

    description = load_scene("cornell-box-measured")
    scene, _, _ = compile_scene(description, width=16, height=16)
    grid = wavelength_grid_nm()
    (diffuse,) = scene.materials.plugins  # the three materials are one Diffuse plugin
    assert isinstance(diffuse, Diffuse)
    reflectance = np.asarray(diffuse.reflectance.table.values)
    for row, material in enumerate(description.materials):
        measured = material.params["reflectance"]
        assert isinstance(measured, PiecewiseLinearSpectrum)
        wl, values = np.asarray(measured.wavelengths_nm), np.asarray(measured.values)
        expected = np.interp(grid, wl, values, left=0.0, right=0.0)
        plugin_row = int(scene.materials.row_of[row])
        np.testing.assert_allclose(reflectance[plugin_row], expected, atol=1e-6)
    radiance = description.emitters[0].radiance
    assert isinstance(radiance, PiecewiseLinearSpectrum)
    wl, values = np.asarray(radiance.wavelengths_nm), np.asarray(radiance.values)
    np.testing.assert_allclose(
        np.asarray(scene.light.radiance.table.values[0]),
        np.interp(grid, wl, values, 0, 0),
        rtol=1e-6,
    )
    img = np.asarray(render(description, spp=4, width=16, height=16, progress=False))
    assert img.shape == (16, 16, 3) and np.all(np.isfinite(img)) and img.mean() > 0


@pytest.mark.slow
def test_render_multi_process_matches_one_process(tmp_path):
    """Two processes joined by `jax.distributed` (CPU, gloo) render alternate steps and sum
    their films: every process returns the single-process image."""
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    script = textwrap.dedent(
        f"""
        import sys, jax, numpy as np
        jax.config.update("jax_cpu_collectives_implementation", "gloo")
        pid = int(sys.argv[1])
        jax.distributed.initialize("127.0.0.1:{port}", num_processes=2, process_id=pid)
        from radiometria.render import Path, render
        from tests.render._synthetic import lit_box_camera, lit_box_scene
        img = render(lit_box_scene(), camera=lit_box_camera(), spp=4,
                     integrator=Path(max_depth=3), seed=5, batch=64, progress=False)
        np.save(r"{tmp_path}/part" + str(pid) + ".npy", np.asarray(img))
        """
    )
    env = {**os.environ, "JAX_PLATFORMS": "cpu"}
    env.pop("XLA_FLAGS", None)
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", script, str(i)],
            cwd=ROOT,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )  # fmt: skip
        for i in range(2)
    ]
    outputs = [p.communicate(timeout=600)[0] for p in procs]
    assert all(p.returncode == 0 for p in procs), "\n".join(outputs)
    scene, cam = lit_box_scene(), lit_box_camera()
    one = np.asarray(
        render(
            scene,
            camera=cam,
            spp=4,
            integrator=PathIntegrator(max_depth=3),
            seed=5,
            batch=64,
            progress=False,
        )
    )
    for i in range(2):
        np.testing.assert_allclose(np.load(tmp_path / f"part{i}.npy"), one, rtol=1e-5, atol=1e-6)


def test_a_loaded_scene_is_compiled_once_and_again_when_edited(monkeypatch):
    """`render` keeps the compilation of a loaded scene (its BVH and plugins) for the next
    render of the same scene and size, and compiles again when the description's content
    changes, also when an array of it is edited in place."""
    import dataclasses

    from radiometria.render import load_scene
    from radiometria.render._scenes import _compile

    _compile.clear_compiled_scenes()
    calls = []
    original = _compile.compile_scene

    def counting(*args, **kwargs):
        calls.append(kwargs.get("width"))
        return original(*args, **kwargs)

    monkeypatch.setattr(_compile, "compile_scene", counting)
    desc = load_scene("cornell-box")
    args = {"spp": 2, "width": 8, "height": 8, "progress": False}
    first = np.asarray(render(desc, seed=1, **args))
    second = np.asarray(render(desc, seed=1, **args))
    np.testing.assert_array_equal(first, second)
    assert len(calls) == 1
    render(desc, seed=1, **(args | {"width": 6}))  # another size: compiled for it
    assert len(calls) == 2
    bright = dataclasses.replace(
        desc, emitters=tuple(dataclasses.replace(e, radiance=e.radiance) for e in desc.emitters)
    )
    render(bright, seed=1, **args)  # equal content: found
    assert len(calls) == 2
    desc.vertices[desc.faces[desc.emitters[0].triangles[0], 0], 1] -= 0.05  # moved in place
    moved = np.asarray(render(desc, seed=1, **args))
    assert len(calls) == 3
    assert not np.array_equal(moved, first)
    _compile.clear_compiled_scenes()


def test_tile_order_gives_each_device_an_interleaved_share():
    """A step's pixels split into n contiguous device shares; share d holds the pixels
    d, d + n, d + 2n, ... of the tile (a regular lattice over the whole tile, which `_band`
    relies on); a tile that n does not divide is refused."""
    for n in (1, 2, 3, 4, 128):
        order = tile_order(128 * 6, n)
        np.testing.assert_array_equal(np.sort(order), np.arange(128 * 6))
        for d, share in enumerate(np.split(order, n)):
            np.testing.assert_array_equal(share, np.arange(d, 128 * 6, n))
    with pytest.raises(ValueError, match="does not split over 3 devices"):
        tile_order(128, 3)


@pytest.mark.parametrize("n_devices", [1, 2, 4])
@pytest.mark.parametrize(
    ("width", "height", "tile", "start"), [(37, 29, 256, 256), (37, 29, 256, 1024), (16, 8, 128, 0)]
)
def test_band_adds_footprints_as_the_scatter_does(n_devices, width, height, tile, start):
    """Each device's footprints as a band of the film (`_band`), summed over the devices and
    added (`_add_band`), give the film the scatter of every footprint entry to its pixel
    (`_add_footprints`, which splatting integrators use): borders, row ends, the image's last
    tile (pixels past the image) and 1, 2 or 4 devices."""
    rng = np.random.default_rng(n_devices + width)
    n_pixels = width * height
    cfg = _driver._Config(n_pixels, tile, 1, width, "splat", (None,) * n_devices, 1)
    pixel = tile_order(tile, n_devices) + start
    footprints = rng.random((tile, 5, 5, 5)).astype(np.float32)
    film = Film(width, height, dtype=jnp.float32, spectral_bins=1)
    film = jax.tree.map(lambda x: x + 1.0, film)  # accumulators already holding something
    want = _driver._add_footprints(film, jnp.asarray(pixel), jnp.asarray(footprints), width, height)
    shares = zip(np.split(pixel, n_devices), np.split(footprints, n_devices), strict=True)
    band = sum(_driver._band(jnp.asarray(f), jnp.asarray(p), cfg) for p, f in shares)
    got = _driver._add_band(film, int(pixel[0]), band, cfg, 2)
    for a, b in ((got.xyz_sum, want.xyz_sum), (got.weight_sum, want.weight_sum),
                 (got.spectral_sum, want.spectral_sum)):  # fmt: skip
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-5)
