"""The Cornell box against Mitsuba 3 `scalar_spectral` (the independent reference renderer).

Small images (32 x 32) keep the suite within its CI budget; `benchmarks/bench_render.py`
makes the full 256 x 256 comparison. Mitsuba is a test dependency (`pip install '.[test]'`).
"""

import numpy as np
import pytest

from radiometria.montecarlo import pixel_z_test
from radiometria.render import OwenSobol, render

from ._mitsuba import (
    cornell_box_materials_xml,
    cornell_box_xml,
    cornell_dict,
    mitsuba_moments,
    rel_mse,
    render_mitsuba,
    z_test_against_mitsuba,
)

mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 is the optional reference renderer")

SIZE = 32
REF_SPP = 2048


@pytest.fixture(scope="module")
def reference():
    """Mitsuba's 2048 spp image of the Cornell box (its noise is 1/32 of a 64 spp image's)."""
    return render_mitsuba(cornell_dict(SIZE, SIZE), REF_SPP, seed=1)


@pytest.mark.slow
def test_cornell_box_means_match_mitsuba(reference):
    """Per-channel image means within 1 % (RGB reflectances upsampled, RGB light x D65)."""
    ours = np.asarray(
        render("cornell-box", spp=256, width=SIZE, height=SIZE, sampler=OwenSobol(), progress=False)
    )
    np.testing.assert_allclose(ours.mean(axis=(0, 1)), reference.mean(axis=(0, 1)), rtol=0.01)


@pytest.mark.slow
def test_cornell_box_error_no_worse_than_mitsuba(reference):
    """relMSE of our 64 spp image <= 1.5 x that of Mitsuba's own 64 spp image."""
    ours = np.asarray(render("cornell-box", spp=64, width=SIZE, height=SIZE, progress=False))
    theirs = render_mitsuba(cornell_dict(SIZE, SIZE), 64, seed=2)
    ours_err, theirs_err = rel_mse(ours, reference), rel_mse(theirs, reference)
    assert ours_err <= 1.5 * theirs_err, (ours_err, theirs_err)


@pytest.mark.slow
def test_cornell_box_from_mitsuba_xml_matches_mitsuba(tmp_path):
    """The same XML file rendered by both renderers (helper G's Mitsuba XML loader)."""
    path = tmp_path / "cornell_box.xml"
    path.write_text(cornell_box_xml(SIZE, SIZE))
    theirs = render_mitsuba(mi.load_file(str(path)), REF_SPP, seed=3)
    ours = np.asarray(render(path, spp=256, sampler=OwenSobol(), progress=False))
    assert ours.shape == (SIZE, SIZE, 3)
    np.testing.assert_allclose(ours.mean(axis=(0, 1)), theirs.mean(axis=(0, 1)), rtol=0.01)


@pytest.mark.slow
def test_mirror_gold_and_glass_match_mitsuba(tmp_path):
    """Conductors (smooth, rough GGX gold) and a glass dielectric, from XML, against Mitsuba.

    Specular paths (the light seen in the mirror, caustics under the glass, which only BSDF
    sampling finds) are noisier: more samples on both sides, and the means within 2 % (both
    renderers' noise is below 0.7 % here).
    """
    path = tmp_path / "cornell_box_materials.xml"
    path.write_text(cornell_box_materials_xml(SIZE, SIZE))
    theirs = render_mitsuba(mi.load_file(str(path)), 2 * REF_SPP, seed=4)
    ours = np.asarray(render(path, spp=512, sampler=OwenSobol(), progress=False))
    np.testing.assert_allclose(ours.mean(axis=(0, 1)), theirs.mean(axis=(0, 1)), rtol=0.02)


@pytest.mark.slow
def test_cornell_box_passes_mitsubas_pixel_z_test(tmp_path):
    """Every pixel of a 16 x 16 Cornell box against Mitsuba's mean and per-sample variance;
    the same box with the white reflectance 10 % darker (only in our file) fails the test."""
    path = tmp_path / "cornell_box.xml"
    xml = cornell_box_xml(16, 16)
    path.write_text(xml)
    res = z_test_against_mitsuba(path, spp=256, ref_spp=4096)
    assert res.passed, res.message

    white = xml.split('id="white"><rgb name="reflectance" value="')[1].split('"')[0]
    darker = " ".join(str(0.9 * float(v)) for v in white.split())
    dark = tmp_path / "dark.xml"
    dark.write_text(xml.replace(f'value="{white}"', f'value="{darker}"'))
    mean, var = mitsuba_moments(path, 4096, seed=1)
    ours = np.asarray(render(dark, spp=256, return_xyz=True, progress=False), np.float64)
    res = pixel_z_test(ours, mean, var, 256, 4096)
    assert not res.passed, res.message
