"""Radiance RGBE pictures: `read_hdr` against Mitsuba 3's own RGBE reader and writer (run-length
encoded files), against an encoder written here from Ward's definition (flat files and flipped
orientations), and on hostile files (names the file; absurd sizes refused before decoding).

`RADIOMETRIA_FUZZ_EXAMPLES=5000 pytest -m fuzz` runs a longer search.
"""

import time

import mitsuba as mi
import numpy as np
import pytest
from hypothesis import given, strategies as st

from radiometria.camera import read_hdr
from radiometria.render._lights import read_envmap
from radiometria.render._textures import read_texture_image

from ..helpers import fuzz_settings, garble_bytes

mi.set_variant("scalar_rgb")

RNG = np.random.default_rng(11)
# Values over many octaves, a few exact zeros (exponent byte 0).
IMAGE = (RNG.random((5, 37, 3)) * 10.0 ** RNG.integers(-3, 4, (5, 37, 1))).astype(np.float32)
IMAGE[0, :3] = 0.0
# Smooth rows give long runs, so Mitsuba's encoder writes both runs and literals.
IMAGE[3] = np.linspace(0.5, 0.5001, 37)[:, None]


def _mitsuba_hdr(path, rgb) -> np.ndarray:
    """Write `rgb` with Mitsuba's RGBE writer; return what Mitsuba reads back."""
    mi.Bitmap(rgb, mi.Bitmap.PixelFormat.RGB).write(str(path), mi.Bitmap.FileFormat.RGBE)
    return np.array(mi.Bitmap(str(path)), np.float32)


def _rgbe_flat(rgb: np.ndarray) -> np.ndarray:
    """Ward's float-to-RGBE encoding (shared exponent of the largest channel), per pixel."""
    peak = rgb.max(axis=-1)
    mant, exp = np.frexp(peak)
    scale = np.where(peak > 1e-32, mant * 256.0 / np.where(peak > 0, peak, 1.0), 0.0)
    out = np.zeros(rgb.shape[:2] + (4,), np.uint8)
    out[..., :3] = np.floor(rgb * scale[..., None]).astype(np.uint8)
    out[..., 3] = np.where(peak > 1e-32, exp + 128, 0).astype(np.uint8)
    return out


def _flat_file(rgbe: np.ndarray, resolution: str, header=b"FORMAT=32-bit_rle_rgbe\n") -> bytes:
    return b"#?RADIANCE\n" + header + b"\n" + resolution.encode() + b"\n" + rgbe.tobytes()


def test_read_hdr_equals_mitsuba_on_its_run_length_encoded_file(tmp_path):
    path = tmp_path / "m.hdr"
    expected = _mitsuba_hdr(path, IMAGE)
    rgb, metadata = read_hdr(path)
    assert rgb.dtype == np.float32 and rgb.shape == IMAGE.shape
    np.testing.assert_array_equal(rgb, expected)
    # The encoding keeps 8 bits of the largest channel: within 2^-8 of it.
    err = np.abs(rgb - IMAGE).max(axis=-1) / np.maximum(IMAGE.max(axis=-1), 1e-30)
    assert err.max() <= 2.0**-7
    assert metadata.get("FORMAT") == "32-bit_rle_rgbe"


def test_read_hdr_reads_flat_scanlines_and_every_row_major_orientation(tmp_path):
    rgbe = _rgbe_flat(IMAGE)
    path = tmp_path / "flat.hdr"
    path.write_bytes(_flat_file(rgbe, f"-Y {IMAGE.shape[0]} +X {IMAGE.shape[1]}"))
    reference = np.array(mi.Bitmap(str(path)), np.float32)  # Mitsuba reads this layout only
    rgb, _ = read_hdr(path)
    np.testing.assert_array_equal(rgb, reference)
    # The same pixels stored bottom-up and/or right-to-left come back top-left first.
    for y, x, stored in [
        ("+", "+", rgbe[::-1]),
        ("-", "-", rgbe[:, ::-1]),
        ("+", "-", rgbe[::-1, ::-1]),
    ]:
        path.write_bytes(_flat_file(np.ascontiguousarray(stored), f"{y}Y 5 {x}X 37"))
        np.testing.assert_array_equal(read_hdr(path)[0], reference, err_msg=f"{y}Y {x}X")


def test_read_hdr_returns_the_header_lines_without_applying_them(tmp_path):
    rgbe = _rgbe_flat(IMAGE)
    path = tmp_path / "exposed.hdr"
    header = b"# a comment\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=2.0\nEXPOSURE=1.5\nSOFTWARE=test\n"
    path.write_bytes(_flat_file(rgbe, "-Y 5 +X 37", header))
    rgb, metadata = read_hdr(path)
    assert metadata == {"FORMAT": "32-bit_rle_rgbe", "EXPOSURE": "2.0 1.5", "SOFTWARE": "test"}
    np.testing.assert_array_equal(rgb, np.array(mi.Bitmap(str(path)), np.float32))


def _hostile(tmp_path):
    good = tmp_path / "good.hdr"
    _mitsuba_hdr(good, IMAGE)
    data = good.read_bytes()
    body = data.index(b"-Y 5 +X 37\n") + len(b"-Y 5 +X 37\n")
    flat = _flat_file(_rgbe_flat(IMAGE), "-Y 5 +X 37")
    return [
        ("garbage.hdr", b"\x00\xff" * 40, "not a Radiance picture"),
        ("empty.hdr", b"", "not a Radiance picture"),
        ("noend.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n", "no end of the header"),
        ("xyze.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\0\0\0\0", "XYZE|xyze"),
        ("noresolution.hdr", data[: body - 11], "resolution line"),
        ("columns.hdr", flat.replace(b"-Y 5 +X 37", b"+X 37 -Y 5"), "column-major"),
        ("badres.hdr", flat.replace(b"-Y 5 +X 37", b"-Y five +X 37"), "malformed resolution"),
        ("huge.hdr", flat.replace(b"-Y 5 +X 37", b"-Y 32768 +X 32768"), "at least .* bytes"),
        ("oversize.hdr", flat.replace(b"-Y 5 +X 37", b"-Y 99999 +X 37"), "between 1 and 32768"),
        ("truncated.hdr", data[: body + 30], "at least|truncated"),
        ("cut.hdr", data[:-20], "truncated in scanline 4"),
        (
            "badrun.hdr",
            data[: body + 4] + b"\xff\x01" + data[body + 6 :],
            "a run of 127 bytes at pixel 0",
        ),
    ]


def test_hostile_hdr_files_name_the_file_and_the_problem(tmp_path):
    for name, data, pattern in _hostile(tmp_path):
        path = tmp_path / name
        path.write_bytes(data)
        with pytest.raises(ValueError, match=pattern) as info:
            read_hdr(path)
        assert str(path) in str(info.value), name
    with pytest.raises(FileNotFoundError, match="missing.hdr"):
        read_hdr(tmp_path / "missing.hdr")


@pytest.mark.fuzz
@fuzz_settings(40)
@given(
    edits=st.lists(
        st.tuples(
            st.sampled_from(["flip", "delete", "insert", "truncate"]),
            st.integers(min_value=0, max_value=2000),
            st.binary(min_size=1, max_size=8),
        ),
        min_size=1,
        max_size=3,
    ),
)
def test_garbled_hdr_reads_or_raises_value_error(tmp_path, edits):
    path = tmp_path / "src.hdr"
    if not path.exists():
        _mitsuba_hdr(path, IMAGE)
    garbled = tmp_path / "t.hdr"
    garbled.write_bytes(garble_bytes(path.read_bytes(), edits))
    start = time.monotonic()
    try:
        rgb, _ = read_hdr(garbled)
        assert rgb.ndim == 3 and rgb.shape[2] == 3 and np.all(np.isfinite(rgb))
    except ValueError as e:
        assert str(garbled) in str(e), e
    assert time.monotonic() - start < 5.0, "reading a tiny garbled .hdr took over 5 s"


def test_hdr_environment_maps_and_textures_read_as_mitsuba_reads_them(tmp_path):
    # The renderer's two readers of images take .hdr files: both give Mitsuba's pixels.
    sky = np.abs(RNG.normal(1.0, 0.5, (4, 8, 3))).astype(np.float32)
    path = tmp_path / "sky.hdr"
    expected = _mitsuba_hdr(path, sky)
    np.testing.assert_array_equal(read_envmap(path), expected)
    np.testing.assert_array_equal(read_texture_image(path), expected)
    np.testing.assert_array_equal(read_texture_image(path, raw=True), expected)  # linear
