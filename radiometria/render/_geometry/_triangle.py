"""The watertight ray-triangle test and the `Hit` it produces (thesis ch. 8).

The triangle test is Woop, Benthin & Wald (2013): each ray is sheared into a space where it is
the +z axis, the 2D edge functions `U, V, W` are evaluated on the transformed corners, and a
hit needs all three of one sign. Corners shared by adjacent triangles are transformed by
identical arithmetic, and each edge function is evaluated with its two corners in a
canonical order (`_edge`), so a shared edge gives exactly opposite values in the two
triangles even where XLA:CPU contracts `a * b - c * d` into a fused multiply-add. A ray
through an edge or a vertex thus hits at least one of the triangles: no ray leaks through a
closed mesh. Edge values that are exactly 0 count as inside (a tie hits both triangles).
The paper's double-precision fallback for `U = V = W = 0` products is omitted: it refines
which of two tied triangles is reported and is not needed for watertightness.

Layout (the measured fact of `design.md`): every test is written structure-of-arrays, one
array per coordinate, so XLA fuses it into one loop. For the brute force (`_traversal.py`,
`_native.py`), `_sorted_corners` puts each triangle's corners in a global (lexicographic)
order, so shared edges see identical operands without a per-ray swap.
"""

from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

__all__ = ["Hit"]


class Hit(eqx.Module):
    """The closest intersection of each ray (a closest-hit query result).

    **Fields:**

    - `t`: ray parameter of the hit, `(n,)`; the hit point is `origin + t * direction`
        (in units of the direction's length). `inf` for a miss. [scene length unit per
        direction length]
    - `prim`: index of the hit triangle in the original face array, `(n,)` int32; -1 for a
        miss.
    - `b1`, `b2`: barycentric coordinates of the hit, `(n,)`, so that the point is
        `(1 - b1 - b2) v0 + b1 v1 + b2 v2`; 0 for a miss. [dimensionless]

    !!! note "Thesis"
        Ch. 8 (ray casting); the triangle parametrisation of `Pharr2023` §6.5.3.
    """

    t: Float[Array, " n"]
    prim: Int[Array, " n"]
    b1: Float[Array, " n"]
    b2: Float[Array, " n"]

    @property
    def valid(self) -> Bool[Array, " n"]:
        """True where the ray hit a triangle."""
        return self.prim >= 0


# ---------------------------------------------------------------------------------------------
# Ray setup and the watertight triangle test (Woop et al. 2013, JCGT 2(1), Listing 1)


class _Ray(NamedTuple):
    # Axis selection masks: the sheared x' axis is world axis 0 where kx0, 1 where kx1, else 2.
    kx0: Array
    kx1: Array
    ky0: Array
    ky1: Array
    kz0: Array
    kz1: Array
    ox: Array  # origin, permuted to (kx, ky, kz)
    oy: Array
    oz: Array
    sx: Array  # shear constants
    sy: Array
    sz: Array


def _pick(m0, m1, a, b, c):
    return jnp.where(m0, a, jnp.where(m1, b, c))


def _setup_rays(origins, directions) -> _Ray:
    """Per-ray constants of the watertight test; inputs `(..., 3)`, outputs `(...,)`."""
    dx, dy, dz = directions[..., 0], directions[..., 1], directions[..., 2]
    ax, ay, az = jnp.abs(dx), jnp.abs(dy), jnp.abs(dz)
    # kz: the dimension where the direction is largest (first one on ties)
    kz0 = (ax >= ay) & (ax >= az)
    kz1 = ~kz0 & (ay >= az)
    kz2 = ~kz0 & ~kz1
    # kx = kz + 1 mod 3, ky = kx + 1 mod 3
    kx0, kx1 = kz2, kz0
    ky0, ky1 = kz1, kz2
    d_kz = _pick(kz0, kz1, dx, dy, dz)
    # The paper swaps kx and ky when d_kz < 0 to keep the winding for back-face culling. Both
    # windings are accepted here, and the swap only negates U, V, W, det and T exactly (t and
    # the barycentrics are unchanged), so it is left out.
    ox, oy, oz = origins[..., 0], origins[..., 1], origins[..., 2]
    d_kx = _pick(kx0, kx1, dx, dy, dz)
    d_ky = _pick(ky0, ky1, dx, dy, dz)
    return _Ray(
        kx0=kx0,
        kx1=kx1,
        ky0=ky0,
        ky1=ky1,
        kz0=kz0,
        kz1=kz1,
        ox=_pick(kx0, kx1, ox, oy, oz),
        oy=_pick(ky0, ky1, ox, oy, oz),
        oz=_pick(kz0, kz1, ox, oy, oz),
        sx=d_kx / d_kz,
        sy=d_ky / d_kz,
        sz=1.0 / d_kz,
    )


def _edge(p_x, p_y, q_x, q_y):
    """2D edge function `p_x q_y - p_y q_x`, exactly antisymmetric: `_edge(q, p) == -_edge(p, q)`.

    The two corners are put in a canonical (lexicographic) order before the products, so the
    two triangles that share an edge evaluate it with the same operands in the same places.
    Without this, a fused multiply-add (which XLA:CPU emits for `a * b - c * d`) rounds the two
    evaluations differently, and rays exactly through a shared edge leak between them
    (measured: 17 of 1122 rays through the edges of an icosphere in float32).
    """
    swap = (p_x > q_x) | ((p_x == q_x) & (p_y > q_y))
    a_x = jnp.where(swap, q_x, p_x)
    a_y = jnp.where(swap, q_y, p_y)
    b_x = jnp.where(swap, p_x, q_x)
    b_y = jnp.where(swap, p_y, q_y)
    e = a_x * b_y - a_y * b_x
    return jnp.where(swap, -e, e)


def _triangle_test(ray: _Ray, v0, v1, v2, t_min, t_max):
    """Watertight test of rays against triangles given as `(x, y, z)` coordinate tuples.

    Every argument broadcasts: `(n,)` with `(n,)` in the BVH loop, `(n, 1)` with `(f,)` in the
    brute force. Returns `(hit, t, b1, b2)`; a hit needs `t_min < t < t_max`.
    """

    def corner(v):
        # translate to the ray origin, permute to (kx, ky, kz) and shear onto the +z axis
        px = _pick(ray.kx0, ray.kx1, v[0], v[1], v[2]) - ray.ox
        py = _pick(ray.ky0, ray.ky1, v[0], v[1], v[2]) - ray.oy
        pz = _pick(ray.kz0, ray.kz1, v[0], v[1], v[2]) - ray.oz
        return px - ray.sx * pz, py - ray.sy * pz, ray.sz * pz

    a_x, a_y, a_z = corner(v0)
    b_x, b_y, b_z = corner(v1)
    c_x, c_y, c_z = corner(v2)
    # scaled barycentrics: 2D edge functions of the sheared corners
    u = _edge(c_x, c_y, b_x, b_y)
    v = _edge(a_x, a_y, c_x, c_y)
    w = _edge(b_x, b_y, a_x, a_y)
    inside = ((u >= 0) & (v >= 0) & (w >= 0)) | ((u <= 0) & (v <= 0) & (w <= 0))
    det = u + v + w
    ok = inside & (det != 0)
    det_safe = jnp.where(ok, det, 1.0)
    inv_det = 1.0 / det_safe
    t_scaled = u * a_z + v * b_z + w * c_z
    t = t_scaled * inv_det
    hit = ok & (t > t_min) & (t < t_max)
    return hit, t, v * inv_det, w * inv_det


def _columns(tri):
    """`(..., 9)` corners -> three `(x, y, z)` tuples of `(...)` columns."""
    cols = [tri[..., i] for i in range(9)]
    return tuple(cols[0:3]), tuple(cols[3:6]), tuple(cols[6:9])


# ---------------------------------------------------------------------------------------------
# Corners in a global order (for the brute force)


def _lex_less(p, q):
    """Lexicographic `p < q` of `(x, y, z)` column tuples (a ray-independent vertex order)."""
    return (p[0] < q[0]) | ((p[0] == q[0]) & ((p[1] < q[1]) | ((p[1] == q[1]) & (p[2] < q[2]))))


def _sorted_corners(tri):
    """`(f, 9)` corners -> `(9, f)` rows `a, b, c`: each triangle's corners sorted by `_lex_less`.

    With the corners of every triangle in one global order, an edge shared by two triangles
    has the same first and second corner in both, so its edge function is evaluated on the
    same operands in the same places (bit-identical, whatever fused multiply-adds XLA emits)
    without the per-ray canonical swap of `_edge`. Sorting permutes the corners, which only
    flips the common sign of `U, V, W` and `det` (the test accepts both signs) and leaves `t`
    unchanged.
    """
    a, b, c = _columns(tri)

    def swap(p, q):
        s = _lex_less(q, p)
        lo = tuple(jnp.where(s, y, x) for x, y in zip(p, q, strict=True))
        hi = tuple(jnp.where(s, x, y) for x, y in zip(p, q, strict=True))
        return lo, hi

    a, b = swap(a, b)
    b, c = swap(b, c)
    a, b = swap(a, b)
    return jnp.stack(a + b + c)
