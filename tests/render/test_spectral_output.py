"""Spectral output (issue 12): `radiometria render --spectral` writes the film's bin-averaged
spectral radiance in the OpenEXR layout of Fichet et al. (2021).

One 16 x 16 scene, rendered once spectrally and once as RGB through the command line (box
filter, independent sampler, so pixels are independent samples): a uniform blackbody sky
(`constant` emitter) seen directly in the image's left half and lighting a diffuse plane with a
piecewise-linear reflectance in its right half (max_depth 2: the plane's radiance is exactly
rho(l) Le(l), nothing occludes its sky). Checked against independent sources: the channel
names are parsed with colour-science's Fichet pattern, the pixels read with OpenEXR, the
spectra integrated against colour-science's CIE 1931 CMFs and converted with its sRGB matrix;
the sky's bins against Planck's law (SciPy constants).
"""

import re

import numpy as np
import pytest
from scipy import constants

from radiometria.cli import main

colour = pytest.importorskip("colour")
OpenEXR = pytest.importorskip("OpenEXR")

SIZE, SPP, SEED = 16, 64, 3
TEMPERATURE, SCALE = 5000.0, 1e-7  # K; Mitsuba's blackbody is in W m^-2 sr^-1 nm^-1
REFLECTANCE = ((360.0, 500.0, 830.0), (0.2, 0.6, 0.4))  # nm, 1: the plane's spectrum
SKY_COLUMNS = slice(0, 7)  # the plane covers world x in [0, 2]: image columns 8-15
PLANE_COLUMNS = slice(9, 16)

SCENE = f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="2"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/>
    </transform>
    <sampler type="independent"><integer name="sample_count" value="{SPP}"/></sampler>
    <film type="hdrfilm"><integer name="width" value="{SIZE}"/>
      <integer name="height" value="{SIZE}"/><rfilter type="box"/></film>
  </sensor>
  <shape type="rectangle">
    <transform name="to_world"><scale x="1" y="2"/><translate x="1" y="0" z="0"/></transform>
    <bsdf type="diffuse"><spectrum name="reflectance"
      value="{", ".join(f"{w:g}:{v:g}" for w, v in zip(*REFLECTANCE, strict=True))}"/></bsdf>
  </shape>
  <emitter type="constant"><spectrum name="radiance" type="blackbody">
    <float name="temperature" value="{TEMPERATURE}"/><float name="scale" value="{SCALE}"/>
  </spectrum></emitter>
</scene>
"""


def _planck(wavelength_nm, temperature):
    """Planck's law [W m^-2 sr^-1 nm^-1] from SciPy's CODATA constants."""
    lam = np.asarray(wavelength_nm) * 1e-9
    h, c, k = constants.h, constants.c, constants.k
    return 2 * h * c**2 / lam**5 / np.expm1(h * c / (lam * k * temperature)) * 1e-9


def _exr(path):
    """(channels by name as float64 arrays, header) read with the OpenEXR binding itself."""
    with OpenEXR.File(str(path), separate_channels=True) as f:
        header = dict(f.header())
        channels = {n: np.asarray(ch.pixels, np.float64) for n, ch in f.channels().items()}
    return channels, header


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    """The spectral EXR (named *.spectral.exr, no flag) and the RGB EXR of the same render."""
    d = tmp_path_factory.mktemp("spectral")
    scene = d / "scene.xml"
    scene.write_text(SCENE)
    common = ["--spp", str(SPP), "--seed", str(SEED), "--sampler", "independent"]
    spectral, rgb = d / "image.spectral.exr", d / "image.exr"
    assert main(["--no-cache", "render", str(scene), *common, "--out", str(spectral)]) == 0
    assert main(["--no-cache", "render", str(scene), *common, "--out", str(rgb)]) == 0
    return spectral, rgb


@pytest.fixture(scope="module")
def spectral_image(outputs):
    """(wavelengths (n,) [nm], spectra (H, W, n), preview RGB (H, W, 3), header), the bands
    found by colour-science's Fichet (2021) channel pattern."""
    from colour.io.fichet2021 import PATTERN_FICHET2021, match_groups_to_nm

    channels, header = _exr(outputs[0])
    pattern = re.compile(rf"^(S[0-3])\.*{PATTERN_FICHET2021}$")
    bands = []
    for name in channels:
        m = pattern.match(name)
        if m is not None:
            assert m.group(1) == "S0"  # unpolarised emission only
            bands.append((match_groups_to_nm(m.group(2), *m.group(4, 5)), name))
    bands.sort()
    wl = np.array([w for w, _ in bands])
    spectra = np.stack([channels[n] for _, n in bands], axis=-1)
    preview = np.stack([channels[c] for c in "RGB"], axis=-1)
    return wl, spectra, preview, header


def _bin_cmfs(wl):
    """Integrals of colour-science's CIE 1931 CMFs over each 1 nm-aligned bin, divided by
    int ybar over the table (the film's normalisation), and the 1 nm table itself."""
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    grid, xyz = np.asarray(cmfs.wavelengths, float), np.asarray(cmfs.values, float)
    norm = np.trapezoid(xyz[:, 1], grid)
    half = (wl[1] - wl[0]) / 2
    rows = []
    for centre in wl:
        inside = (grid >= centre - half - 1e-9) & (grid <= centre + half + 1e-9)
        rows.append(np.trapezoid(xyz[inside], grid[inside], axis=0))
    return np.asarray(rows) / norm, grid, xyz / norm


def test_spectral_exr_follows_the_fichet_layout(outputs, spectral_image):
    wl, spectra, preview, header = spectral_image
    np.testing.assert_allclose(wl, 365.0 + 10.0 * np.arange(47))  # 10 nm bins, 360-830 nm
    assert header["spectralLayoutVersion"] == "1.0"
    assert header["emissiveUnits"] == "W.m^-2.sr^-1"
    assert int(header["spp_reached"]) == SPP and int(header["spectral_bins"]) == 47
    assert spectra.shape == (SIZE, SIZE, 47) and np.all(np.isfinite(spectra))
    # The R, G, B preview is the RGB output of the same render: the spectral film changes
    # nothing in the XYZ film. (Up to float32 rounding: the two steps are different programs,
    # and XLA may fuse, and so round, the same sums differently in each.)
    rgb, _ = _exr(outputs[1])
    rgb = np.stack([rgb[c] for c in "RGB"], axis=-1)
    np.testing.assert_allclose(preview, rgb, rtol=2e-6, atol=1e-12)
    try:  # colour-science's own reader needs OpenImageIO
        import OpenImageIO  # noqa: F401
    except ImportError:
        return
    components = colour.io.read_spectral_image_Fichet2021(str(outputs[0]))
    np.testing.assert_allclose(components["S0"][0], wl)
    np.testing.assert_allclose(components["S0"][1], spectra, rtol=1e-6)


def test_spectra_integrate_to_the_rgb_output(spectral_image):
    """CMF-weighted bins equal the RGB output up to the binning error, which for these smooth
    spectra is computed in closed form; the noise of the difference from the pixels' spread."""
    wl, spectra, preview, _ = spectral_image
    bins_xyz, grid, cmf = _bin_cmfs(wl)
    to_rgb = np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB)
    from_bins = np.einsum("ij,hwb,bj->hwi", to_rgb, spectra, bins_xyz)
    sky = SCALE * _planck(grid, TEMPERATURE)
    rho = np.interp(grid, *REFLECTANCE)
    for columns, spectrum in ((SKY_COLUMNS, sky), (PLANE_COLUMNS, rho * sky)):
        d = (from_bins - preview)[:, columns].reshape(-1, 3)
        exact = np.trapezoid(spectrum[:, None] * cmf, grid, axis=0)
        inside = np.abs(grid[None, :] - wl[:, None]) <= 5.0  # (bins, grid): 1 nm-aligned bins
        in_bins = [np.trapezoid(spectrum[m], grid[m]) / 10.0 for m in inside]
        binning = to_rgb @ (np.asarray(in_bins) @ bins_xyz - exact)  # E[from_bins - rgb]
        se = d.std(axis=0, ddof=1) / np.sqrt(d.shape[0])
        mean_rgb = preview[:, columns].reshape(-1, 3).mean(axis=0)
        assert np.all(np.abs(d.mean(axis=0) - binning) < 5 * se + 1e-4 * mean_rgb)
        assert np.all(np.abs(binning) < 0.01 * mean_rgb)  # 10 nm bins: < 1 % here
        assert np.all(np.abs(d.mean(axis=0)) < 0.02 * mean_rgb)


def test_directly_seen_blackbody_gives_its_bin_averages(spectral_image):
    """The sky's pixels: each bin is the bin average of scale * B(l, T) within noise (z < 5
    per bin, from the spread over independent pixels); 5 % off in temperature is caught."""
    wl, spectra, _, _ = spectral_image
    sky = spectra[:, SKY_COLUMNS].reshape(-1, wl.size)
    fine = np.linspace(-5.0, 5.0, 101)

    def bin_average(temperature):
        return SCALE * np.trapezoid(_planck(wl[:, None] + fine, temperature), fine, axis=1) / 10

    se = sky.std(axis=0, ddof=1) / np.sqrt(sky.shape[0])
    assert np.all(se > 0)
    z = (sky.mean(axis=0) - bin_average(TEMPERATURE)) / se
    assert np.max(np.abs(z)) < 5, z
    z_wrong = (sky.mean(axis=0) - bin_average(1.05 * TEMPERATURE)) / se
    assert np.max(np.abs(z_wrong)) > 5


def test_spectral_output_is_refused_where_it_cannot_be_written(tmp_path, capsys):
    assert main(["render", "cornell-box", "--spp", "1", "--spectral",
                 "--out", str(tmp_path / "x.png")]) == 2  # fmt: skip
    assert "must end in .exr" in capsys.readouterr().err
    assert main(["render", "cornell-box", "--spp", "1", "--spectral", "--resume",
                 "--out", str(tmp_path / "x.exr")]) == 2  # fmt: skip
    assert "--checkpoint or --resume" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_render_refuses_bad_spectral_bins_before_rendering(tmp_path, monkeypatch):
    from radiometria.render import _driver, render
    from radiometria.render._integrators import PTracer

    scene = tmp_path / "scene.xml"
    scene.write_text(SCENE)
    for bad, error, message in (
        (0, ValueError, r"\[1, 4710\].*got 0"),
        (4711, ValueError, r"\[1, 4710\].*got 4711"),
        (4.0, TypeError, "int"),
        (True, TypeError, "int"),
    ):
        with pytest.raises(error, match=message):
            render(scene, spp=1, spectral_bins=bad, progress=False)
    with pytest.raises(ValueError, match="PTracer"):
        render(scene, spp=1, spectral_bins=8, integrator=PTracer(), progress=False)
    with pytest.raises(ValueError, match="checkpoint"):
        render(scene, spp=1, spectral_bins=8, checkpoint=tmp_path / "c.npz", progress=False)
    # 16 x 16 pixels x (48 + 12 x 47) B = 153 KiB: refused with 200 KiB available (half of it
    # may go to the film), which is plenty for the RGB film's 12 KiB.
    monkeypatch.setattr(_driver, "_available_host_memory", lambda: 200 * 1024)
    monkeypatch.setattr(_driver, "Film", lambda *a, **k: pytest.fail("film allocated"))
    with pytest.raises(ValueError, match=r"612 bytes per pixel, 47 spectral bins"):
        render(scene, spp=1, spectral_bins=47, progress=False)
