"""Packaged CIE tables: equal to colour-science's, sha256 as recorded, accessors and names."""

import hashlib
import json
import re

import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.colorimetry as rc
from radiometria.colorimetry import _data, _make_data

colour = pytest.importorskip("colour")


def test_packaged_tables_equal_colour_science():
    tables = _make_data.colour_tables()
    for fname, arrays in tables.items():
        with np.load(_data._DATA_DIR / fname) as f:
            assert sorted(f.files) == sorted(arrays)
            for key, ref in arrays.items():
                assert f[key].dtype == np.float64
                np.testing.assert_array_equal(f[key], ref, err_msg=f"{fname}:{key}")


def test_get_cmfs_equals_colour():
    for name in _data.CMFS_XYZ:
        c = rc.get_cmfs(name)
        ref = colour.MSDS_CMFS[name]
        np.testing.assert_array_equal(np.asarray(c.wavelengths_nm), ref.wavelengths)
        np.testing.assert_array_equal(np.asarray(c.values), ref.values)
    rgb = rc.get_cmfs("Wright & Guild 1931 2 Degree RGB CMFs")
    np.testing.assert_array_equal(
        np.asarray(rgb.values),
        colour.colorimetry.MSDS_CMFS_RGB["Wright & Guild 1931 2 Degree RGB CMFs"].values,
    )


def test_get_illuminant_equals_colour():
    for name in ["A", "D50", "D55", "D65", "D75", "E"] + [f"FL{i}" for i in range(1, 13)]:
        s = rc.get_illuminant(name)
        ref = colour.SDS_ILLUMINANTS[name]
        np.testing.assert_array_equal(np.asarray(s.wavelengths_nm), ref.wavelengths)
        np.testing.assert_array_equal(np.asarray(s.values), ref.values)


def test_provenance_sha256_matches_files_and_docstring():
    prov = json.loads((_data._DATA_DIR / "provenance.json").read_text())
    assert "licence" in prov and "CIE" in prov["licence"]
    for fname, meta in prov["files"].items():
        digest = hashlib.sha256((_data._DATA_DIR / fname).read_bytes()).hexdigest()
        assert digest == meta["sha256"], fname
        assert digest in _data.__doc__, f"module docstring lacks the sha256 of {fname}"
        assert meta["primary_source"] and meta["colour_object"]


def test_build_data_is_reproducible(tmp_path):
    prov = _make_data.build_data(tmp_path)
    packaged = json.loads((_data._DATA_DIR / "provenance.json").read_text())
    for fname, meta in prov["files"].items():
        assert meta["sha256"] == packaged["files"][fname]["sha256"], fname


def test_observer_aliases():
    a = rc.get_cmfs("CIE 1931 2°")
    b = rc.get_cmfs("cie_2_1931")
    assert a.name == b.name == "CIE 1931 2 Degree Standard Observer"
    assert rc.get_cmfs("CIE 1964 10°").name == "CIE 1964 10 Degree Standard Observer"


def test_unknown_names_list_valid_ones():
    with pytest.raises(ValueError, match=re.escape("'CIE 1931 2 Degree Standard Observer'")):
        rc.get_cmfs("CIE 1931 3 Degree")
    with pytest.raises(ValueError, match="'D65'"):
        rc.get_illuminant("D66")


def test_tabulated_spectra_interpolation():
    c = rc.get_cmfs()
    v = c(jnp.array([555.0, 555.5, 300.0, 900.0]))
    assert v.shape == (4, 3)
    np.testing.assert_allclose(v[0], np.asarray(c.values)[195])
    np.testing.assert_allclose(v[1], 0.5 * (np.asarray(c.values)[195] + np.asarray(c.values)[196]))
    np.testing.assert_array_equal(v[2:], 0.0)
    d65 = rc.get_illuminant("D65")
    assert float(d65(900.0, extrapolation="constant")) == float(d65.values[-1])
