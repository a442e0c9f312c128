"""The packaged wide-gamut tables (Display P3, Rec.2020, ACEScg, beside sRGB): provenance,
accuracy over the colours a reflectance can have, and what the lookup returns for the others.
"""

import hashlib

import numpy as np
import pytest

import radiometria.upsampling as up
from radiometria.upsampling import _data
from radiometria.upsampling._roundtrip import has_reflectance, object_colour_scale

SPACES = ["sRGB", "Display P3", "ITU-R BT.2020", "ACEScg"]


def _lab(xyz, white_xyz):
    """CIELAB by colour-science (independent of radiometria's colorimetry)."""
    import colour

    return colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(white_xyz))


def _delta_E_2000(lab_a, lab_b):
    import colour

    return np.asarray(colour.delta_E(lab_a, lab_b, method="CIE 2000"))


def test_packaged_files_match_their_provenance():
    assert set(_data.PACKAGED_FILES) == set(SPACES)
    for space, fname in _data.PACKAGED_FILES.items():
        path = _data.DATA_DIR / fname
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
        assert digest == _data.PACKAGED_SHA256[fname], fname
        assert fname in _data.__doc__ and digest in _data.__doc__  # the docstring's record
        scale, coeffs, meta = _data.read_packaged(path)  # checks the stored array sha256
        assert meta["colourspace"] == space and meta["resolution"] == 64
        assert coeffs.shape == (3, 64, 64, 64, 3) and coeffs.dtype == np.float32
        np.testing.assert_allclose(scale, up.brightness_scale(64), rtol=1e-6, atol=1e-12)
        s = meta["fit_summary"]
        n = s["converged"] + s["out_of_reach"] + s["not_converged"] + s["tail_free"]
        assert n == s["entries"]
        tails = meta["fit"]["infrared_tails"]  # the tail stage ran (`_tails.py`)
        assert 0 < tails["replaced"] <= tails["entries_with_tail"]
        assert s["residual_max_converged"] <= s["tolerance"]
        assert meta["fit"]["wavelength_step_nm"] == 1.0
        if space == "sRGB":
            assert s["out_of_reach"] == 0 and s["not_converged"] == 0
        else:  # measured: 56, 453, 1272 entries stopped early, nearly all out of reach
            assert s["not_converged"] <= 0.002 * s["entries"]
            assert meta["roundtrip_random_1e5_linear"]["fraction_out_of_reach"] > 0


def test_get_lut_reads_the_packaged_tables_without_fitting(monkeypatch):
    def no_fit(*args, **kwargs):
        raise AssertionError("get_lut fitted a table that is packaged")

    monkeypatch.setattr(_data, "fit_lut", no_fit)
    for space, alias in zip(SPACES, ["sRGB", "P3-D65", "Rec.2020", "ACEScg"], strict=True):
        assert _data.packaged_path(alias) == _data.DATA_DIR / _data.PACKAGED_FILES[space]
        lut = _data._get_lut_cached.__wrapped__(space)  # bypass the session cache
        assert lut.colourspace == space and lut.resolution == 64
    assert _data.packaged_path("ProPhoto RGB") is None  # fitted on first use instead


def test_object_colour_scale_matches_a_linear_programme():
    """t* = max t such that t rgb = sum_i s_i W_i with 0 <= s_i <= 1, by SciPy's HiGHS."""
    from scipy.optimize import linprog

    rng = np.random.default_rng(3)
    for space in ("sRGB", "ITU-R BT.2020", "ACEScg"):
        model = up.forward_model(space)
        rgb = np.concatenate([rng.random((6, 3)), np.eye(3), [[1.0, 1.0, 1.0], [0.5, 0.5, 0.5]]])
        t = object_colour_scale(rgb, space)
        w = model.weights_XYZ  # (n, 3)
        for x, t_ours in zip(rgb @ model.matrix_RGB_to_XYZ.T, t, strict=True):
            n = w.shape[0]
            res = linprog(
                np.r_[np.zeros(n), -1.0],
                A_eq=np.c_[w.T, -x],
                b_eq=np.zeros(3),
                bounds=[(0.0, 1.0)] * n + [(0.0, None)],
                method="highs",
            )
            assert res.status == 0
            np.testing.assert_allclose(t_ours, -res.fun, rtol=1e-6, atol=1e-9)
        np.testing.assert_array_equal(has_reflectance(rgb, space), t >= 1.0 - 1e-9)
    # White is exactly the perfect reflector; Rec.2020's primaries are monochromatic.
    assert abs(object_colour_scale(np.ones((1, 3)), "sRGB")[0] - 1.0) < 1e-9
    assert np.all(object_colour_scale(np.eye(3), "ITU-R BT.2020") < 0.05)


def _reachable_roundtrip_delta_E(space, *, refine=True):
    """CIEDE2000 (colour-science) of the round trip of random colours of the space's cube that a
    reflectance can have: 3000 uniform linear colours and 1000 dark ones (u^4). `refine=False`
    measures the table's trilinear interpolation alone (pbrt's lookup)."""
    lut = up.get_lut(space)
    if not refine:
        lut = lut.with_refinement(0)
    model = up.forward_model(space)
    rng = np.random.default_rng(11)
    rgb = np.concatenate([rng.random((3000, 3)), rng.random((1000, 3)) ** 4])
    rgb = rgb[has_reflectance(rgb, space)]
    spectra = np.asarray(up.RGBAlbedoSpectrum(lut, rgb)(model.wavelengths_nm))
    xyz_out = spectra @ model.weights_XYZ
    xyz_in = rgb @ model.matrix_RGB_to_XYZ.T
    de = _delta_E_2000(_lab(xyz_in, model.white_XYZ), _lab(xyz_out, model.white_XYZ))
    assert rgb.shape[0] >= 3000
    return de


# The tables' trilinear interpolation alone (pbrt's lookup), measured on this sample when the
# tables were built (max, mean, p99): it misses the sRGB goal (max <= 1, mean <= 0.03) in the
# cells of the table that touch colours no reflectance has (see `_lut.py`), which is why the
# wide-gamut tables refine their lookups. Held to these values (x 1.1) so the tables' own
# quality cannot regress unseen.
WIDE_GAMUT_INTERPOLATION = {
    "Display P3": (5.936, 0.0428, 0.582),
    "ITU-R BT.2020": (3.181, 0.0550, 0.730),
    "ACEScg": (7.798, 0.0823, 1.604),
}


@pytest.mark.slow
@pytest.mark.parametrize("space", SPACES)
def test_packaged_tables_reach_the_srgb_accuracy_on_reachable_colours(space):
    """Issue 17's goal for every packaged table: max CIEDE2000 <= 1, mean <= 0.03 over the
    colours of the cube that a reflectance has (the wide-gamut lookups refined by the fit,
    `_lut.py`; sRGB by pbrt's plain lookup)."""
    assert (up.get_lut(space).refine_steps > 0) == (space != "sRGB")
    de = _reachable_roundtrip_delta_E(space)
    assert de.max() <= 1.0 and de.mean() <= 0.03, (de.max(), de.mean())


@pytest.mark.slow
@pytest.mark.parametrize("space", SPACES[1:])
def test_wide_gamut_table_interpolation_alone(space):
    """Without refinement the wide-gamut tables miss the goal (which is why they refine), by no
    more than when they were built."""
    de = _reachable_roundtrip_delta_E(space, refine=False)
    mx, mean, p99 = WIDE_GAMUT_INTERPOLATION[space]
    assert de.max() > 1.0  # the refinement is needed
    assert de.max() <= 1.1 * mx and de.mean() <= 1.1 * mean, (de.max(), de.mean())
    assert np.quantile(de, 0.99) <= 1.1 * p99


@pytest.mark.parametrize("space", ["Display P3", "ACEScg"])
def test_refined_lookup_gradient_matches_finite_differences(space):
    """d S(lambda) / d rgb of a refined lookup (implicit-function derivative) against central
    differences of the refined lookup itself, for colours in cells that mix reachable and
    unreachable nodes and for ordinary ones."""
    import jax

    lut = up.get_lut(space)
    rgb = np.array([[0.7756, 0.0065, 0.0014], [0.4666, 0.0025, 0.1192], [0.3, 0.5, 0.2]])
    rgb = rgb[has_reflectance(rgb, space)]
    assert rgb.shape[0] >= 2
    wl = np.array([450.0, 550.0, 610.0, 650.0])

    def s(x):
        return up.RGBAlbedoSpectrum(lut, x[None])(wl)[0]

    h = 1e-6
    for x in rgb:
        jac = np.asarray(jax.jacfwd(s)(x))
        rev = np.asarray(jax.jacrev(s)(x))
        fd = np.stack(
            [(np.asarray(s(x + h * e)) - np.asarray(s(x - h * e))) / (2 * h) for e in np.eye(3)],
            axis=-1,
        )
        np.testing.assert_allclose(jac, fd, rtol=2e-3, atol=1e-5)
        np.testing.assert_allclose(rev, jac, rtol=1e-9, atol=1e-12)


def test_refine_steps_come_from_the_fit_record(tmp_path):
    """`load_lut` refines the lookups of a table whose fit found unreachable colours; sRGB
    stays pbrt's plain lookup; a bad value is refused by name."""
    for space in SPACES:
        scale, coeffs, meta = _data.read_packaged(_data.DATA_DIR / _data.PACKAGED_FILES[space])
        unreachable = meta["fit_summary"]["out_of_reach"] > 0
        assert unreachable == (space != "sRGB")
        assert up.get_lut(space).refine_steps == (32 if unreachable else 0)
    lut = up.get_lut("ACEScg")
    assert lut.with_refinement(0).refine_steps == 0
    with pytest.raises(ValueError, match="refine_steps"):
        lut.with_refinement(-1)
    with pytest.raises((TypeError, ValueError), match="refine_steps"):  # jaxtyping or ours
        up.RGBToSpectrumLUT(lut.scale, lut.coeffs, "ACEScg", refine_steps=2.5)


def _optimal_colours_Lab(model):
    """CIELAB of every band-pass and band-stop 0/1 reflectance on the 1 nm grid: the optimal
    colours (Rösch-MacAdam), a fine sample of the object-colour solid's boundary."""
    w = model.weights_XYZ
    cum = np.concatenate([np.zeros((1, 3)), np.cumsum(w, axis=0)])
    a, b = np.triu_indices(cum.shape[0], k=1)
    band = cum[b] - cum[a]  # reflectance 1 on samples a .. b - 1
    xyz = np.concatenate([band, model.white_XYZ - band])
    return _lab(xyz, model.white_XYZ)


@pytest.mark.parametrize("space", ["ITU-R BT.2020", "ACEScg"])
def test_out_of_reach_colours_get_a_bounded_nearest_fit(space):
    """Colours of the cube that no reflectance has. The looked-up spectrum is in [0, 1] and its
    colour is one a reflectance has. At the table's nodes (where the fit stored its least-
    squares best fit) that colour is the nearest reachable one in CIELAB: within 0.01 of the
    nearest optimal colour on the 1 nm grid (measured: 0.002; it can be closer, as the
    solid's boundary also holds spectra with one fractional sample). Between nodes the refined
    lookup (a local fit from the interpolated coefficients and from 0) is not guaranteed to
    find the nearest colour, but its colour is much nearer than the flat spectrum of the same
    L* (at most half its distance)."""
    lut = up.get_lut(space)
    model = up.forward_model(space)
    scale = np.asarray(lut.scale, np.float64)
    rng = np.random.default_rng(5)
    k = rng.integers(20, 64, 400)
    ij = rng.integers(0, 64, (400, 2)) / 63.0
    nodes = scale[k, None] * np.c_[np.ones(400), ij]  # nodes of the red-largest block
    nodes = nodes[~has_reflectance(nodes, space)][:40]
    off = rng.random((2000, 3))
    off = off[~has_reflectance(off, space)][:100]
    assert nodes.shape[0] == 40 and off.shape[0] == 100
    opt = _optimal_colours_Lab(model)
    for rgb, at_nodes in ((nodes, True), (off, False)):
        spectra = np.asarray(up.RGBAlbedoSpectrum(lut, rgb)(model.wavelengths_nm))
        assert spectra.min() >= 0.0 and spectra.max() <= 1.0
        xyz = spectra @ model.weights_XYZ
        assert np.all(object_colour_scale(xyz @ model.matrix_XYZ_to_RGB.T, space) >= 1 - 1e-6)
        lab_t = _lab(rgb @ model.matrix_RGB_to_XYZ.T, model.white_XYZ)
        d_fit = np.linalg.norm(_lab(xyz, model.white_XYZ) - lab_t, axis=-1)
        d_flat = np.hypot(lab_t[:, 1], lab_t[:, 2])  # to the grey of the same L*
        assert np.all(d_fit <= 0.5 * d_flat), np.max(d_fit / d_flat)
        if at_nodes:
            d_opt = np.array([np.linalg.norm(opt - lt, axis=-1).min() for lt in lab_t])
            assert np.all(d_fit <= d_opt + 0.01), np.max(d_fit - d_opt)
