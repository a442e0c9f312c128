"""TEMPORARY stand-ins (helper P) for modules of other helpers that have not landed yet.

Each name mirrors the agreed API in .notes/API.md; this file is deleted once the real
modules exist. Nothing here is public.
"""

import jax.numpy as jnp
import numpy as np


# --- montecarlo -----------------------------------------------------------------------------
def sample_visible_wavelengths(u):
    return 538.0 - 138.888889 * jnp.arctanh(0.85691062 - 1.82750197 * u)


def visible_wavelengths_pdf(wavelength_nm):
    inside = (wavelength_nm >= 360.0) & (wavelength_nm <= 830.0)
    return jnp.where(inside, 0.0039398042 / jnp.cosh(0.0072 * (wavelength_nm - 538.0)) ** 2, 0.0)


def power_heuristic(nf, f_pdf, ng, g_pdf):
    f = nf * f_pdf
    g = ng * g_pdf
    f2 = f * f
    den = f2 + g * g
    return jnp.where(den > 0, f2 / jnp.where(den > 0, den, 1.0), 0.0)


def sample_uniform_triangle(u):
    u0, u1 = u[..., 0], u[..., 1]
    b0 = jnp.where(u0 < u1, u0 / 2, u0 - u1 / 2)
    b1 = jnp.where(u0 < u1, u1 - u0 / 2, u1 / 2)
    return jnp.stack([b0, b1, 1 - b0 - b1], axis=-1)


def sample_uniform_disk_concentric(u):
    uo = 2.0 * u - 1.0
    ux, uy = uo[..., 0], uo[..., 1]
    zero = (ux == 0) & (uy == 0)
    big = jnp.abs(ux) > jnp.abs(uy)
    sux = jnp.where(ux == 0, 1.0, ux)
    suy = jnp.where(uy == 0, 1.0, uy)
    r = jnp.where(big, ux, uy)
    theta = jnp.where(big, (jnp.pi / 4) * (uy / sux), jnp.pi / 2 - (jnp.pi / 4) * (ux / suy))
    r = jnp.where(zero, 0.0, r)
    return jnp.stack([r * jnp.cos(theta), r * jnp.sin(theta)], axis=-1)


def sample_cosine_hemisphere(u):
    d = sample_uniform_disk_concentric(u)
    z = jnp.sqrt(jnp.maximum(0.0, 1.0 - d[..., 0] ** 2 - d[..., 1] ** 2))
    return jnp.stack([d[..., 0], d[..., 1], z], axis=-1)


# --- scattering -----------------------------------------------------------------------------
def coordinate_system(n):
    sign = jnp.where(n[..., 2] >= 0, 1.0, -1.0).astype(n.dtype)
    a = -1.0 / (sign + n[..., 2])
    b = n[..., 0] * n[..., 1] * a
    s = jnp.stack([1 + sign * n[..., 0] ** 2 * a, sign * b, -sign * n[..., 0]], axis=-1)
    t = jnp.stack([b, sign + n[..., 1] ** 2 * a, -n[..., 1]], axis=-1)
    return s, t


# --- render geometry ------------------------------------------------------------------------
def intersect_soa(p0, e1, e2, origins, directions, tmax):
    """Moeller-Trumbore against all triangles, (rays, 1) x (1, tris) broadcasting."""

    def c(a, i):
        return a[:, i : i + 1]

    def r(a, i):
        return a[None, :, i]

    ox, oy, oz = c(origins, 0), c(origins, 1), c(origins, 2)
    dx, dy, dz = c(directions, 0), c(directions, 1), c(directions, 2)
    e1x, e1y, e1z = r(e1, 0), r(e1, 1), r(e1, 2)
    e2x, e2y, e2z = r(e2, 0), r(e2, 1), r(e2, 2)
    px, py, pz = dy * e2z - dz * e2y, dz * e2x - dx * e2z, dx * e2y - dy * e2x
    det = e1x * px + e1y * py + e1z * pz
    inv = 1.0 / jnp.where(det == 0, 1.0, det)
    tx, ty, tz = ox - r(p0, 0), oy - r(p0, 1), oz - r(p0, 2)
    b1 = (tx * px + ty * py + tz * pz) * inv
    qx, qy, qz = ty * e1z - tz * e1y, tz * e1x - tx * e1z, tx * e1y - ty * e1x
    b2 = (dx * qx + dy * qy + dz * qz) * inv
    t = (e2x * qx + e2y * qy + e2z * qz) * inv
    ok = (det != 0) & (b1 >= 0) & (b2 >= 0) & (b1 + b2 <= 1) & (t > 0) & (t < tmax[:, None])
    t = jnp.where(ok, t, jnp.inf)
    prim = jnp.argmin(t, axis=1).astype(jnp.int32)
    tmin = jnp.min(t, axis=1)
    hit = jnp.isfinite(tmin)
    b1h = jnp.take_along_axis(b1, prim[:, None], axis=1)[:, 0]
    b2h = jnp.take_along_axis(b2, prim[:, None], axis=1)[:, 0]
    return tmin, jnp.where(hit, prim, -1), b1h, b2h


def intersect_soa_any(p0, e1, e2, origins, directions, tmax):
    t, prim, _, _ = intersect_soa(p0, e1, e2, origins, directions, tmax)
    return prim >= 0


# --- colorimetry ----------------------------------------------------------------------------
def cmfs_on_grid(grid_nm):
    import colour

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    return np.asarray(cmfs.copy().align(colour.SpectralShape(360, 830, 1))[grid_nm])


def d65_on_grid(grid_nm):
    import colour

    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(colour.SpectralShape(360, 830, 1))
    return np.asarray(d65[grid_nm])


# --- scattering BxDF ------------------------------------------------------------------------
import equinox as eqx  # noqa: E402


class BSDFSample(eqx.Module):
    f: object
    wi: object
    pdf: object
    is_delta: object


class DiffuseBxDF(eqx.Module):
    reflectance: object

    def f(self, wo, wi):
        same = (wo[..., 2] * wi[..., 2]) > 0
        return jnp.where(same[..., None], self.reflectance / jnp.pi, 0.0)

    def pdf(self, wo, wi):
        same = (wo[..., 2] * wi[..., 2]) > 0
        return jnp.where(same, jnp.abs(wi[..., 2]) / jnp.pi, 0.0)

    def sample_f(self, wo, u_lobe, u2):
        wi = sample_cosine_hemisphere(u2).astype(wo.dtype)
        wi = wi.at[..., 2].multiply(jnp.where(wo[..., 2] < 0, -1.0, 1.0).astype(wo.dtype))
        pdf = jnp.abs(wi[..., 2]) / jnp.pi
        return BSDFSample(self.f(wo, wi), wi, pdf, jnp.zeros(pdf.shape, bool))
