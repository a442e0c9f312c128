"""Table files: .npz (pbrt layout + metadata) and rgb2spec .coeff (2019 and 2026 layouts)."""

import json
import os
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import radiometria.upsampling as up


@pytest.fixture(scope="module")
def small_lut():
    res = 5
    coeffs = np.random.default_rng(4).normal(size=(3, res, res, res, 3)).astype(np.float32)
    return up.RGBToSpectrumLUT(up.brightness_scale(res).astype(np.float32), coeffs, "sRGB")


def _same(a, b):
    return np.array_equal(np.asarray(a.coeffs), np.asarray(b.coeffs)) and np.array_equal(
        np.asarray(a.scale), np.asarray(b.scale)
    )


@pytest.mark.parametrize("suffix", [".npz", ".coeff"])
def test_roundtrip_is_bit_exact(tmp_path, small_lut, suffix):
    path = up.save_lut(small_lut, tmp_path / f"t{suffix}", fit_settings={"note": "test"})
    lut, info = up.load_lut(path, with_info=True)
    assert _same(lut, small_lut) and lut.colourspace == "sRGB"
    assert info["format"] == ("npz" if suffix == ".npz" else "rgb2spec-2026")
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"t{suffix}"]  # no temp files left
    assert (os.stat(path).st_mode & 0o777) != 0o600


def test_npz_metadata_and_pbrt_layout(tmp_path, small_lut):
    path = up.save_lut(small_lut, tmp_path / "t.npz")
    with np.load(path, allow_pickle=False) as f:
        assert f["scale"].shape == (5,) and f["coeffs"].shape == (3, 5, 5, 5, 3)
        meta = json.loads(str(f["metadata"][()]))
    assert meta["colourspace"] == "sRGB" and meta["resolution"] == 5 and len(meta["sha256"]) == 64


def test_reads_rgb2spec_2019_layout(tmp_path, small_lut):
    path = tmp_path / "old.coeff"
    with open(path, "wb") as f:
        f.write(b"SPEC" + struct.pack("<I", 5))
        f.write(np.asarray(small_lut.scale, "<f4").tobytes())
        f.write(np.asarray(small_lut.coeffs, "<f4").tobytes())
    lut, info = up.load_lut(path, with_info=True)
    assert info["format"] == "rgb2spec-2019" and _same(lut, small_lut)


def test_2026_block_is_the_forward_model(tmp_path, small_lut):
    path = up.save_lut(small_lut, tmp_path / "t.coeff")
    data = path.read_bytes()
    off = 8 + 4 * 5 + 36 * 125
    (nfine,) = struct.unpack_from("<I", data, off)
    block = np.frombuffer(data, "<f4", 4 * nfine + 12, off + 4)
    assert nfine % 16 == 0 and nfine >= 471
    tbl = block[nfine : 4 * nfine].reshape(3, nfine)
    np.testing.assert_allclose(tbl.sum(axis=1), 1.0, rtol=1e-5)  # white -> RGB (1, 1, 1)
    m = up.forward_model("sRGB")
    np.testing.assert_allclose(
        block[4 * nfine : 4 * nfine + 9].reshape(3, 3), m.matrix_RGB_to_XYZ, rtol=1e-6
    )


def test_reads_mitsuba_shipped_table():
    mi = pytest.importorskip("mitsuba")
    path = Path(mi.__file__).parent / "data" / "srgb.coeff"
    if not path.exists():
        pytest.skip("this Mitsuba wheel ships no data/srgb.coeff")
    lut, info = up.load_lut(path, with_info=True)
    assert info["format"] == "rgb2spec-2026" and lut.resolution == 64 and lut.colourspace == "sRGB"


def _corrupt_cases(tmp_path, small_lut):
    good_coeff = up.save_lut(small_lut, tmp_path / "good.coeff").read_bytes()
    good_npz = up.save_lut(small_lut, tmp_path / "good.npz")
    cases = {}
    cases["truncated.coeff"] = (good_coeff[:100], "truncated")
    cases["header.coeff"] = (b"SPEK" + good_coeff[4:], "not an rgb2spec file")
    cases["block.coeff"] = (good_coeff[:-7], "forward-model block")
    nan = bytearray(good_coeff)
    nan[8 + 4 * 5 : 8 + 4 * 5 + 4] = struct.pack("<f", float("nan"))
    cases["nan.coeff"] = (bytes(nan), "non-finite")
    cases["garbage.npz"] = (b"not a zip file at all", "not a readable .npz")
    # Checksum: change one coefficient but keep the metadata.
    with np.load(good_npz, allow_pickle=False) as f:
        arrays = {k: f[k] for k in f.files}
    arrays["coeffs"] = arrays["coeffs"].copy()
    arrays["coeffs"][0, 1, 2, 3, 0] += 1.0
    p = tmp_path / "tmp_checksum.npz"
    np.savez(p, **arrays)
    cases["checksum.npz"] = (p.read_bytes(), "checksum mismatch")
    p = tmp_path / "tmp_missing.npz"
    np.savez(p, scale=arrays["scale"])
    cases["missing.npz"] = (p.read_bytes(), "missing array")
    p = tmp_path / "tmp_shape.npz"
    np.savez(p, scale=arrays["scale"], coeffs=arrays["coeffs"][:, :4])
    cases["shape.npz"] = (p.read_bytes(), "shape")
    return cases


def test_bad_files_raise_naming_file_and_problem(tmp_path, small_lut):
    for name, (data, match) in _corrupt_cases(tmp_path, small_lut).items():
        path = tmp_path / name
        path.write_bytes(data)
        with pytest.raises(up.LUTFileError, match=match) as err:
            up.load_lut(path)
        assert name in str(err.value), str(err.value)
    with pytest.raises(up.LUTFileError, match="no such file"):
        up.load_lut(tmp_path / "absent.npz")
    with pytest.raises(ValueError, match=".npz or .coeff"):
        up.save_lut(small_lut, tmp_path / "t.txt")


def test_failed_write_leaves_nothing(tmp_path, small_lut, monkeypatch):
    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez_compressed", boom)
    with pytest.raises(OSError, match="disk full"):
        up.save_lut(small_lut, tmp_path / "t.npz")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_mitsuba_loads_our_coeff(tmp_path):
    """Current Mitsuba (3.9 with the 2026 rgb2spec) reads our .coeff and fetches the same
    coefficients as our lookup; it refuses the 2019 layout."""
    pytest.importorskip("mitsuba")
    lut = up.get_lut()
    (tmp_path / "data").mkdir()
    up.save_lut(lut, tmp_path / "data" / "srgb.coeff")
    code = (
        "import mitsuba as mi; mi.set_variant('scalar_spectral');"
        "print(list(mi.srgb_model_fetch(mi.Color3f(0.2, 0.5, 0.1))))"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    got = np.array(json.loads(out.stdout.strip().splitlines()[-1]))
    np.testing.assert_allclose(
        got, np.asarray(lut.coefficients(np.array([0.2, 0.5, 0.1]))), rtol=1e-5
    )
    # The 2019 layout (no forward-model block) is refused by this Mitsuba.
    data = (tmp_path / "data" / "srgb.coeff").read_bytes()
    (tmp_path / "data" / "srgb.coeff").write_bytes(data[: 8 + 4 * 64 + 36 * 64**3])
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True)
    assert out.returncode != 0 and "Could not load" in out.stderr


def test_packaged_table_reads_with_load_lut_and_rejects_bad_planes(tmp_path):
    from radiometria.upsampling._data import SRGB_FILE

    lut, info = up.load_lut(SRGB_FILE, with_info=True)
    assert info["format"] == "npz" and lut.resolution == 64
    assert info["metadata"]["sha256"]  # the packaged file carries its checksum
    with np.load(SRGB_FILE) as f:
        arrays = {k: np.asarray(f[k]) for k in f.files}
    bad = tmp_path / "planes.npz"
    np.savez(bad, **{**arrays, "coeffs_planes": arrays["coeffs_planes"][:, :-9]})
    with pytest.raises(up.LUTFileError, match="coeffs_planes"):
        up.load_lut(bad)
    flipped = arrays["coeffs_planes"].copy()
    flipped[0, 0] ^= 1
    np.savez(bad, **{**arrays, "coeffs_planes": flipped})
    with pytest.raises(up.LUTFileError, match="checksum"):
        up.load_lut(bad)
