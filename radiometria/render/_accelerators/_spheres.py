"""Triangles and analytic spheres as one accelerator (thesis ch. 8).

A scene's `sphere` shapes are loaded as tessellations, whose triangles carry the shape's rows
of the per-triangle tables (material, media, emitter, uv). `SphereAccelerator` leaves those
triangles out of the triangle accelerator and intersects the true spheres instead
(`Spheres`): a hit on a sphere reports the row of one of its triangles as `prim`, so
everything the integrators look up by face is unchanged, and `RenderScene` replaces the hit's
position, normal and uv by the sphere's (`RenderScene.face_sphere`).
"""

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Int

from ..._checks import device_array
from .._geometry._sphere import Spheres
from .._geometry._triangle import Hit
from ._base import AbstractAccelerator
from ._build import build_accelerator

__all__ = ["SphereAccelerator"]


class SphereAccelerator(AbstractAccelerator):
    """A triangle accelerator over the triangles that are no sphere, plus analytic spheres.

    **Fields:**

    - `triangles`: the accelerator of the other triangles (`BVHAccelerator` or
        `BruteForceAccelerator`), or `None` when the scene has only spheres.
    - `triangle_face`: `(g,)` int32 scene face index of each of `triangles`' faces.
    - `spheres`: the `Spheres`; a hit on sphere `j` reports `prim = spheres.face[j]` and
        barycentrics 0.

    Hits are those of the two queries combined: the nearer one wins (the same `t` on a
    triangle and a sphere goes to the triangle).

    !!! note "Thesis"
        Ch. 8 (ray casting).

    ??? cite "References"
        `Pharr2023` §7.1 (aggregates of several kinds of primitive); `Haines2019`.
    """

    triangles: AbstractAccelerator | None
    triangle_face: Int[Array, " g"] | None
    spheres: Spheres

    @classmethod
    def from_triangles(
        cls,
        vertices,
        faces,
        *,
        dtype=jnp.float32,
        spheres: Spheres | None = None,
        sphere_faces=None,
        kind: str = "auto",
    ) -> "SphereAccelerator":
        """Build the accelerator (NumPy work, outside `jit`).

        **Arguments:**

        - `vertices`, `faces`: the scene's triangles, as in `build_accelerator`.
        - `dtype`: floating dtype of the stored triangles.
        - `spheres`: the analytic `Spheres` (required).
        - `sphere_faces`: `(f,)` booleans, the triangles that tessellate those spheres (left
            out of the triangle accelerator; required: without it the tessellations would
            stand beside the spheres).
        - `kind`: the triangle accelerator's kind (`build_accelerator`).
        """
        if spheres is None or sphere_faces is None:
            raise TypeError("SphereAccelerator needs `spheres` and `sphere_faces`.")
        faces = np.asarray(faces)
        drop = np.asarray(sphere_faces, bool)
        if drop.shape != (len(faces),):
            raise ValueError(f"`sphere_faces` must have shape ({len(faces)},), got {drop.shape}.")
        keep = np.flatnonzero(~drop).astype(np.int32)
        if not len(keep):
            return cls(triangles=None, triangle_face=None, spheres=spheres)
        inner = build_accelerator(vertices, faces[keep], kind=kind, dtype=dtype)
        return cls(triangles=inner, triangle_face=device_array(keep), spheres=spheres)

    def _rays(self, origins, directions, t_max):
        dtype = self.spheres.center.dtype
        o = device_array(origins, dtype)
        d = device_array(directions, dtype)
        return o, d, jnp.broadcast_to(device_array(t_max, dtype), o.shape[:1])

    def intersect_closest(self, origins, directions, t_max):
        o, d, t_max = self._rays(origins, directions, t_max)
        t_s, index = self.spheres.intersect_closest(o, d, t_max)
        if self.triangles is None:
            zero = jnp.zeros_like(t_s)
            prim = jnp.where(index >= 0, self.spheres.face[jnp.maximum(index, 0)], -1)
            return Hit(t=t_s, prim=prim, b1=zero, b2=zero)
        hit = self.triangles.intersect_closest(o, d, t_max)
        prim = jnp.where(hit.prim >= 0, self.triangle_face[jnp.maximum(hit.prim, 0)], -1)
        on_sphere = t_s < hit.t
        face = self.spheres.face[jnp.maximum(index, 0)]
        return Hit(
            t=jnp.where(on_sphere, t_s.astype(hit.t.dtype), hit.t),
            prim=jnp.where(on_sphere, face, prim),
            b1=jnp.where(on_sphere, 0.0, hit.b1).astype(hit.b1.dtype),
            b2=jnp.where(on_sphere, 0.0, hit.b2).astype(hit.b2.dtype),
        )

    def intersect_any(self, origins, directions, t_max):
        o, d, t_max = self._rays(origins, directions, t_max)
        blocked = self.spheres.intersect_any(o, d, t_max)
        if self.triangles is None:
            return blocked
        return blocked | self.triangles.intersect_any(o, d, t_max)
