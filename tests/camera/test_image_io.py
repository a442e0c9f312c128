"""Image files: EXR round trip (bit-exact float32, metadata), spectral EXR layout, sRGB PNG,
atomic writes and clear errors."""

import subprocess
import sys

import colour
import matplotlib.image as mpimg
import numpy as np
import OpenEXR
import pytest

import radiometria.camera as cam
from radiometria import _image_files
from radiometria.colorimetry import srgb_eotf_inverse


def _image(h=5, w=7, c=3, seed=0):
    rng = np.random.default_rng(seed)
    img = rng.standard_normal((h, w, c)).astype(np.float32) * 10.0
    img[0, 0, 0] = np.float32(1e-40)  # a subnormal survives a bit-exact round trip
    img[0, 1, 1] = np.float32(3.4e38)
    return img


def test_exr_round_trip_is_bit_exact_and_keeps_metadata(tmp_path):
    img = _image()
    meta = {
        "renderer": "radiometria",
        "spp": 64,
        "exposure": 0.5,
        "wavelengths": ["360", "830"],
        "cameraToWorld": np.eye(4),
        "whitepoint": (0.3127, 0.329),
    }
    path = cam.write_exr(tmp_path / "img.exr", img, metadata=meta)
    rgb, got = cam.read_exr(path)
    assert rgb.dtype == np.float32 and rgb.shape == img.shape
    assert np.array_equal(rgb.view(np.uint32), img.view(np.uint32))
    assert got["renderer"] == "radiometria" and got["spp"] == 64
    assert got["exposure"] == 0.5 and got["wavelengths"] == ["360", "830"]
    np.testing.assert_array_equal(got["cameraToWorld"], np.eye(4, dtype=np.float32))
    np.testing.assert_allclose(got["whitepoint"], [0.3127, 0.329], rtol=1e-7)
    # A standard reader sees float32 R, G, B channels, row 0 at the top.
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = f.channels()
        assert sorted(ch) == ["B", "G", "R"]
        assert ch["R"].type() == OpenEXR.FLOAT
        np.testing.assert_array_equal(ch["G"].pixels, img[..., 1])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["img.exr"]  # no temporary left


def test_read_exr_validates(tmp_path):
    with pytest.raises(FileNotFoundError, match="missing.exr"):
        cam.read_exr(tmp_path / "missing.exr")
    bad = tmp_path / "garbage.exr"
    bad.write_bytes(b"not an exr file")
    with pytest.raises(ValueError, match="garbage.exr"):
        cam.read_exr(bad)
    r = np.ones((2, 3), np.float32)
    OpenEXR.File({"type": OpenEXR.scanlineimage}, {"R": r, "G": r}).write(str(tmp_path / "rg.exr"))
    with pytest.raises(ValueError, match=r"rg\.exr.*missing channel 'B'"):
        cam.read_exr(tmp_path / "rg.exr")
    u = np.ones((2, 3), np.uint32)
    OpenEXR.File({"type": OpenEXR.scanlineimage}, {"R": r, "G": r, "B": u}).write(
        str(tmp_path / "uint.exr")
    )
    with pytest.raises(ValueError, match=r"uint\.exr.*'B'.*FLOAT or HALF"):
        cam.read_exr(tmp_path / "uint.exr")
    # HALF channels are accepted and widened.
    h = np.full((2, 3), 0.5, np.float16)
    OpenEXR.File({"type": OpenEXR.scanlineimage}, {"R": h, "G": h, "B": h}).write(
        str(tmp_path / "half.exr")
    )
    rgb, _ = cam.read_exr(tmp_path / "half.exr")
    assert rgb.dtype == np.float32 and np.all(rgb == 0.5)


def test_writers_fail_cleanly_on_unwritable_paths(tmp_path):
    img = _image()
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    for target in (tmp_path / "no_such_dir" / "img.exr", blocker / "img.exr"):
        with pytest.raises(OSError, match="img.exr"):
            cam.write_exr(target, img)
        with pytest.raises(OSError, match="img.png"):
            cam.write_png(target.with_suffix(".png"), img)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file"]


def test_failed_write_leaves_previous_file_intact(tmp_path):
    path = tmp_path / "img.exr"
    cam.write_exr(path, _image(seed=1))
    before = path.read_bytes()
    with pytest.raises(TypeError, match="metadata"):
        cam.write_exr(path, _image(seed=2), metadata={"bad": object()})
    with pytest.raises(ValueError, match="reserved"):
        cam.write_exr(path, _image(seed=2), metadata={"channels": "R"})
    with pytest.raises(ValueError, match="rgb"):
        cam.write_exr(path, np.zeros((4, 4, 2), np.float32))
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["img.exr"]


def test_png_is_srgb_encoded_and_readable(tmp_path):
    lin = np.linspace(0.0, 1.0, 4 * 64 * 3).reshape(4, 64, 3)
    lin[0, 0] = [-1.0, np.nan, 2.0]  # clipped: 0, NaN -> 0, 1
    path = cam.write_png(tmp_path / "img.png", lin)
    read = mpimg.imread(path)
    assert read.shape == (4, 64, 3) and read.dtype == np.float32
    expected = colour.cctf_encoding(np.clip(np.nan_to_num(lin), 0.0, 1.0), function="sRGB")
    np.testing.assert_allclose(read, expected, atol=0.5 / 255 + 1e-6)
    np.testing.assert_array_equal(read[0, 0], [0.0, 0.0, 1.0])
    # Exposure: +1 stop doubles the linear values before encoding.
    path2 = cam.write_png(tmp_path / "img2.png", lin * 0.25, exposure=2.0)
    np.testing.assert_allclose(mpimg.imread(path2)[1:], read[1:], atol=1.01 / 255)
    assert path.read_bytes()[12:16] == b"IHDR" and b"sRGB" in path.read_bytes()[:64]


def test_spectral_exr_layout_and_round_trip(tmp_path):
    wl = np.array([400.0, 550.0, 612.5, 700.0])
    spec = np.abs(_image(c=4))
    rgb = np.abs(_image(seed=3))
    path = cam.write_spectral_exr(tmp_path / "s.exr", spec, wl, rgb=rgb, metadata={"spp": 4})
    with OpenEXR.File(str(path), separate_channels=True) as f:
        header, names = dict(f.header()), sorted(f.channels())
    # Fichet et al. 2021: "S0.<wavelength with decimal comma><unit>", plus an RGB preview.
    assert names == sorted(
        ["S0.400,000000nm", "S0.550,000000nm", "S0.612,500000nm", "S0.700,000000nm", "R", "G", "B"]
    )
    assert header["spectralLayoutVersion"] == "1.0"
    assert header["emissiveUnits"] == "W.m^-2.sr^-1"
    got, got_wl, meta = cam.read_spectral_exr(path)
    np.testing.assert_array_equal(got_wl, wl)
    assert np.array_equal(got, spec) and meta["spp"] == 4
    assert np.array_equal(cam.read_exr(path)[0], rgb)
    assert cam.spectral_channel_name(550.0) == "S0.550,000000nm"
    with pytest.raises(ValueError, match="wavelengths_nm"):
        cam.write_spectral_exr(tmp_path / "t.exr", spec, wl[:3])
    with pytest.raises(ValueError, match="distinct"):
        cam.write_spectral_exr(tmp_path / "t.exr", spec, np.array([400.0, 400.0, 500.0, 600.0]))
    with pytest.raises(ValueError, match="no spectral channel"):
        cam.read_spectral_exr(cam.write_exr(tmp_path / "rgb.exr", rgb))


def test_concurrent_writers_leave_one_complete_file(tmp_path):
    """Two writers racing on one path (two renders with the same --out): every read finds
    one writer's complete image, never a mix or a truncated file (atomic rename)."""
    import threading

    from radiometria.camera import read_exr, write_exr

    path = tmp_path / "race.exr"
    images = [np.full((64, 64, 3), v, np.float32) for v in (0.25, 0.75)]

    def writer(image):
        for _ in range(20):
            write_exr(path, image)

    threads = [threading.Thread(target=writer, args=(im,)) for im in images]
    for t in threads:
        t.start()
    seen = set()
    while any(t.is_alive() for t in threads):
        if path.exists():
            rgb, _ = read_exr(path)
            assert np.unique(rgb).size == 1  # one writer's image, whole
            seen.add(float(rgb[0, 0, 0]))
    for t in threads:
        t.join()
    final, _ = read_exr(path)
    assert float(final[0, 0, 0]) in (0.25, 0.75) and np.unique(final).size == 1
    assert not [p for p in tmp_path.iterdir() if p.name != "race.exr"]  # no temporaries left


def test_png_encoding_is_the_colorimetry_srgb_encoding():
    """The NumPy sRGB encoding of the PNG writer is `colorimetry.srgb_eotf_inverse`."""
    x = np.concatenate([np.linspace(0.0, 1.0, 1001), [0.0031308, 0.0031309, 1e-6]])
    np.testing.assert_allclose(
        _image_files._srgb_encode(x), np.asarray(srgb_eotf_inverse(x)), rtol=1e-14, atol=1e-15
    )


def test_image_files_load_without_jax():
    """The command line writes a warm-started render's image without importing JAX's
    modules: the image-file module needs NumPy only."""
    code = "import sys, radiometria._image_files; print('jax' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0 and out.stdout.strip() == "False", out.stderr
