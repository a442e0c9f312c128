"""Spectral indices of refraction: dispersion formulas and tabulated metals."""

import hashlib
from importlib import resources

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

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
