"""GridMedium: trilinear lookup, ratio-tracked transmittance and spectral tracking on a
linear-ramp grid against closed-form optical depths (SciPy quadrature of the ramp)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.interpolate import RegularGridInterpolator

from radiometria.media import GridMedium, IsotropicPhaseFunction, trilinear_lookup

N = 20000
X = 8


def _ramp_grid():
    """Density 2x at the voxel centres along x (constant in y and z), shape (2, 3, X)."""
    centres = (np.arange(X) + 0.5) / X
    return np.broadcast_to(2.0 * centres, (2, 3, X)).copy(), centres


def _tau_ramp():
    """Optical depth of the ramp along local x through the whole box, for s = 1, with the
    box scaled by 2: integral of 2 * interp(x) dx over [0, 1] (clamped ends)."""
    _, centres = _ramp_grid()
    val, _ = quad(lambda x: np.interp(x, centres, 2.0 * centres), 0.0, 1.0, points=[centres[0],
                  centres[-1]])  # fmt: skip
    return 2.0 * val


def test_trilinear_lookup_reproduces_an_affine_field_between_voxel_centres():
    rng = np.random.default_rng(0)
    shape = (4, 5, 6)  # Z, Y, X
    zc, yc, xc = [(np.arange(s) + 0.5) / s for s in shape]
    coef = np.array([0.3, -0.7, 1.1])
    grid = 2.0 + coef[0] * xc[None, None, :] + coef[1] * yc[None, :, None]
    grid = grid + coef[2] * zc[:, None, None]
    lo = np.array([xc[0], yc[0], zc[0]])
    hi = np.array([xc[-1], yc[-1], zc[-1]])
    p = lo + (hi - lo) * rng.random((200, 3))
    got = np.asarray(trilinear_lookup(jnp.asarray(grid), jnp.asarray(p)))
    np.testing.assert_allclose(got, 2.0 + p @ coef, rtol=1e-12)
    # Outside the unit box the medium is empty; at the faces values are clamped.
    out = trilinear_lookup(jnp.asarray(grid), jnp.asarray([[1.1, 0.5, 0.5], [0.0, 0.0, 0.0]]))
    np.testing.assert_allclose(np.asarray(out), [0.0, grid[0, 0, 0]], rtol=1e-12)


@pytest.mark.parametrize("shape", [(4, 5, 6), (33, 34, 35)], ids=["corner gathers", "one gather"])
def test_trilinear_lookup_equals_scipy_on_a_random_grid(shape):
    """Both ways of reading the grid (corner by corner; one gather above 32^3 voxels) equal
    SciPy's `RegularGridInterpolator` between the voxel centres, clamped towards the faces."""
    rng = np.random.default_rng(1)
    grid = rng.random(shape)
    centres = [(np.arange(n) + 0.5) / n for n in shape]  # z, y, x
    p = rng.random((500, 3))  # x, y, z in the unit box, also between the faces and centres
    clamped = np.stack([np.clip(p[:, 2 - i], c[0], c[-1]) for i, c in enumerate(centres)], -1)
    want = RegularGridInterpolator(centres, grid)(clamped)
    got = np.asarray(trilinear_lookup(jnp.asarray(grid), jnp.asarray(p)))
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-14)


def _medium(s, albedo=0.8):
    grid, _ = _ramp_grid()
    return GridMedium(
        density=jnp.asarray(grid),
        sigma_t=jnp.asarray(s),
        albedo=albedo,
        phase=IsotropicPhaseFunction(),
        to_world=np.diag([2.0, 2.0, 2.0, 1.0]),
    )


def _rays(n):
    o = np.tile([-1.0, 1.0, 1.0], (n, 1))  # starts outside the box: clipping is exercised
    w = np.tile([1.0, 0.0, 0.0], (n, 1))
    lam = np.tile([500.0, 600.0], (n, 1))
    u = jax.random.uniform(jax.random.key(3), (n, 2), jnp.float64)
    return jnp.asarray(o), jnp.asarray(w), jnp.full((n,), 4.0), jnp.asarray(lam), u


def test_ratio_tracking_through_a_ramp_grid_matches_the_closed_form_optical_depth():
    s = np.array([0.5, 1.0])
    tau = _tau_ramp() * s
    assert np.isclose(_tau_ramp(), 2.0, rtol=1e-9)  # the quadrature itself: 2 * 1.0
    o, w, t_max, lam, u = _rays(N)
    tr = np.asarray(_medium(s).transmittance(o, w, t_max, lam, u))
    mean = tr.mean(axis=0)
    se = tr.std(axis=0) / np.sqrt(N)
    assert np.all(np.abs(mean - np.exp(-tau)) < 4 * se + 1e-4), (mean, np.exp(-tau), se)
    # A segment ending halfway through the box: local x in [0, 0.5].
    half, _ = quad(lambda x: np.interp(x, (np.arange(X) + 0.5) / X,
                   2.0 * (np.arange(X) + 0.5) / X), 0.0, 0.5)  # fmt: skip
    tr_h = np.asarray(_medium(s).transmittance(o, w, jnp.full((N,), 2.0), lam, u))
    se_h = tr_h.std(axis=0) / np.sqrt(N)
    assert np.all(np.abs(tr_h.mean(axis=0) - np.exp(-2.0 * half * s)) < 4 * se_h + 1e-4)


def test_ratio_tracking_with_russian_roulette_stays_unbiased_in_a_thick_ramp():
    """Optical depths 4 and 7 (T = 0.018 and 0.0009): estimates fall below 0.05 and play
    Russian roulette (some end at exactly 0, which plain ratio tracking never gives here);
    the mean is still the closed-form transmittance at both wavelengths."""
    s = np.array([2.0, 3.5])
    tau = _tau_ramp() * s
    o, w, t_max, lam, u = _rays(N)
    tr = np.asarray(_medium(s).transmittance(o, w, t_max, lam, u))
    assert 0.05 < np.mean(np.all(tr == 0.0, axis=-1)) < 0.95  # roulette ended some walks
    mean, se = tr.mean(axis=0), tr.std(axis=0) / np.sqrt(N)
    assert np.all(np.abs(mean - np.exp(-tau)) < 4 * se + 1e-6), (mean, np.exp(-tau), se)


def test_spectral_tracking_is_unbiased_at_every_wavelength():
    """E[w_j 1_no event] = T_j and E[w_j 1_event] = albedo (1 - T_j) for a constant albedo."""
    s = np.array([0.5, 1.5])
    albedo = np.array([0.9, 0.6])
    tau = _tau_ramp() * s
    o, w, t_max, lam, u = _rays(N)
    mi = _medium(s, albedo).sample_free_flight(o, w, t_max, lam, u)
    wgt = np.asarray(mi.weight)
    ev = np.asarray(mi.scattered)[:, None]
    for est, expected in ((wgt * ~ev, np.exp(-tau)), (wgt * ev, albedo * (1 - np.exp(-tau)))):
        mean, se = est.mean(axis=0), est.std(axis=0) / np.sqrt(N)
        assert np.all(np.abs(mean - expected) < 4 * se + 1e-4), (mean, expected, se)
    # Events lie inside the box (world x in [0, 2]) and the distance is the path's.
    t = np.asarray(mi.t)
    assert np.all((t[ev[:, 0]] >= 1.0) & (t[ev[:, 0]] <= 3.0))
    assert np.all(t[~ev[:, 0]] == 4.0)


def test_grid_medium_rejects_bad_grids():
    iso = IsotropicPhaseFunction()
    with pytest.raises(ValueError, match="density"):
        GridMedium(-jnp.ones((2, 2, 2)), 1.0, 0.5, iso)
    with pytest.raises(ValueError, match="density"):
        GridMedium(jnp.full((2, 2, 2), jnp.nan), 1.0, 0.5, iso)
    with pytest.raises(ValueError, match="albedo"):
        GridMedium(jnp.ones((2, 2, 2)), 1.0, 1.5, iso)
    with pytest.raises(ValueError, match="to_world"):
        GridMedium(jnp.ones((2, 2, 2)), 1.0, 0.5, iso, to_world=np.zeros((4, 4)))
