"""Chapter 3 figures: Fresnel curves, lobes, albedos and ray geometry against closed forms, an
independent numpy complex Fresnel, SciPy quadrature, colour-science and Mitsuba 3."""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate, special

from radiometria.figures import FIGURES, make_figures
from radiometria.figures._scattering import (
    albedo_roughness_data,
    brdf_lobes_data,
    fresnel_conductors_data,
    fresnel_dielectric_data,
    reflection_refraction_data,
    reflection_types_data,
)
from radiometria.scattering import conductor_ior


@pytest.fixture(scope="module")
def panels():
    return {p["title"].split(" (")[0]: p for p in reflection_types_data(n_samples=65_536)}


@pytest.fixture(scope="module")
def geometry():
    return reflection_refraction_data()


def _fresnel(cos_i, n):
    """Unpolarised Fresnel reflectance for a (complex) relative index n (Born & Wolf 1.5.2)."""
    n = np.asarray(n, complex)
    cos_t = np.sqrt(1 - (1 - cos_i**2) / n**2 + 0j)
    r_s = (cos_i - n * cos_t) / (cos_i + n * cos_t)
    r_p = (n * cos_i - cos_t) / (n * cos_i + cos_t)
    return 0.5 * (abs(r_s) ** 2 + abs(r_p) ** 2)


def _ggx(wl, w, alpha):
    """Torrance-Sparrow with the GGX distribution and height-correlated Smith G, F = 1."""
    h = wl + w
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    c = h[..., 2]
    tan2 = (1 - c**2) / c**2
    d = alpha**2 / (np.pi * c**4 * (alpha**2 + tan2) ** 2)

    def lam(z):
        return 0.5 * (-1 + np.sqrt(1 + alpha**2 * (1 - z**2) / z**2))

    g = 1 / (1 + lam(w[..., 2]) + lam(wl[2]))
    return np.where(w[..., 2] > 0, d * g / (4 * np.abs(w[..., 2]) * wl[2]), 0.0)


def test_reflection_types_lobes_closed_forms(panels):
    for name, p in panels.items():
        if p["kind"] != "lobe":
            continue
        t, wl = p["t"], p["light"]
        w = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)
        up, cos = w[:, 2] > 0, np.abs(w[:, 2])
        expected = {
            "diffuse reflection": np.where(up, 0.8 / np.pi, 0.0) * cos,
            "glossy reflection": _ggx(wl, w, 0.25) * cos,
            "retroreflection": np.where(up, 0.8 * 14 / (2 * np.pi), 0.0)
            * np.maximum(w @ wl, 0.0) ** 12
            * cos,
            "diffuse transmission": np.where(up, 0.1, 0.7) / np.pi * cos,
        }[name]
        np.testing.assert_allclose(p["lobe"], expected, rtol=1e-6, atol=1e-12, err_msg=name)


def _hemisphere_integral(fn, upper: bool, n_phi: int = 512) -> float:
    """int f |cos theta| d omega over one hemisphere: adaptive `quad` in cos(theta) outside,
    Gauss-Legendre in phi inside."""
    x, wx = special.roots_legendre(n_phi)
    phi, w_phi = np.pi * (x + 1), np.pi * wx

    def ring(mu):
        s = np.sqrt(max(0.0, 1 - mu * mu))
        w = np.stack([s * np.cos(phi), s * np.sin(phi), np.full_like(phi, mu)], axis=-1)
        return float(np.sum(w_phi * fn(w))) * abs(mu)

    lo, hi = (0.0, 1.0) if upper else (-1.0, 0.0)
    value, err = integrate.quad(ring, lo, hi, epsabs=1e-8, epsrel=1e-8, limit=200)
    assert err < 1e-6
    return value


def test_reflection_types_lobes_integrate_to_the_albedo(panels):
    """SciPy quadrature of the plotted function f(w_l, w)|cos| over each hemisphere equals the
    reflected / transmitted fraction the figure prints (Monte Carlo from `sample_f`)."""
    for name, p in panels.items():
        if p["kind"] != "lobe":
            continue
        f = eqx.filter_jit(lambda b, wo, wi: b.f(wo, wi, mode="importance"))
        wl = jnp.asarray(p["light"])

        def fn(w, b=p["bxdf"], f=f, wl=wl):
            return np.asarray(f(b, wl, jnp.asarray(w)))[:, 0]

        for side, upper in (("r", True), ("t", False)):
            quad = _hemisphere_integral(fn, upper)
            mc, se = p[f"albedo_{side}"], p[f"se_{side}"]
            assert abs(quad - mc) <= 5 * se + 1e-6, (name, side, quad, mc, se)
    # Closed forms where there is one: Lambert R; the diffuse sheet R and T.
    assert panels["diffuse reflection"]["albedo_r"] == pytest.approx(0.8, abs=1e-6)
    assert panels["diffuse reflection"]["albedo_t"] == 0.0


def test_reflection_types_delta_lobes(panels):
    wl = panels["perfectly specular reflection"]["light"]
    mirror = np.array([-wl[0], -wl[1], wl[2]])  # law of reflection about +z
    p = panels["perfectly specular reflection"]
    eta, k = (float(np.asarray(x)) for x in conductor_ior("Au", 550.0))
    np.testing.assert_allclose(p["directions"], [mirror], atol=1e-12)
    np.testing.assert_allclose(p["fractions"], [_fresnel(wl[2], eta + 1j * k)], rtol=1e-9)
    assert p["albedo_r"] == pytest.approx(p["fractions"][0], rel=1e-9)
    p = panels["specular transmission"]
    (wr, wt), (fr, ft) = p["directions"], p["fractions"]
    np.testing.assert_allclose(wr, mirror, atol=1e-12)
    sin_i = np.hypot(wl[0], wl[1])
    assert np.hypot(wt[0], wt[1]) * 1.5 == pytest.approx(sin_i, rel=1e-12)  # Snell
    assert wt[2] < 0 and wt[0] * wl[0] < 0  # the far side, across the normal
    assert fr == pytest.approx(_fresnel(wl[2], 1.5), rel=1e-9)
    assert ft == pytest.approx(1 - fr, rel=1e-9)  # flux fractions (importance transport)
    assert p["albedo_r"] + p["albedo_t"] == pytest.approx(1.0, abs=1e-9)
    assert p["albedo_r"] == pytest.approx(fr, abs=5 * p["se_r"] + 1e-9)


def test_reflection_refraction_figure_obeys_the_laws(geometry):
    for c in geometry["cases"]:
        wi, wr, wt = c["wi"], c["wr"], c["wt"]
        for w in (wi, wr, wt):
            assert np.linalg.norm(w) == pytest.approx(1.0, abs=1e-12)
            assert w[1] == 0.0  # the plane of incidence
        # Law of reflection (eq. 3.7): theta_r = theta_i, phi_r = phi_i + pi.
        assert c["theta_r"] == pytest.approx(c["theta_i"], abs=1e-12)
        np.testing.assert_allclose(wr, [-wi[0], 0.0, wi[2]], atol=1e-12)
        sin_i = np.sin(c["theta_i"])
        assert c["valid"] == (c["eta_i"] * sin_i < c["eta_t"])
        if c["valid"]:  # Snell's law (eq. 3.7) on the drawn angle and vector
            assert c["eta_i"] * sin_i == pytest.approx(c["eta_t"] * np.sin(c["theta_t"]))
            assert c["eta_i"] * sin_i == pytest.approx(c["eta_t"] * abs(wt[0]), rel=1e-12)
            assert wt[2] < 0 and wt[0] > 0
            assert c["R"] == pytest.approx(_fresnel(np.cos(c["theta_i"]), c["eta_t"] / c["eta_i"]))
        else:
            assert np.isnan(c["theta_t"]) and c["R"] == 1.0
    assert [c["valid"] for c in geometry["cases"]] == [True, True, False]
    theta = geometry["theta_i"]
    for name, (eta_i, eta_t) in (("air_glass", (1.0, 1.5)), ("glass_air", (1.5, 1.0))):
        cur = geometry[name]
        np.testing.assert_allclose(cur["theta_r"], theta, atol=1e-7)
        valid = eta_i * np.sin(theta) < eta_t
        np.testing.assert_array_equal(cur["valid"], valid)
        np.testing.assert_allclose(
            eta_t * np.sin(cur["theta_t"][valid]), eta_i * np.sin(theta[valid]), atol=1e-12
        )
        assert np.all(np.isnan(cur["theta_t"][~valid]))


@pytest.mark.parametrize(
    "name",
    [
        "fig_3_1_reflection_types",
        "fig_3_2_reflection_refraction",
        "fig_3_fresnel_dielectric",
    ],
)
def test_scattering_figure_written(tmp_path, name):
    assert name in FIGURES
    paths = make_figures(tmp_path, [name], smoke=True)
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]
    assert all(p.stat().st_size > 1000 for p in paths)


# --- Fresnel curves --------------------------------------------------------------------------


def _fresnel_sp(cos_i, n):
    """(R_s, R_p) for a relative index n (complex for conductors), light from the side of the
    normal when cos_i > 0, from inside (index n relative to outside: 1/n) when cos_i < 0.
    Born & Wolf 1.5.2, with complex square roots, so total internal reflection gives |r| = 1."""
    cos_i = np.asarray(cos_i, float)
    n = np.where(cos_i < 0, 1 / np.asarray(n, complex), np.asarray(n, complex))
    c = np.abs(cos_i)
    cos_t = np.sqrt(1 - (1 - c**2) / n**2 + 0j)
    r_s = (c - n * cos_t) / (c + n * cos_t)
    r_p = (n * c - cos_t) / (n * c + cos_t)
    return abs(r_s) ** 2, abs(r_p) ** 2


def test_fresnel_dielectric_figure_equals_numpy_fresnel():
    data = fresnel_dielectric_data(smoke=True)
    theta, eta = data["theta"], data["eta"]
    assert eta == 1.5 and theta[0] == 0 and theta[-1] == pytest.approx(np.pi / 2)
    for side, sign in (("outside", 1.0), ("inside", -1.0)):
        d = data[side]
        r_s, r_p = _fresnel_sp(sign * np.cos(theta), eta)
        np.testing.assert_allclose(d["R_s"], r_s, atol=1e-12, err_msg=side)
        np.testing.assert_allclose(d["R_p"], r_p, atol=1e-12, err_msg=side)
        np.testing.assert_allclose(d["F"], 0.5 * (r_s + r_p), atol=1e-12, err_msg=side)
        assert d["F"][0] == pytest.approx(0.04, abs=1e-12)  # ((1.5 - 1) / (1.5 + 1))^2
        # Brewster's angle: tan(theta_B) = eta_t / eta_i, where R_p vanishes.
        rel = eta if side == "outside" else 1 / eta
        assert d["brewster"] == pytest.approx(np.degrees(np.arctan(rel)), abs=1e-12)
        assert _fresnel_sp(sign * np.cos(np.radians(d["brewster"])), eta)[1] < 1e-25
        assert np.argmin(d["R_p"]) == np.argmin(np.abs(np.degrees(theta) - d["brewster"]))
    # Total internal reflection beyond the critical angle, arcsin(1 / 1.5) = 41.81 deg.
    critical = data["inside"]["critical"]
    assert critical == pytest.approx(41.8103149, abs=1e-6)
    tir = np.degrees(theta) > critical
    np.testing.assert_allclose(data["inside"]["F"][tir], 1.0, atol=1e-12)
    assert np.all(data["inside"]["F"][~tir] < 1.0)


@pytest.fixture(scope="module")
def metals():
    return fresnel_conductors_data(smoke=True)


def test_fresnel_conductors_figure_equals_numpy_fresnel(metals):
    theta = metals["theta"]
    assert list(metals["metals"]) == ["Au", "Ag", "Cu", "Al"]
    for sym, m in metals["metals"].items():
        n = m["eta"] + 1j * m["k"]
        expected = ((m["eta"] - 1) ** 2 + m["k"] ** 2) / ((m["eta"] + 1) ** 2 + m["k"] ** 2)
        np.testing.assert_allclose(m["R"], expected, rtol=1e-12, err_msg=sym)
        np.testing.assert_allclose(m["R"], np.mean(_fresnel_sp(1.0, n), axis=0), rtol=1e-12)
        n550 = m["eta_550"] + 1j * m["k_550"]
        r_s, r_p = _fresnel_sp(np.cos(theta), n550)
        np.testing.assert_allclose(m["F_550"], 0.5 * (r_s + r_p), atol=1e-12, err_msg=sym)
        i550 = np.argmin(np.abs(metals["wavelengths_nm"] - 550.0))
        if metals["wavelengths_nm"][i550] == 550.0:
            assert m["F_550"][0] == pytest.approx(m["R"][i550], rel=1e-12)
        assert m["F_550"][-1] == pytest.approx(1.0, abs=1e-9)  # grazing incidence
    # Gold and copper reflect red far better than blue; silver and aluminium are bright.
    wl = metals["wavelengths_nm"]
    for sym in ("Au", "Cu"):
        R = metals["metals"][sym]["R"]
        assert R[wl >= 700].min() > 0.9 and R[(wl > 420) & (wl < 460)].max() < 0.6
    for sym in ("Ag", "Al"):
        assert metals["metals"][sym]["R"][wl >= 450].min() > 0.85


def test_fresnel_conductors_figure_optical_constants_match_mitsuba(metals):
    """Normal-incidence reflectance at the plotted wavelengths against Mitsuba 3's conductor
    presets (its own tabulated eta, k; 4 wavelengths per query in `scalar_spectral`)."""
    mi = pytest.importorskip("mitsuba")
    import drjit as dr

    wl = metals["wavelengths_nm"]
    pick = np.flatnonzero((wl >= 400) & (wl <= 760))[::5]
    pick = pick[: 4 * (len(pick) // 4)]
    mi.set_variant("scalar_spectral")
    try:
        for sym, m in metals["metals"].items():
            bsdf = mi.load_dict({"type": "conductor", "material": sym})
            for group in pick.reshape(-1, 4):
                si = dr.zeros(mi.SurfaceInteraction3f)
                si.wi = mi.Vector3f(0.0, 0.0, 1.0)
                si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
                si.wavelengths = mi.Spectrum([float(w) for w in wl[group]])
                _, weight = bsdf.sample(mi.BSDFContext(), si, 0.5, mi.Point2f(0.5, 0.5))
                np.testing.assert_allclose(m["R"][group], np.array(weight), rtol=1e-4)
    finally:
        mi.set_variant("scalar_rgb")


def test_fresnel_conductors_figure_swatches_equal_colour_science(metals):
    colour = pytest.importorskip("colour")
    wl = metals["wavelengths_nm"]
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    for sym, m in metals["metals"].items():
        sd = colour.SpectralDistribution(dict(zip(wl, m["R"], strict=True)))
        xyz = colour.sd_to_XYZ(sd, cmfs, d65, method="Integration") / 100
        rgb = colour.XYZ_to_sRGB(xyz)
        np.testing.assert_allclose(m["rgb"], np.clip(rgb, 0, 1), atol=0.01, err_msg=sym)
    gold, silver = metals["metals"]["Au"]["rgb"], metals["metals"]["Ag"]["rgb"]
    assert gold[0] > gold[1] > gold[2] and np.ptp(silver) < 0.05


# --- BRDF lobes ------------------------------------------------------------------------------


def _oren_nayar(wo, wi, sigma):
    """Qualitative Oren-Nayar (Oren & Nayar 1994, pbrt-v3 8.4.2) in angles, R = 1."""
    s2 = sigma**2
    A, B = 1 - s2 / (2 * (s2 + 0.33)), 0.45 * s2 / (s2 + 0.09)
    th_o, th_i = np.arccos(wo[:, 2]), np.arccos(wi[2])
    cos_dphi = np.cos(np.arctan2(wo[:, 1], wo[:, 0]) - np.arctan2(wi[1], wi[0]))
    cos_dphi = np.where(np.hypot(wo[:, 0], wo[:, 1]) < 1e-12, 0.0, cos_dphi)
    alpha, beta = np.maximum(th_o, th_i), np.minimum(th_o, th_i)
    return (A + B * np.maximum(0, cos_dphi) * np.sin(alpha) * np.tan(beta)) / np.pi


def test_brdf_lobes_figure_equal_closed_forms():
    data = brdf_lobes_data(smoke=True)
    t, wi = data["t"], data["wi"]
    np.testing.assert_allclose(wi, [-np.sqrt(0.5), 0, np.sqrt(0.5)], atol=1e-15)
    wo = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)
    assert list(data["ggx"]) == [0.05, 0.1, 0.2, 0.4, 0.7]
    for alpha, v in data["ggx"].items():
        np.testing.assert_allclose(v, _ggx(wi, wo, alpha) * np.cos(t), rtol=1e-6, atol=1e-12)
        # The normalised lobe peaks near the mirror direction, theta_o = +45 deg, for small
        # alpha (the off-specular shift grows with alpha, Torrance-Sparrow).
        if alpha <= 0.1:
            assert abs(np.degrees(t[np.argmax(v)]) - 45.0) < 3.0
    (l_lab, _, lam), *on = data["diffuse"]
    assert l_lab == "Lambert"
    np.testing.assert_allclose(lam, np.cos(t) / np.pi, rtol=1e-12, atol=1e-15)
    for (label, _, v), sigma in zip(on, (0.5, 1.0), strict=True):
        assert f"{sigma:g}" in label
        np.testing.assert_allclose(v, _oren_nayar(wo, wi, sigma) * np.cos(t), rtol=1e-6, atol=1e-12)
    # Oren-Nayar scatters more back towards the light than forward (where it is A / pi).
    back, fwd = np.argmin(np.abs(t + np.pi / 4)), np.argmin(np.abs(t - np.pi / 4))
    for _, _, v in on:
        assert v[back] > v[fwd] and v[fwd] < lam[fwd]


# --- albedo against roughness ----------------------------------------------------------------


@pytest.fixture(scope="module")
def albedos():
    return albedo_roughness_data(smoke=True)


def test_albedo_roughness_figure_conductor_equals_quadrature(albedos):
    """The Monte Carlo albedo of the unit-Fresnel GGX conductor equals SciPy quadrature of the
    closed-form Torrance-Sparrow lobe (`_ggx`) times cos, within 5 standard errors; it is
    below 1 (single scattering loses energy) and decreases with roughness."""
    alphas, mus = albedos["alphas"], albedos["mus"]
    np.testing.assert_allclose(mus, [1.0, 0.5, 0.2])
    res = albedos["conductor"]
    assert res.shape == (3, alphas.size, 2) and albedos["n"] == 4096
    for i, mu in enumerate(mus):
        wo = np.array([np.sqrt(1 - mu * mu), 0.0, mu])
        for j, alpha in enumerate(alphas[::2]):
            quad = _hemisphere_integral(lambda w, a=alpha, wo=wo: _ggx(wo, w, a), True)
            mean, se = res[i, 2 * j]
            assert abs(mean - quad) <= 5 * se + 1e-3, (mu, alpha, mean, quad, se)
        assert np.all(np.diff(res[i, :, 0]) < 0)
    assert np.all(res[:, :, 0] < 1.0)
    assert res[0, 0, 0] > 0.99 and res[2, -1, 0] < 0.75  # smooth at normal; rough at grazing


def test_albedo_roughness_figure_dielectric_equals_quadrature(albedos):
    """R + T of the rough dielectric: SciPy quadrature of its f |cos| (importance transport)
    over both hemispheres equals the plotted Monte Carlo mean within 5 standard errors."""
    from radiometria.scattering import RoughDielectricBxDF

    f = eqx.filter_jit(lambda b, wo, wi: b.f(wo, wi, mode="importance"))
    res = albedos["dielectric"]
    for i, mu in enumerate(albedos["mus"][:2]):
        wo = jnp.asarray([np.sqrt(1 - mu * mu), 0.0, mu])
        for j in (2, 5):
            b = RoughDielectricBxDF(albedos["alphas"][j], 1.5)

            def fn(w, b=b, wo=wo):
                return np.asarray(f(b, wo, jnp.asarray(w)))[:, 0]

            quad = _hemisphere_integral(fn, True) + _hemisphere_integral(fn, False)
            mean, se = res[i, j]
            assert abs(mean - quad) <= 5 * se + 1e-3, (mu, j, mean, quad, se)
    assert np.all(res[:, :, 0] < 1.0 + 5 * res[:, :, 1])
