"""Figures 3.1 and 3.2: lobes, albedos and ray geometry against closed forms and SciPy."""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate, special

from radiometria.figures import FIGURES, make_figures
from radiometria.figures._scattering import reflection_refraction_data, reflection_types_data
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


@pytest.mark.parametrize("name", ["fig_3_1_reflection_types", "fig_3_2_reflection_refraction"])
def test_scattering_figure_written(tmp_path, name):
    assert name in FIGURES
    paths = make_figures(tmp_path, [name], smoke=True)
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]
    assert all(p.stat().st_size > 1000 for p in paths)
