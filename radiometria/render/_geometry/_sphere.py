"""Analytic spheres: the ray-sphere test and the sphere's surface parametrisation (thesis ch. 8).

Mitsuba 3 and pbrt-v4 intersect a `sphere` shape exactly; a tessellation lies inside the true
sphere (by 1.1e-3 of the radius for the loader's mesh) and costs thousands of triangles in the
BVH. `Spheres` holds a few true spheres as arrays and answers the two ray queries by testing
every ray against every sphere, vectorised as `(k, n)` arrays (k is small: the renderer keeps
this for scenes with at most `MAX_ANALYTIC_SPHERES` spheres). The test is the quadratic of
Haines, Guenther & Akenine-Moeller (2019), which keeps float32 accurate for rays that start
far from the sphere (the discriminant from the ray's closest approach to the centre, the two
roots from the numerically stable pair `q / a`, `c / q`).

The surface parametrisation is Mitsuba's (and the loader's tessellation's): in the sphere's
object frame, `u = phi / 2 pi` with `phi` from +x towards +y, `v = theta / pi` with `theta`
from +z, so `dp/du = 2 pi (-y, x, 0)` and `dp/dv = pi (z x / rho, z y / rho, -rho)` with
`rho = sqrt(x^2 + y^2)`, in scene units per uv unit.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from ..._checks import device_array
from ..._math import acos_fast, atan2_fast, dot

__all__ = ["MAX_ANALYTIC_SPHERES", "Spheres", "sphere_uv"]

MAX_ANALYTIC_SPHERES = 32
"""The most spheres a scene intersects analytically (each ray is tested against every one);
a scene with more keeps their tessellations in its BVH."""


def _roots(f, d, radius):
    """The two ray parameters `(t0 <= t1)` where `o + t d` meets the sphere (`f = o - c`),
    and whether the ray meets it at all (Haines et al. 2019, eqs. 7.5-7.8).

    `f` and `d` are triples of components `(x, y, z)`, each an array (`(k, n)` and `(1, n)`
    in `Spheres._t`: spheres by rays, the rays along the last axis, which XLA:CPU
    vectorises; written on `(n, k, 3)` arrays the same test took 40 against 5 ns per ray
    for k = 2, and 122 against 41 ns for k = 8, 2048 float32 rays on one core); `radius`
    broadcasts against them."""
    a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    b = f[0] * d[0] + f[1] * d[1] + f[2] * d[2]  # half the linear coefficient
    c = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] - radius * radius
    # Discriminant / (4 a) from the closest approach of the line to the centre.
    ba = b / a
    closest = [fi - ba * di for fi, di in zip(f, d, strict=True)]
    disc = radius * radius - sum(g * g for g in closest)
    root = jnp.sqrt(jnp.maximum(a * disc, 0.0))
    q = -(b + jnp.where(b >= 0, root, -root))
    q_safe = jnp.where(q == 0, 1.0, q)
    t0, t1 = q / a, jnp.where(q == 0, q / a, c / q_safe)
    return jnp.minimum(t0, t1), jnp.maximum(t0, t1), disc >= 0


def sphere_uv(to_local: Float[Array, "n 3 3"], normal: Float[Array, "n 3"]) -> Float[Array, "n 2"]:
    """Mitsuba's uv `(phi / 2 pi, theta / pi)` of the points of spheres whose outward unit
    normals are `normal`, each sphere's object frame given by `to_local` (module docstring).
    [1]"""
    q = jnp.einsum("nij,nj->ni", to_local, normal)
    phi = atan2_fast(q[:, 1], q[:, 0])
    phi = jnp.where(phi < 0, phi + 2.0 * jnp.pi, phi)
    theta = acos_fast(jnp.clip(q[:, 2], -1.0, 1.0))
    return jnp.stack([phi / (2.0 * jnp.pi), theta / jnp.pi], axis=-1)


class Spheres(eqx.Module):
    """A few true spheres as one pytree of arrays, and the ray queries against all of them.

    **Fields:**

    - `center`: `(k, 3)` sphere centres. [scene length unit]
    - `radius`: `(k,)` radii. [scene length unit]
    - `to_local`: `(k, 3, 3)` rotation from the scene's axes to each sphere's object frame,
        whose axes set the uv parametrisation (module docstring).
    - `face`: `(k,)` int32 row of the scene's per-triangle tables (material, media, emitter)
        that stands for each sphere: a closest hit on sphere `j` reports `prim = face[j]`.

    !!! note "Thesis"
        Ch. 8 (ray casting).

    ??? cite "References"
        `Haines2019` (the ray-sphere quadratic in floating point); `Pharr2023` §6.2
        (spheres); `Jakob2022` (Mitsuba 3's `sphere` and its uv).
    """

    center: Float[Array, "k 3"]
    radius: Float[Array, " k"]
    to_local: Float[Array, "k 3 3"]
    face: Int[Array, " k"]

    @classmethod
    def from_arrays(cls, center, radius, rotation, face, *, dtype=jnp.float32) -> "Spheres":
        """Spheres from NumPy arrays, checked (outside `jit`).

        **Arguments:**

        - `center`: `(k, 3)` centres. [scene length unit]
        - `radius`: `(k,)` radii, positive. [scene length unit]
        - `rotation`: `(k, 3, 3)` rotations from each sphere's object frame to the scene's
            axes (orthonormal, determinant +1).
        - `face`: `(k,)` triangle-table row of each sphere (`Spheres.face`).
        - `dtype`: floating dtype of the arrays.
        """
        center = np.asarray(center, np.float64).reshape(-1, 3)
        k = len(center)
        radius = np.asarray(radius, np.float64).reshape(k)
        rotation = np.asarray(rotation, np.float64).reshape(k, 3, 3)
        if not (np.all(np.isfinite(center)) and np.all(np.isfinite(radius))):
            raise ValueError("sphere centres and radii must be finite.")
        if np.any(radius <= 0):
            raise ValueError(f"sphere radii must be positive, got {radius[radius <= 0]}.")
        gram = np.einsum("kji,kjl->kil", rotation, rotation)
        if np.abs(gram - np.eye(3)).max(initial=0.0) > 1e-6 or np.any(np.linalg.det(rotation) < 0):
            raise ValueError("sphere rotations must be orthonormal with determinant +1.")
        if k:  # the nearest rotation (polar decomposition), exact to rounding
            u, _, vt = np.linalg.svd(rotation)
            rotation = u @ vt
        return cls(
            center=device_array(center, dtype),
            radius=device_array(radius, dtype),
            to_local=device_array(np.swapaxes(rotation, 1, 2), dtype),
            face=device_array(np.asarray(face).reshape(k), jnp.int32),
        )

    def _t(self, origins, directions, t_max):
        """`(k, n)` the first ray parameter in `(0, t_max)` on each sphere, inf where none
        (spheres by rays: `_roots`)."""
        f = [origins[:, i][None, :] - self.center[:, i][:, None] for i in range(3)]
        d = [directions[:, i][None, :] for i in range(3)]
        t0, t1, meets = _roots(f, d, self.radius[:, None])
        t = jnp.where(t0 > 0, t0, t1)
        return jnp.where(meets & (t > 0) & (t < t_max[None, :]), t, jnp.inf)

    def intersect_closest(
        self,
        origins: Float[Array, "n 3"],
        directions: Float[Array, "n 3"],
        t_max: Float[Array, " n"],
    ) -> tuple[Float[Array, " n"], Int[Array, " n"]]:
        """The closest sphere on each ray segment `0 < t < t_max`.

        **Arguments:**

        - `origins`, `directions`: `(n, 3)` rays (directions of any length). [scene units]
        - `t_max`: `(n,)` exclusive upper limits. [direction lengths]

        **Returns:**

        `(t (n,), index (n,) int32)`: the ray parameter (inf for none) and the sphere's index
        into the fields (-1 for none).
        """
        t = self._t(origins, directions, t_max)
        index = jnp.argmin(t, axis=0).astype(jnp.int32)
        t_hit = jnp.min(t, axis=0)
        return t_hit, jnp.where(jnp.isfinite(t_hit), index, -1)

    def intersect_any(
        self,
        origins: Float[Array, "n 3"],
        directions: Float[Array, "n 3"],
        t_max: Float[Array, " n"],
    ) -> Bool[Array, " n"]:
        """Whether a sphere lies on each ray segment `0 < t < t_max` (arguments as in
        `intersect_closest`)."""
        return jnp.any(jnp.isfinite(self._t(origins, directions, t_max)), axis=0)

    def normal(self, index: Int[Array, " n"], p: Float[Array, "n 3"]) -> Float[Array, "n 3"]:
        """The outward unit normal of sphere `index` at (or nearest to) the points `p`."""
        w = p - self.center[index]
        return w / jnp.sqrt(jnp.maximum(dot(w, w), jnp.finfo(p.dtype).tiny))[:, None]

    def surface(self, index: Int[Array, " n"], p: Float[Array, "n 3"]):
        """The surface point of sphere `index` nearest to `p` with its normal and uv.

        **Returns:**

        `(point (n, 3), normal (n, 3), uv (n, 2))`: `p` moved onto the sphere along its
        normal (as pbrt-v4 refines its sphere hits), the outward unit normal and Mitsuba's
        `(phi / 2 pi, theta / pi)`. [scene units; 1]
        """
        n = self.normal(index, p)
        point = self.center[index] + self.radius[index][:, None] * n
        return point, n, sphere_uv(self.to_local[index], n).astype(p.dtype)

    def tangents(self, index: Int[Array, " n"], normal: Float[Array, "n 3"]):
        """`(dp/du, dp/dv)` `(n, 3)` of sphere `index` where its outward normal is `normal`
        (module docstring). At the poles dp/dv is 0 (the frame falls back to the normal's).
        [scene units per uv unit]"""
        r = self.radius[index][:, None]
        q = jnp.einsum("nij,nj->ni", self.to_local[index], normal) * r
        x, y, z = q[:, 0], q[:, 1], q[:, 2]
        rho = jnp.sqrt(x * x + y * y)
        inv = jnp.where(rho > 0, 1.0 / jnp.where(rho > 0, rho, 1.0), 0.0)
        du = 2.0 * jnp.pi * jnp.stack([-y, x, jnp.zeros_like(x)], axis=-1)
        dv = jnp.pi * jnp.stack([z * x * inv, z * y * inv, -rho], axis=-1)
        to_world = lambda w: jnp.einsum("nji,nj->ni", self.to_local[index], w)
        return to_world(du), to_world(dv)
