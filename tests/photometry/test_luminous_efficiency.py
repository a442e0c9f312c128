"""Packaged CIE V(lambda) and V'(lambda): provenance, equality with colour-science, lookup."""

import hashlib
import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from colour.colorimetry import SDS_LEFS_PHOTOPIC, SDS_LEFS_SCOTOPIC

from radiometria.photometry import luminous_efficiency_function, luminous_efficiency_table
from radiometria.photometry._efficiency import DATA_DIR, _write_tables

COLOUR_SDS = {
    "photopic": SDS_LEFS_PHOTOPIC["CIE 1924 Photopic Standard Observer"],
    "scotopic": SDS_LEFS_SCOTOPIC["CIE 1951 Scotopic Standard Observer"],
}


@pytest.mark.parametrize("vision", ["photopic", "scotopic"])
def test_luminous_efficiency_table_equals_colour_science(vision):
    wavelengths_nm, values = luminous_efficiency_table(vision)
    sd = COLOUR_SDS[vision]
    np.testing.assert_array_equal(np.asarray(wavelengths_nm), sd.wavelengths)
    np.testing.assert_array_equal(np.asarray(values), sd.values)  # bit for bit


def test_luminous_efficiency_provenance_sha256():
    provenance = json.loads((DATA_DIR / "provenance.json").read_text())
    assert set(provenance) == {"cie_1924_photopic.csv", "cie_1951_scotopic.csv"}
    for filename, record in provenance.items():
        digest = hashlib.sha256((DATA_DIR / filename).read_bytes()).hexdigest()
        assert digest == record["sha256"], filename
        for field in ("source", "original_source", "url", "licence", "retrieved"):
            assert record[field], (filename, field)


def test_luminous_efficiency_tables_regenerate_identically(tmp_path):
    # `_write_tables` reproduces the packaged files byte for byte from colour-science.
    provenance = _write_tables(tmp_path, retrieved="2026-11-22")
    for filename in provenance:
        assert (tmp_path / filename).read_bytes() == (DATA_DIR / filename).read_bytes()
    assert (tmp_path / "provenance.json").read_bytes() == (
        DATA_DIR / "provenance.json"
    ).read_bytes()


@pytest.mark.parametrize(("vision", "peak_nm"), [("photopic", 555.0), ("scotopic", 507.0)])
def test_luminous_efficiency_function_peaks(vision, peak_nm):
    assert float(luminous_efficiency_function(peak_nm, vision=vision)) == 1.0
    wavelengths_nm, values = luminous_efficiency_table(vision)
    assert float(jnp.max(values)) == 1.0


@pytest.mark.parametrize("vision", ["photopic", "scotopic"])
def test_luminous_efficiency_function_interpolates_and_is_zero_outside(vision):
    sd = COLOUR_SDS[vision]
    new = np.linspace(300.0, 900.0, 1201)
    expected = np.interp(new, sd.wavelengths, sd.values, left=0.0, right=0.0)
    np.testing.assert_allclose(
        luminous_efficiency_function(new, vision=vision), expected, rtol=1e-14, atol=1e-17
    )
    assert float(luminous_efficiency_function(1000.0, vision=vision)) == 0.0


def test_luminous_efficiency_function_float32_jit_grad():
    w = jnp.asarray([500.5, 555.0, 600.25], jnp.float32)
    v = luminous_efficiency_function(w)
    assert v.dtype == jnp.float32
    np.testing.assert_allclose(jax.jit(luminous_efficiency_function)(w), v)
    slope = jax.grad(lambda x: luminous_efficiency_function(x))(560.5)
    assert float(slope) == pytest.approx(
        float(COLOUR_SDS["photopic"][561.0] - COLOUR_SDS["photopic"][560.0]), rel=1e-12
    )


def test_luminous_efficiency_rejects_bad_vision():
    with pytest.raises(ValueError, match="vision"):
        luminous_efficiency_function(555.0, vision="mesopic")
    with pytest.raises(ValueError, match="vision"):
        luminous_efficiency_table("Photopic")
