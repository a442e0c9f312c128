"""Spectral indices of refraction: dispersion formulas and tabulated metals."""

import hashlib
from importlib import resources

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads

import radiometria.scattering as sc


@pytest.mark.parametrize(
    "name,wl,n_ref",
    [
        # Reference values: SCHOTT N-BK7 datasheet n_d = 1.5168 (587.56 nm), n_F = 1.5224
        # (486.13 nm), n_C = 1.5143 (656.27 nm); Malitson 1965 fused silica n_d = 1.4585;
        # Daimon & Masumura 2007 (20 °C) fit: n(589.3 nm) = 1.3333.
        ("BK7", 587.56, 1.5168),
        ("N-BK7", 486.13, 1.5224),
        ("BK7", 656.27, 1.5143),
        ("fused silica", 587.56, 1.4585),
        ("SiO2", 486.13, 1.4632),
        ("water", 589.3, 1.3333),
        ("H2O", 589.3, 1.3333),
    ],
)
def test_dielectric_ior_reference_values(name, wl, n_ref):
    np.testing.assert_allclose(sc.dielectric_ior(name, wl), n_ref, atol=1.5e-4)


def test_dielectric_ior_normal_dispersion_and_shapes():
    wl = jnp.linspace(380.0, 780.0, 41)
    for name in ("BK7", "fused silica", "water"):
        n = np.asarray(sc.dielectric_ior(name, wl))
        assert n.shape == (41,) and np.all(np.diff(n) < 0)  # n falls with wavelength
    assert sc.dielectric_ior("BK7", jnp.ones((2, 4)) * 500.0).shape == (2, 4)
    with pytest.raises(ValueError, match="dielectric"):
        sc.dielectric_ior("unobtainium", 500.0)
    with pytest.raises(eqx.EquinoxRuntimeError, match="wavelength_nm"):
        sc.dielectric_ior("BK7", -500.0)


def test_conductor_tables_provenance_hashes():
    doc = sc.conductor_ior.__module__
    import importlib

    mod_doc = importlib.import_module(doc).__doc__
    for m in sc.CONDUCTORS:
        for c in ("eta", "k"):
            name = f"{m}.{c}.spd"
            data = (
                resources.files("radiometria.scattering").joinpath("data", "ior", name).read_bytes()
            )
            assert hashlib.sha256(data).hexdigest() in mod_doc, name


def test_conductor_ior_interpolates_table_nodes():
    tab = sc.get_conductor("Au")
    # At table nodes the interpolant reproduces the table.
    eta, k = tab(tab.wavelengths_eta_nm)
    np.testing.assert_allclose(eta, tab.eta, rtol=1e-14)
    # Gold: strong absorption, yellow (reflectance rises from blue to red).
    wl = jnp.array([450.0, 550.0, 650.0])
    eta, k = sc.conductor_ior("Au", wl)
    R = np.asarray(sc.fresnel_conductor(1.0, eta, k))
    assert R[0] < R[1] < R[2]
    # Silver and aluminium are bright everywhere in the visible.
    for m in ("Ag", "Al"):
        e, kk = sc.conductor_ior(m, jnp.linspace(400.0, 700.0, 7))
        assert np.all(np.asarray(sc.fresnel_conductor(1.0, e, kk)) > 0.85)
    # Constant extrapolation beyond the table.
    e_hi, _ = sc.conductor_ior("Cu", 2000.0)
    np.testing.assert_allclose(e_hi, sc.get_conductor("Cu").eta[-1])
    with pytest.raises(ValueError, match="conductor"):
        sc.conductor_ior("Pt", 500.0)


def test_conductor_ior_jit_grad():
    f = jax.jit(lambda wl: sc.fresnel_conductor(0.7, *sc.conductor_ior("Cu", wl)))
    np.testing.assert_allclose(
        f(jnp.array([500.0, 600.0])),
        sc.fresnel_conductor(0.7, *sc.conductor_ior("Cu", jnp.array([500.0, 600.0]))),
    )
    g = jax.grad(lambda wl: f(wl).sum())(jnp.array([500.0, 600.0]))
    assert np.all(np.isfinite(np.asarray(g)))


@pytest.mark.parametrize("metal", ["Au", "Ag", "Cu", "Al"])
def test_conductor_ior_matches_mitsuba_presets(metal):
    mi = pytest.importorskip("mitsuba")
    import drjit as dr

    mi.set_variant("scalar_spectral")
    try:
        bsdf = mi.load_dict({"type": "conductor", "material": metal})
        wls = [[400.0, 480.0, 555.5, 700.0], [420.0, 515.0, 610.0, 760.0]]
        for wl in wls:
            si = dr.zeros(mi.SurfaceInteraction3f)
            si.wi = mi.Vector3f(0.3, 0.0, float(np.sqrt(1 - 0.09)))
            si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
            si.wavelengths = mi.Spectrum(wl)
            _, weight = bsdf.sample(mi.BSDFContext(), si, 0.5, mi.Point2f(0.5, 0.5))
            eta, k = sc.conductor_ior(metal, jnp.asarray(wl))
            ours = sc.fresnel_conductor(float(np.sqrt(1 - 0.09)), eta, k)
            np.testing.assert_allclose(ours, np.array(weight), rtol=1e-5)
    finally:
        mi.set_variant("scalar_rgb")


# --------------------------------------------------------------------------------------------
# Relative complex index of two absorbing media (thesis footnote 18)


def _fresnel_numpy(cos_i, n1, n2):
    """Unpolarised reflectance from the complex Fresnel amplitudes with complex n1, n2 (Born &
    Wolf 14.2): n1 sin(theta_1) = n2 sin(theta_2), r_s = (n1 c1 - n2 c2)/(n1 c1 + n2 c2),
    r_p = (n2 c1 - n1 c2)/(n2 c1 + n1 c2); the transmitted wave decays (Im(n2 c2) >= 0)."""
    c1 = np.asarray(cos_i, complex)
    s1 = np.sqrt(1 - c1**2)
    c2 = np.sqrt(1 - (n1 * s1 / n2) ** 2)
    c2 = np.where(np.imag(n2 * c2) < 0, -c2, c2)
    r_s = (n1 * c1 - n2 * c2) / (n1 * c1 + n2 * c2)
    r_p = (n2 * c1 - n1 * c2) / (n2 * c1 + n1 * c2)
    return 0.5 * (np.abs(r_s) ** 2 + np.abs(r_p) ** 2)


def test_relative_complex_ior_vacuum_is_identity():
    eta, k = sc.conductor_ior("Au", jnp.linspace(400.0, 700.0, 7))
    e, kk = sc.relative_complex_ior(1.0, 0.0, eta, k)
    np.testing.assert_allclose(e, eta, rtol=1e-15)
    np.testing.assert_allclose(kk, k, rtol=1e-15)


def test_relative_complex_ior_matches_complex_division_and_fresnel():
    rng = np.random.default_rng(0)
    n = 200
    eta_i = rng.uniform(1.0, 2.0, n)
    k_i = rng.uniform(0.0, 0.05, n)  # a weakly absorbing incident medium (tinted glass)
    eta_t = rng.uniform(0.1, 3.0, n)
    k_t = rng.uniform(1.0, 5.0, n)  # a metal
    e, k = sc.relative_complex_ior(eta_i, k_i, eta_t, k_t)
    ratio = (eta_t + 1j * k_t) / (eta_i + 1j * k_i)
    np.testing.assert_allclose(e, ratio.real, rtol=1e-14)
    np.testing.assert_allclose(k, ratio.imag, rtol=1e-14)
    assert float(jnp.min(k)) >= 0
    cos_i = rng.uniform(0.0, 1.0, n)
    F = sc.fresnel_conductor(cos_i, e, k)
    F_ref = _fresnel_numpy(cos_i, eta_i + 1j * k_i, eta_t + 1j * k_t)
    np.testing.assert_allclose(F, F_ref, rtol=1e-10, atol=1e-14)
    # Gold seen from inside water (eta_i = 1.333) is darker than seen from air at normal
    # incidence: the index contrast is smaller.
    eta_au, k_au = sc.conductor_ior("Au", 550.0)
    ew, kw = sc.relative_complex_ior(1.333, 0.0, eta_au, k_au)
    assert float(sc.fresnel_conductor(1.0, ew, kw)) < float(sc.fresnel_conductor(1.0, eta_au, k_au))


def test_relative_complex_ior_transformations_and_errors():
    f = jax.jit(sc.relative_complex_ior)
    out = f(1.5, 0.01, jnp.array([0.2, 0.3]), jnp.array([3.0, 2.0]))
    ref = sc.relative_complex_ior(1.5, 0.01, jnp.array([0.2, 0.3]), jnp.array([3.0, 2.0]))
    np.testing.assert_allclose(out, ref, rtol=1e-15)
    check_grads(lambda a, b: sc.relative_complex_ior(a, 0.1, b, 2.0)[1], (1.4, 0.5), 1)
    g = eqx.filter_jit(sc.relative_complex_ior)
    with pytest.raises(eqx.EquinoxRuntimeError, match="eta_i"):
        g(0.0, 0.0, 1.0, 1.0)
    with pytest.raises(eqx.EquinoxRuntimeError, match="k_t"):
        g(1.0, 0.0, 1.0, -1.0)
    with pytest.raises(ValueError, match="broadcast"):
        sc.relative_complex_ior(jnp.ones(2), 0.0, jnp.ones(3), 0.0)
