"""Chapter 5-7 figures: point sets against SciPy's QMC generators and discrepancy, convergence
slopes against QMC theory, variance-reduction estimators against SciPy quadrature of their
exact moments."""

import itertools

import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate, special
from scipy.stats import qmc

from radiometria.figures import FIGURES, _montecarlo, make_figures
from radiometria.figures._montecarlo import (
    _H,
    _RECT,
    RECT_METHODS,
    convergence_figure_data,
    point_sets_data,
    variance_reduction_data,
)

# --- fig. 5: point sets ---------------------------------------------------------------------


@pytest.fixture(scope="module")
def points():
    return point_sets_data(smoke=True)


def _one_per_cell(pts, nx, ny):
    """Every cell of an nx x ny grid on [0, 1)^2 holds exactly one point."""
    ix, iy = np.floor(pts[:, 0] * nx).astype(int), np.floor(pts[:, 1] * ny).astype(int)
    counts = np.zeros((nx, ny), int)
    np.add.at(counts, (ix, iy), 1)
    return bool(np.all(counts == 1))


def test_point_sets_figure_qmc_equals_scipy(points):
    """Unscrambled Halton (bases 2, 3) and Sobol (Joe-Kuo) equal SciPy's, point for point."""
    n, sets = points["n"], dict(points["sets"])
    assert n == 64 and points["side"] == 8
    np.testing.assert_array_equal(sets["Halton (2, 3)"], qmc.Halton(2, scramble=False).random(n))
    np.testing.assert_array_equal(sets["Sobol (Joe-Kuo)"], qmc.Sobol(2, scramble=False).random(n))


def test_point_sets_figure_stratification(points):
    n, side, sets = points["n"], points["side"], dict(points["sets"])
    for pts in sets.values():
        assert pts.shape == (n, 2) and np.all((pts >= 0) & (pts < 1))
    assert _one_per_cell(sets[f"stratified {side}x{side}"], side, side)
    assert _one_per_cell(sets["Latin hypercube"], n, 1) and _one_per_cell(
        sets["Latin hypercube"], 1, n
    )
    # Sobol, scrambled or not, is a (0, 6, 2)-net in base 2: one point in every elementary
    # interval of volume 1/64; Halton is not (its bases differ).
    m = int(np.log2(n))
    for name in ("Sobol (Joe-Kuo)", "Sobol, Owen-scrambled"):
        for a in range(m + 1):
            assert _one_per_cell(sets[name], 2**a, 2 ** (m - a)), (name, a)
    assert not _one_per_cell(sets["independent"], side, side)


def test_point_sets_figure_discrepancy(points):
    """L2-star discrepancy (scipy.stats.qmc.discrepancy): for iid uniform points
    E[D^2] = (2^-d - 3^-d) / n (Warnock); the QMC sets lie far below that, the plotted
    independent set near it."""
    n, sets = points["n"], dict(points["sets"])
    disc = {k: qmc.discrepancy(v, method="L2-star") for k, v in sets.items()}
    expected = (2.0**-2 - 3.0**-2) / n
    assert 0.05 * expected < disc["independent"] ** 2 < 5 * expected
    for name in ("Halton (2, 3)", "Sobol (Joe-Kuo)", "Sobol, Owen-scrambled", "stratified 8x8"):
        assert disc[name] ** 2 < 0.25 * expected, (name, disc[name] ** 2, expected)
        assert disc[name] < disc["independent"]


# --- fig. 6: convergence --------------------------------------------------------------------


def _gauss_legendre_integral(f, dim, breaks, order=24):
    """Tensor Gauss-Legendre rule on [0, 1]^dim, split at `breaks` (dim,) so that each piece
    is smooth (the kinks and jumps of Genz's continuous and discontinuous families)."""
    x, w = special.roots_legendre(order)
    total = 0.0
    for box in itertools.product(*[((0.0, b), (b, 1.0)) for b in breaks]):
        nodes = [lo + (hi - lo) * (x + 1) / 2 for lo, hi in box]
        weights = [(hi - lo) / 2 * w for lo, hi in box]
        grid = np.stack(np.meshgrid(*nodes, indexing="ij"), -1).reshape(-1, dim)
        wgrid = np.prod(np.stack(np.meshgrid(*weights, indexing="ij"), -1), -1).ravel()
        total += float(wgrid @ np.asarray(f(jnp.asarray(grid))))
    return total


@pytest.fixture(scope="module")
def convergence():
    """Smoke sizes, 32 replicates; Latin hypercube left out (its per-n compilations are most of
    the 20 s the full data take)."""
    return convergence_figure_data(smoke=True, n_replicates=32, methods=("mc", "halton", "sobol"))


def test_convergence_figure_exact_integrals(convergence):
    """The reference integrals (genz's closed forms) against Gauss-Legendre quadrature of the
    plotted integrands."""
    for p in convergence["problems"]:
        breaks = p["w"] if p["kind"] in ("continuous", "discontinuous") else [0.5] * p["dim"]
        order = 12 if p["dim"] == 4 else 24
        quad = _gauss_legendre_integral(p["f"], p["dim"], breaks, order)
        assert p["exact"] == pytest.approx(quad, rel=1e-9, abs=1e-12), p["title"]


def test_convergence_figure_slopes(convergence):
    """Fitted log-log slopes of the RMSE, n = 16 ... 256, 32 replicates per n.

    Tolerance: an RMSE from r = 32 replicates has a relative standard error of about
    1/sqrt(2 r) = 0.125 (more for skewed errors); the least-squares slope over 5 points
    spaced ln 2 apart then has a standard error of about 0.125 / sqrt(sum (ln n - mean)^2) =
    0.125 / 2.19 = 0.057, so +-0.3 is about 5 standard errors. Independent sampling
    converges as n^-1/2; Owen-scrambled
    Sobol as n^-3/2 on smooth integrands (Owen 1997), at least n^-1 here; on the
    discontinuous one as n^-3/4 at best in d = 2 (Owen 2013 ch. 17), so it lies between.
    """
    ns = convergence["ns"]
    assert ns == [16, 32, 64, 128, 256] and convergence["n_replicates"] == 32
    assert [p["kind"] for p in convergence["problems"]] == [
        "gaussian", "oscillatory", "continuous", "discontinuous"
    ]  # fmt: skip
    for p in convergence["problems"]:
        slope = {m: float(s.slope) for m, s in p["studies"].items()}
        name = p["title"]
        for m, s in p["studies"].items():
            np.testing.assert_array_equal(np.asarray(s.ns), ns)
            fit = np.polyfit(np.log(ns), np.log(np.asarray(s.rmse)), 1)[0]
            assert slope[m] == pytest.approx(fit, abs=1e-9)
        assert -0.8 < slope["mc"] < -0.2, (name, slope)
        if p["kind"] == "discontinuous":
            assert -1.2 < slope["sobol"] < -0.45, (name, slope)
        else:
            assert slope["sobol"] < -1.0, (name, slope)
            assert slope["halton"] < -0.7, (name, slope)
            assert slope["sobol"] < slope["mc"] - 0.5, (name, slope)


def test_convergence_figure_mc_rmse_is_sigma_over_sqrt_n(convergence):
    """For independent sampling RMSE = sigma_f / sqrt(n): sigma_f from Gauss-Legendre
    quadrature of f^2 on the d = 2 integrands; the geometric mean over n of the ratio is
    within 25 % (about 4 standard errors for 32 replicates and 5 nested counts)."""
    ns = np.asarray(convergence["ns"], float)
    for p in convergence["problems"]:
        if p["dim"] != 2:
            continue
        breaks = p["w"] if p["kind"] == "discontinuous" else [0.5, 0.5]
        m2 = _gauss_legendre_integral(lambda x, f=p["f"]: f(x) ** 2, 2, breaks)
        sigma = np.sqrt(m2 - p["exact"] ** 2)
        ratio = np.asarray(p["studies"]["mc"].rmse) * np.sqrt(ns) / sigma
        assert abs(np.log(ratio).mean()) < np.log(1.25), (p["title"], ratio)


# --- fig. 7: variance reduction -------------------------------------------------------------


def _rect_moment(power_d: int, power_h: int) -> float:
    """int over the rectangle of H^power_h / d^power_d dA, d^2 = x^2 + y^2 + H^2 (SciPy)."""
    (x0, x1), (y0, y1) = _RECT
    value, err = integrate.dblquad(
        lambda y, x: _H**power_h / (x * x + y * y + _H * _H) ** (power_d / 2),
        x0, x1, y0, y1, epsabs=1e-13, epsrel=1e-12,
    )  # fmt: skip
    return value


def _term_moments(method: str) -> np.ndarray:
    """E[t^k], k = 1..4, of one term of each simple estimator, by SciPy quadrature.

    With cos(theta) = cos(theta_l) = H / d and d omega = H / d^3 dA:
    uniform hemisphere t = 2 pi cos 1_A:  E[t^k] = (2 pi)^(k-1) int cos^k d omega;
    cosine hemisphere t = pi 1_A:        E[t^k] = pi^(k-1) int cos d omega;
    light area t = A H^2 / d^4:           E[t^k] = A^(k-1) int (H^2 / d^4)^k dA;
    spherical triangles t = Omega cos:    E[t^k] = Omega^(k-1) int cos^k d omega.
    """
    (x0, x1), (y0, y1) = _RECT
    area = (x1 - x0) * (y1 - y0)
    omega = _rect_moment(3, 1)
    cos_k = lambda k: _rect_moment(k + 3, k + 1)  # noqa: E731 (int cos^k d omega)
    ks = range(1, 5)
    if method == "uniform hemisphere":
        return np.array([(2 * np.pi) ** (k - 1) * cos_k(k) for k in ks])
    if method == "cosine hemisphere":
        return np.array([np.pi ** (k - 1) * cos_k(1) for k in ks])
    if method == "light area":
        return np.array([area ** (k - 1) * _rect_moment(4 * k, 2 * k) for k in ks])
    if method == "spherical triangles":
        return np.array([omega ** (k - 1) * cos_k(k) for k in ks])
    raise ValueError(method)


@pytest.fixture(scope="module")
def variance():
    return variance_reduction_data(smoke=True)


@pytest.mark.slow
def test_variance_reduction_figure_exact_irradiance(variance):
    """Lambert's polygon formula against SciPy: E = int H^2 / d^4 dA (eq. 1.13)."""
    assert variance["exact"] == pytest.approx(_rect_moment(4, 2), rel=1e-10)
    assert variance["methods"] == RECT_METHODS


@pytest.mark.slow
def test_variance_reduction_figure_variances_equal_quadrature(variance):
    """The per-sample variances of the four simple estimators equal their exact values (SciPy
    quadrature of E[t], E[t^2]) within 5 standard errors of a sample variance,
    sqrt((mu_4 - sigma^4) / n) with the exact central fourth moment."""
    n = variance["n_var"]
    exact_var = {}
    for method in ("uniform hemisphere", "cosine hemisphere", "light area", "spherical triangles"):
        m1, m2, m3, m4 = _term_moments(method)
        assert m1 == pytest.approx(variance["exact"], rel=1e-9), method  # unbiased
        var = m2 - m1**2
        mu4 = m4 - 4 * m3 * m1 + 6 * m2 * m1**2 - 3 * m1**4
        got = variance["per_sample_var"][RECT_METHODS.index(method)]
        assert abs(got - var) < 5 * np.sqrt((mu4 - var**2) / n), (method, got, var)
        exact_var[method] = var
    # Variance ratios > 1 that theory guarantees: uniform solid-angle sampling of the light
    # beats uniform hemisphere sampling (Omega < 2 pi in the same second moment), and the
    # control variate with the fitted coefficient does not lose to plain area sampling.
    got = dict(zip(RECT_METHODS, variance["per_sample_var"], strict=True))
    assert exact_var["uniform hemisphere"] / exact_var["spherical triangles"] > 1
    assert got["uniform hemisphere"] / got["spherical triangles"] > 1
    assert exact_var["light area"] / got["light area + control variate"] > 1
    for mis in ("MIS balance (light + cosine)", "MIS power (light + cosine)"):
        assert got[mis] < min(exact_var["uniform hemisphere"], exact_var["cosine hemisphere"])


@pytest.mark.slow
def test_variance_reduction_figure_rmse(variance):
    """RMSE ~ sqrt(var / n): log-log slopes near -1/2 (4 counts, 32 replicates: slope
    standard error about 0.05, bound 0.25) and RMSE sqrt(n) / sigma near 1 (geometric mean over
    the counts; bound a factor 1.6, about 4 standard errors for the most skewed estimator)."""
    ns = np.asarray(variance["ns"], float)
    for method, rmse, var in zip(
        RECT_METHODS, variance["rmse"], variance["per_sample_var"], strict=True
    ):
        slope = np.polyfit(np.log(ns), np.log(rmse), 1)[0]
        assert abs(slope + 0.5) < 0.25, (method, slope)
        ratio = rmse * np.sqrt(ns) / np.sqrt(var)
        assert abs(np.log(ratio).mean()) < np.log(1.6), (method, ratio)


def test_montecarlo_figure_written(tmp_path):
    assert "fig_5_point_sets" in FIGURES
    paths = make_figures(tmp_path, ["fig_5_point_sets"], smoke=True)
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "helper", "fixture"),
    [
        ("fig_6_convergence", "convergence_figure_data", "convergence"),
        ("fig_7_variance_reduction", "variance_reduction_data", "variance"),
    ],
)
def test_montecarlo_figure_drawn_from_its_data(
    tmp_path, monkeypatch, request, name, helper, fixture
):
    """The figure draws the data its helper returns (the module's fixture, not recomputed)."""
    data = request.getfixturevalue(fixture)
    if name == "fig_6_convergence":  # the fixture leaves Latin hypercube out: reuse "mc"
        problems = [
            {**p, "studies": {"lhs": p["studies"]["mc"], **p["studies"]}} for p in data["problems"]
        ]
        data = {**data, "problems": problems}
    calls = []
    monkeypatch.setattr(_montecarlo, helper, lambda **kw: calls.append(kw) or data)
    paths = make_figures(tmp_path, [name], smoke=True)
    assert calls == [{"smoke": True}]
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]
