"""Hostile OpenEXR files: `read_exr` and `read_spectral_exr` raise `ValueError` naming the file
for garbage, truncation, missing or integer channels and absurd dataWindows (refused from the
header before the binding allocates); a fuzz test garbles valid files.

The valid files are written with the OpenEXR binding directly, not with `write_exr`.
`RADIOMETRIA_FUZZ_EXAMPLES=5000 pytest -m fuzz` runs a longer search.
"""

import re
import struct
import time

import numpy as np
import OpenEXR
import pytest
from hypothesis import given, strategies as st

from radiometria.camera import read_exr, read_spectral_exr

from ..helpers import fuzz_settings, garble_bytes

RGB = np.random.default_rng(3).random((8, 8, 3)).astype(np.float32)


def _exr(tmp_path, channels: dict, name="src.exr") -> bytes:
    path = tmp_path / name
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, channels).write(str(path))
    return path.read_bytes()


def _rgb_channels(r=None):
    return {
        "R": RGB[..., 0].copy() if r is None else r,
        "G": RGB[..., 1].copy(),
        "B": RGB[..., 2].copy(),
    }


def _with_data_window(data: bytes, x0, y0, x1, y1) -> bytes:
    key = b"dataWindow\0box2i\0"
    at = data.find(key) + len(key) + 4  # after the attribute's size field
    return data[:at] + struct.pack("<4i", x0, y0, x1, y1) + data[at + 16 :]


def _hostile(tmp_path):
    good = _exr(tmp_path, _rgb_channels())
    return [
        ("garbage.exr", b"\x00\xff" * 64, r"not an OpenEXR file \(it starts with"),
        ("empty.exr", b"", r"not an OpenEXR file"),
        ("header_cut.exr", good[:100], r"truncated header in attribute"),
        ("body_cut.exr", good[: len(good) - 200], r"not a readable OpenEXR file"),
        (
            "exabyte.exr",
            _with_data_window(good, 0, 0, 2**30, 2**30),
            r"dataWindow 1073741825 x 1073741825 with 3 channel\(s\) would need .* GiB.*memory",
        ),
        (
            "tall.exr",
            _with_data_window(good, 0, 0, 7, 10**6 - 1),
            r"dataWindow height 1000000 needs 62,500 chunk offsets",
        ),
        ("inverted.exr", _with_data_window(good, 0, 0, -5, -5), r"empty or inverted dataWindow"),
        (
            "no_blue.exr",
            _exr(tmp_path, {k: v for k, v in _rgb_channels().items() if k != "B"}),
            r"missing channel 'B' \(has: G, R\)",
        ),
        (
            "uint.exr",
            _exr(tmp_path, _rgb_channels(np.zeros((8, 8), np.uint32))),
            r"channel 'R' must be FLOAT or HALF",
        ),
    ]


def test_read_exr_names_file_and_problem(tmp_path):
    for name, content, message in _hostile(tmp_path):
        path = tmp_path / name
        path.write_bytes(content)
        with pytest.raises(ValueError) as info:
            read_exr(path)
        text = str(info.value)
        assert text.startswith(repr(str(path))), text
        assert re.search(message, text), (name, text)


def test_read_exr_reads_binding_written_file_and_widens_half(tmp_path):
    path = tmp_path / "half.exr"
    path.write_bytes(_exr(tmp_path, _rgb_channels(RGB[..., 0].astype(np.float16))))
    rgb, _ = read_exr(path)
    assert rgb.dtype == np.float32
    np.testing.assert_array_equal(rgb[..., 0], RGB[..., 0].astype(np.float16).astype(np.float32))
    np.testing.assert_array_equal(rgb[..., 1:], RGB[..., 1:])


def test_read_spectral_exr_refuses_missing_and_integer_bands(tmp_path):
    path = tmp_path / "rgb.exr"
    path.write_bytes(_exr(tmp_path, _rgb_channels()))
    with pytest.raises(ValueError, match=r"rgb\.exr'?: no spectral channel"):
        read_spectral_exr(path)
    path = tmp_path / "uint_band.exr"
    path.write_bytes(_exr(tmp_path, {"S0.550,000000nm": np.zeros((8, 8), np.uint32)}))
    with pytest.raises(ValueError, match=r"uint_band\.exr'?: channel 'S0\.550,000000nm' must be"):
        read_spectral_exr(path)


# -- fuzzing ---------------------------------------------------------------------------------

FUZZ = fuzz_settings(40)


@pytest.mark.fuzz
@FUZZ
@given(
    spectral=st.booleans(),
    edits=st.lists(
        st.tuples(
            st.sampled_from(["flip", "delete", "insert", "truncate", "int32"]),
            st.integers(min_value=0, max_value=10**5),
            st.binary(min_size=1, max_size=8),
            st.sampled_from([0, -1, 1, 2**31 - 1, -(2**31), 10**6, 2]),
        ),
        min_size=1,
        max_size=3,
    ),
)
def test_garbled_exr_reads_or_raises_value_error(tmp_path_factory, spectral, edits):
    tmp = tmp_path_factory.mktemp("fuzz")
    if spectral:
        channels = {"S0.450,000000nm": RGB[..., 2].copy(), "S0.550,000000nm": RGB[..., 1].copy()}
    else:
        channels = _rgb_channels()
    data = _exr(tmp, channels)
    path = tmp / "t.exr"
    path.write_bytes(garble_bytes(data, edits))
    start = time.monotonic()
    try:
        (read_spectral_exr if spectral else read_exr)(path)
    except ValueError as e:
        assert str(path) in str(e), e
    assert time.monotonic() - start < 10.0, "reading a tiny garbled EXR took over 10 s"
