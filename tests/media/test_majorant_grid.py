"""The coarse majorant grid of `GridMedium`: conservative per-cell bounds, and the DDA-walked
spectral and residual ratio tracking stay unbiased on a high-contrast field (a dense blob in an
empty box) against optical depths integrated with SciPy's own trilinear interpolator."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator

from radiometria.media import (
    GridMedium,
    HomogeneousMedium,
    IsotropicPhaseFunction,
    coarse_majorant_grid,
    trilinear_lookup,
)

SHAPE = (12, 14, 16)  # Z, Y, X
BOX = 2.0  # the grid's box is [0, 2]^3 in the scene


def _blob():
    """A dense Gaussian blob (peak 8) off-centre in an otherwise empty box."""
    z, y, x = np.meshgrid(*[(np.arange(n) + 0.5) / n for n in SHAPE], indexing="ij")
    r2 = (x - 0.55) ** 2 + (y - 0.45) ** 2 + (z - 0.5) ** 2
    d = 8.0 * np.exp(-r2 / (2 * 0.12**2))
    return np.where(d > 0.05, d, 0.0)


def _scipy_density(grid):
    """Clamped trilinear interpolation between voxel centres, by SciPy (local coordinates)."""
    centres = [(np.arange(n) + 0.5) / n for n in grid.shape]
    f = RegularGridInterpolator(centres, grid, method="linear")
    lo = np.array([c[0] for c in centres])
    hi = np.array([c[-1] for c in centres])

    def density(p_xyz):
        p = np.clip(np.asarray(p_xyz)[..., ::-1], lo, hi)  # (z, y, x), clamped to the centres
        return f(p)

    return density


def _tau(grid, o, w, t_max, s=1.0):
    """Optical depth of the scene segment o + t w, t in (0, t_max): along a line the trilinear
    density is a cubic between the planes of voxel centres and box faces, so Gauss-Legendre
    with 3 nodes per piece is exact."""
    dens = _scipy_density(grid)
    planes = [np.concatenate([[0.0, 1.0], (np.arange(n) + 0.5) / n]) for n in grid.shape[::-1]]
    cuts = [0.0, t_max]
    for a in range(3):
        if w[a] != 0:
            cuts += list((BOX * planes[a] - o[a]) / w[a])
    cuts = np.unique(np.clip(cuts, 0.0, t_max))
    x, wt = np.polynomial.legendre.leggauss(3)
    a, b = cuts[:-1, None], cuts[1:, None]
    t = (0.5 * (b - a) * x[None] + 0.5 * (a + b)).ravel()
    p = (o[None] + t[:, None] * w[None]) / BOX
    inside = np.all((p >= 0) & (p <= 1), axis=1)
    f = np.where(inside, dens(np.clip(p, 0, 1)), 0.0).reshape(a.shape[0], 3)
    return s * float(np.sum(0.5 * (b - a) * f * wt[None]))


def _medium(grid, s, albedo=0.8, **kw):
    return GridMedium(
        density=jnp.asarray(grid),
        sigma_t=jnp.asarray(s),
        albedo=albedo,
        phase=IsotropicPhaseFunction(),
        to_world=np.diag([BOX, BOX, BOX, 1.0]),
        **kw,
    )


@pytest.mark.parametrize("resolution", [None, (3, 5, 7), (12, 14, 16), (1, 2, 1)])
def test_the_majorant_grid_bounds_the_density_everywhere(resolution):
    rng = np.random.default_rng(1)
    grid = rng.gamma(0.5, 2.0, SHAPE) * (rng.random(SHAPE) < 0.3)
    hi, lo = coarse_majorant_grid(grid, resolution)
    res = np.asarray(hi.shape)
    # random points, and points on the cells' faces (where two cells meet)
    p = rng.random((20000, 3))
    faces = rng.integers(0, res[::-1] + 1, (2000, 3)) / res[::-1]
    p = np.concatenate([p, np.where(rng.random((2000, 3)) < 0.5, faces, rng.random((2000, 3)))])
    d = np.asarray(trilinear_lookup(jnp.asarray(grid), jnp.asarray(p)))
    assert np.allclose(d, _scipy_density(grid)(p), rtol=1e-12, atol=1e-12)
    # every cell containing a point (both cells on a face) bounds it
    for side in (0.0, 1e-9):
        cell = np.clip(np.floor(p * res[::-1] - side).astype(int), 0, res[::-1] - 1)
        assert np.all(hi[cell[:, 2], cell[:, 1], cell[:, 0]] >= d)
        assert np.all(lo[cell[:, 2], cell[:, 1], cell[:, 0]] <= d)
    assert np.isclose(hi.max(), grid.max()) and np.isclose(lo.min(), grid.min())


def _rays(n_each):
    """Four segments through or near the blob, along oblique directions (every axis stepped
    both ways), starting inside or outside the box; each repeated n_each times."""
    o = np.array([[-0.3, 0.1, 0.2], [2.3, 1.7, 1.9], [0.2, 0.9, 1.0], [1.1, -0.5, 0.95]])
    tgt = np.array([[2.1, 1.8, 1.9], [0.0, 0.2, 0.1], [1.9, 0.8, 1.05], [1.1, 2.5, 1.05]])
    w = tgt - o
    t_max = np.linalg.norm(w, axis=1) * np.array([1.0, 1.0, 0.6, 1.0])
    w = w / np.linalg.norm(w, axis=1, keepdims=True)
    rep = lambda a: jnp.asarray(np.repeat(a, n_each, axis=0))  # noqa: E731
    return o, w, t_max, rep(o), rep(w), rep(t_max)


N_EACH = 6000


@pytest.mark.parametrize("resolution", [None, 1])
def test_tracking_through_the_majorant_grid_is_unbiased_on_a_dense_blob(resolution):
    grid = _blob()
    s = np.array([0.3, 0.8])
    albedo = np.array([0.9, 0.6])
    o, w, t_max, oo, ww, tt = _rays(N_EACH)
    tau = np.array([[_tau(grid, o[i], w[i], t_max[i], sj) for sj in s] for i in range(4)])
    assert np.all(tau.max(axis=1) > 1.0) and tau.max() > 3.0  # high contrast on the paths
    n = oo.shape[0]
    lam = jnp.tile(jnp.asarray([500.0, 600.0]), (n, 1))
    u = jax.random.uniform(jax.random.key(7), (n, 2), jnp.float64)
    med = _medium(grid, s, albedo, majorant_resolution=resolution)
    expect_hi = (1, 1, 1) if resolution == 1 else (6, 7, 8)
    assert med.majorant_grid.shape == expect_hi
    tr = np.asarray(med.transmittance(oo, ww, tt, lam, u)).reshape(4, N_EACH, 2)
    mi = med.sample_free_flight(oo, ww, tt, lam, u)
    wgt = np.asarray(mi.weight).reshape(4, N_EACH, 2)
    ev = np.asarray(mi.scattered).reshape(4, N_EACH, 1)
    T = np.exp(-tau)
    for est, expected in ((tr, T), (wgt * ~ev, T), (wgt * ev, albedo * (1 - T))):
        mean, se = est.mean(axis=1), est.std(axis=1) / np.sqrt(N_EACH)
        assert np.all(np.abs(mean - expected) < 4.5 * se + 2e-4), (mean, expected, se)
    # events lie on their segments, inside the blob's support
    t = np.asarray(mi.t).reshape(4, N_EACH)
    assert np.all(t[ev[..., 0]] >= 0) and np.all(t <= t_max[:, None] + 1e-9)


def test_a_denser_blob_fails_the_unbiasedness_check():
    """Negative control: the same check against the optical depth of a 10 % thinner blob."""
    grid = _blob()
    o, w, t_max, oo, ww, tt = _rays(N_EACH)
    tau = np.array([_tau(0.9 * grid, o[i], w[i], t_max[i]) for i in range(4)])
    n = oo.shape[0]
    lam = jnp.full((n, 1), 550.0)
    u = jax.random.uniform(jax.random.key(7), (n, 2), jnp.float64)
    tr = np.asarray(_medium(grid, 1.0).transmittance(oo, ww, tt, lam, u)).reshape(4, N_EACH)
    mean, se = tr.mean(axis=1), tr.std(axis=1) / np.sqrt(N_EACH)
    assert np.any(np.abs(mean - np.exp(-tau)) > 4.5 * se + 2e-4)


def test_a_constant_grid_is_the_homogeneous_medium():
    """Per-cell controls make residual ratio tracking exact for a constant grid, whatever the
    cells; free flights have the homogeneous medium's mean weights."""
    grid = np.full(SHAPE, 1.7)
    s = np.array([0.4, 0.9])
    o, w, t_max, oo, ww, tt = _rays(250)
    n = oo.shape[0]
    lam = jnp.tile(jnp.asarray([500.0, 600.0]), (n, 1))
    u = jax.random.uniform(jax.random.key(2), (n, 2), jnp.float64)
    med = _medium(grid, s, 0.7, majorant_resolution=(4, 5, 6))
    tr = np.asarray(med.transmittance(oo, ww, tt, lam, u))
    # the part of each segment inside the box, in closed form
    o_b, w_b = np.asarray(oo) / BOX, np.asarray(ww) / BOX
    with np.errstate(divide="ignore"):
        ta, tb = (0 - o_b) / w_b, (1 - o_b) / w_b
    t0 = np.maximum(np.max(np.minimum(ta, tb), axis=1), 0)
    t1 = np.minimum(np.min(np.maximum(ta, tb), axis=1), np.asarray(tt))
    length = np.maximum(t1 - t0, 0)
    homo = HomogeneousMedium(1.7 * s, 0.7, IsotropicPhaseFunction())
    assert np.allclose(tr, np.exp(-1.7 * s[None] * length[:, None]), rtol=1e-10)
    o_in = jnp.asarray(np.asarray(oo) + t0[:, None] * np.asarray(ww))
    tr_h = np.asarray(homo.transmittance(o_in, ww, jnp.asarray(length), lam, u))
    assert np.allclose(tr, tr_h, rtol=1e-10)


def test_compacting_the_walks_into_fewer_lanes_changes_no_estimate(monkeypatch):
    """The tracking loops gather the walks still going into an eighth as many lanes as
    others end (`_grid._staged_loop`); every path's estimate equals, to the bit, what one
    loop over all the lanes gives, for free flights and transmittances."""
    from radiometria.media import _grid

    grid = _blob()
    s = np.array([0.3, 0.8])
    _, _, _, oo, ww, tt = _rays(300)
    n = oo.shape[0]
    lam = jnp.tile(jnp.asarray([500.0, 600.0]), (n, 1))
    u = jax.random.uniform(jax.random.key(3), (n, 2), jnp.float64)
    med = _medium(grid, s, np.array([0.9, 0.6]))

    def estimates():
        mi = med.sample_free_flight(oo, ww, tt, lam, u)
        tr = med.transmittance(oo, ww, tt, lam, u)
        return [np.asarray(x) for x in (mi.t, mi.scattered, mi.weight, tr)]

    staged = estimates()
    monkeypatch.setattr(_grid, "_STAGE_MIN", 10**9)  # one loop over all lanes
    single = estimates()
    for a, b in zip(staged, single, strict=True):
        np.testing.assert_array_equal(a, b)
    assert staged[1].any() and not staged[1].all()
