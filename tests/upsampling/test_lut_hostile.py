"""Hostile coefficient-table files: every bad `.npz` or `.coeff` gets a `LUTFileError` naming
the file and the field, and absurd sizes are refused from the headers before any allocation;
a fuzz test mutates valid tables.

The hostile archives are built with `zipfile` and `numpy.lib.format` directly (independent of
`save_lut`). `RADIOMETRIA_FUZZ_EXAMPLES=5000 pytest -m fuzz` runs a longer search.
"""

import io
import json
import re
import time
import zipfile

import numpy as np
import pytest
from hypothesis import given, strategies as st

import radiometria.upsampling as up

from ..helpers import fuzz_settings, garble_bytes

RES = 3
SCALE = np.linspace(0.0, 1.0, RES).astype(np.float32)
COEFFS = np.random.default_rng(7).normal(size=(3, RES, RES, RES, 3)).astype(np.float32)


def _npz(**arrays) -> bytes:
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    return buf.getvalue()


def _npz_declaring(name: str, shape, dtype="<f4", payload: bytes = b"\0" * 64) -> bytes:
    """An archive with a member `name` whose .npy header declares `shape` but which holds only
    `payload`, beside a valid `scale` or `coeffs`."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        head = io.BytesIO()
        np.lib.format.write_array_header_1_0(
            head, {"descr": dtype, "fortran_order": False, "shape": tuple(shape)}
        )
        z.writestr(name + ".npy", head.getvalue() + payload)
        other, value = ("coeffs", COEFFS) if name == "scale" else ("scale", SCALE)
        npy = io.BytesIO()
        np.save(npy, value)
        z.writestr(other + ".npy", npy.getvalue())
    return buf.getvalue()


def _meta(**fields):
    return np.asarray(json.dumps(fields))


GOOD = _npz(scale=SCALE, coeffs=COEFFS)
TERA = (3, 10**4, 10**4, 10**4, 3)
HOSTILE = [
    ("garbage.npz", b"\x00\xff" * 64, r"not a readable \.npz file: it starts with"),
    ("empty.npz", b"", r"not a readable \.npz file"),
    ("truncated.npz", GOOD[: len(GOOD) // 2], r"truncated or corrupt"),
    ("no_coeffs.npz", _npz(scale=SCALE), r"missing array\(s\) \['coeffs'\]"),
    (
        "terabyte.npz",
        _npz_declaring("coeffs", TERA),
        r"`coeffs` declares shape .*36,000,000,000,000 bytes.*holds 64 bytes",
    ),
    (
        "res_huge.npz",
        _npz_declaring("scale", (10**6,), payload=b"\0" * 4 * 10**6),
        r"`scale` must be .* 2 <= res <= 1024",
    ),
    (
        "scale_2d.npz",
        _npz(scale=np.zeros((2, 2)), coeffs=COEFFS),
        r"`scale` must be a float array of shape \(res,\)",
    ),
    (
        "coeffs_int.npz",
        _npz(scale=SCALE, coeffs=COEFFS.astype(np.int32)),
        r"`coeffs` must be float .* declares int32",
    ),
    (
        "coeffs_shape.npz",
        _npz(scale=SCALE, coeffs=COEFFS[:2]),
        r"`coeffs` must be float of shape \(3, 3, 3, 3, 3\)",
    ),
    (
        "planes.npz",
        _npz(scale=SCALE, coeffs_planes=np.zeros((4, 5), np.uint16)),
        r"`coeffs_planes` must be uint8",
    ),
    (
        "nan.npz",
        _npz(scale=SCALE, coeffs=np.where(COEFFS > 1, np.nan, COEFFS)),
        r"`coeffs` has \d+ non-finite values",
    ),
    (
        "inf_scale.npz",
        _npz(scale=np.array([0, np.inf, 1], np.float32), coeffs=COEFFS),
        r"`scale` has 1 non-finite",
    ),
    (
        "scale_order.npz",
        _npz(scale=SCALE[::-1].copy(), coeffs=COEFFS),
        r"`scale` must increase strictly from 0 to 1",
    ),
    (
        "meta_json.npz",
        _npz(scale=SCALE, coeffs=COEFFS, metadata=np.asarray("{oops")),
        r"`metadata` is not valid JSON",
    ),
    (
        "meta_list.npz",
        _npz(scale=SCALE, coeffs=COEFFS, metadata=np.asarray("[1]")),
        r"`metadata` must be a JSON object, found list",
    ),
    (
        "meta_array.npz",
        _npz(scale=SCALE, coeffs=COEFFS, metadata=np.arange(3)),
        r"`metadata` must be one JSON string",
    ),
    (
        "meta_sha.npz",
        _npz(scale=SCALE, coeffs=COEFFS, metadata=_meta(sha256=5)),
        r"metadata `sha256` must be 64 lowercase hex",
    ),
    (
        "meta_checksum.npz",
        _npz(scale=SCALE, coeffs=COEFFS, metadata=_meta(sha256="0" * 64)),
        r"checksum mismatch",
    ),
    (
        "meta_res.npz",
        _npz(scale=SCALE, coeffs=COEFFS, metadata=_meta(resolution=64)),
        r"metadata `resolution` 64 != array resolution 3",
    ),
    (
        "meta_space.npz",
        _npz(scale=SCALE, coeffs=COEFFS, metadata=_meta(colourspace="CMYK")),
        r"metadata `colourspace` 'CMYK' is not one of",
    ),
    (
        "meta_format.npz",
        _npz(scale=SCALE, coeffs=COEFFS, metadata=_meta(format="pbrt")),
        r"metadata `format` 'pbrt'",
    ),
    (
        "meta_version.npz",
        _npz(scale=SCALE, coeffs=COEFFS, metadata=_meta(version=99)),
        r"version` 99 is newer",
    ),
    ("garbage.coeff", b"\x00\xff" * 64, r"not an rgb2spec file"),
    (
        "res_huge.coeff",
        b"SPEC" + (10**6).to_bytes(4, "little"),
        r"header resolution 1000000 is outside \[2, 1024\]",
    ),
    (
        "truncated.coeff",
        b"SPEC" + (64).to_bytes(4, "little") + b"\0" * 100,
        r"truncated: 108 bytes, the table of res 64 needs",
    ),
]


@pytest.mark.parametrize("name,content,message", HOSTILE, ids=[h[0] for h in HOSTILE])
def test_load_lut_names_file_and_field(tmp_path, name, content, message):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(up.LUTFileError) as info:
        up.load_lut(path)
    text = str(info.value)
    assert text.startswith(f"Coefficient table {str(path)!r}: "), text
    assert re.search(message, text), text


def test_load_lut_reads_the_valid_source(tmp_path):
    path = tmp_path / "good.npz"
    path.write_bytes(GOOD)
    lut = up.load_lut(path)
    np.testing.assert_array_equal(np.asarray(lut.coeffs), COEFFS)
    np.testing.assert_array_equal(np.asarray(lut.scale), SCALE)


# -- fuzzing ---------------------------------------------------------------------------------

FUZZ = fuzz_settings(40)
ARRAYS = st.one_of(
    st.sampled_from([SCALE, COEFFS, np.zeros(0), np.array("x"), np.array([np.nan]), COEFFS[:1]]),
    st.builds(
        np.zeros,
        st.lists(st.integers(min_value=0, max_value=4), max_size=5).map(tuple),
        st.sampled_from([np.float32, np.float64, np.int8, np.uint8, np.complex64, np.bool_]),
    ),
)
META = st.dictionaries(
    st.sampled_from(["format", "version", "sha256", "resolution", "colourspace", "fit"]),
    st.one_of(st.none(), st.integers(), st.text(max_size=8), st.sampled_from(["sRGB", "0" * 64])),
    max_size=4,
)


def _load_or_own_error(path):
    start = time.monotonic()
    try:
        up.load_lut(path)
    except up.LUTFileError as e:
        assert str(path) in str(e), e
    assert time.monotonic() - start < 10.0, "reading a tiny table took over 10 s"


@pytest.mark.fuzz
@FUZZ
@given(
    members=st.dictionaries(
        st.sampled_from(["scale", "coeffs", "coeffs_planes", "metadata", "other"]),
        ARRAYS,
        max_size=4,
    ),
    meta=st.one_of(st.none(), META.map(lambda m: np.asarray(json.dumps(m)))),
)
def test_fuzzed_npz_members_load_or_raise_lut_file_error(tmp_path_factory, members, meta):
    if meta is not None:
        members["metadata"] = meta
    path = tmp_path_factory.mktemp("fuzz") / "t.npz"
    path.write_bytes(_npz(**{"scale": SCALE, "coeffs": COEFFS, **members}))
    _load_or_own_error(path)


@pytest.mark.fuzz
@FUZZ
@given(
    source=st.sampled_from(["npz", "coeff"]),
    edits=st.lists(
        st.tuples(
            st.sampled_from(["flip", "delete", "insert", "truncate"]),
            st.integers(min_value=0, max_value=10**6),
            st.binary(min_size=1, max_size=8),
        ),
        min_size=1,
        max_size=3,
    ),
)
def test_garbled_table_bytes_load_or_raise_lut_file_error(tmp_path_factory, source, edits):
    tmp = tmp_path_factory.mktemp("fuzz")
    lut = up.RGBToSpectrumLUT(SCALE, COEFFS, "sRGB")
    data = up.save_lut(lut, tmp / f"good.{source}").read_bytes()
    path = tmp / f"t.{source}"
    path.write_bytes(garble_bytes(data, edits))
    _load_or_own_error(path)
