r"""Picking one of a few area emitters by its estimated contribution at the shading point.

Selection by power alone ignores where the shading point is: a large, dim emitter far away is
picked as often as from close by, and a small bright one next to the point as rarely as from
the far end of the scene. `EmitterBounds` bounds each emitter (a sphere around its triangles,
a cone around their normals, pbrt-v4's `LightBounds`) and estimates what it can contribute
at a point $\mathbf p$ as its mean radiance times an estimate of the solid angle it subtends,

$$I_e(\mathbf p) = \bar L_e\,\min\Big(\frac{A_e\cos\theta'}{d^2},\;
  2\pi(1-\cos\theta_b),\;\Omega_{\max}\Big),\qquad
  \theta' = \max(0,\ \theta_w - \theta_o - \theta_b),$$

with $d$ the distance from the bounding sphere's centre, $\theta_w$ the angle between the
normal cone's axis and the direction to $\mathbf p$ (its absolute cosine for two-sided
emitters), $\theta_o$ the cone's half-angle, $\theta_b$ the half-angle the bounding sphere
subtends ($\pi$ from inside it), $A_e$ the emitter's area and $\Omega_{\max}$ $2\pi$ for a
flat emitter ($\theta_o = 0$), $4\pi$ otherwise. $A_e\cos\theta'/d^2$ is pbrt-v4's
importance (`Pharr2023` §12.6.3, `LightBounds::Importance`) without the receiver's normal,
which the densities of BSDF samples would then need; the two caps keep a large emitter close
by from being overrated (the solid angle of the bounding sphere, and of a half-space). A flat
one-sided emitter also gets $I_e = 0$ behind the planes of all its triangles, where the cone
alone is loose (a point just behind a large emitter sees it edge-on within its bounding
sphere's angle). $I_e = 0$ only when no point of the emitter faces $\mathbf p$: the bounds
are conservative, so every emitter that can light $\mathbf p$ keeps a positive probability
and next-event estimation stays unbiased. The emitter is picked with probability
$P_e(\mathbf p) = I_e / \sum_i I_i$, then one of its triangles by power, as before.

On `benchmarks/bench_media.py`'s heterogeneous scene (a large dim emitter behind the medium,
a small bright one above it; 256 x 256, 16 spp, against a 1024-spp Mitsuba reference) the
relative MSE was 4.99e-2 with selection by power, 4.16e-2 picking the two emitters
uniformly (Mitsuba 3's choice; Mitsuba itself: 4.20e-2) and 4.07e-2 with this estimate, in
the same render time.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from ..._checks import device_array
from ..._math import acos_fast, asin_fast

__all__ = ["MAX_SPATIAL_EMITTERS", "EmitterBounds"]

MAX_SPATIAL_EMITTERS = 64  # more emitters are picked by power alone (an (n, E) table per query)
_ANGLE_MARGIN = 1e-3  # radians: float rounding must not zero an emitter seen edge-on


class EmitterBounds(eqx.Module):
    """Bounds of each of `E` area emitters and the selection probabilities they give
    (module docstring).

    **Fields:**

    - `center`, `radius`: `(E, 3)`, `(E,)` bounding sphere of each emitter. [scene units]
    - `axis`, `theta_o`: `(E, 3)`, `(E,)` unit axis and half-angle of the cone holding the
        emitting sides' normals (`theta_o = pi`: any direction). [1], [rad]
    - `two_sided`: `(E,)` bool, emitters emitting on both sides.
    - `area`: `(E,)` emitting area. [scene units^2]
    - `radiance`: `(E,)` mean emitted radiance (the power's). [W m^-2 sr^-1 nm^-1]
    - `omega_max`: `(E,)` cap on the solid angle (2 pi flat, 4 pi otherwise). [sr]
    - `plane`: `(E,)` for a flat one-sided emitter the least `axis . y` over its points `y`
        (a point `p` with `axis . p` at most that is behind every triangle), else -inf.
        [scene units]
    - `power_prob`: `(E,)` each emitter's share of the triangles' power-based probabilities.
    - `cdf_lo`: `(E,)` the triangles' cumulative probability before each emitter's first.
    - `first`, `last`: `(E,)` int32, each emitter's triangles in the light arrays.
    - `slot`: `(R,)` int32, the index in these arrays of each emitter row of the scene (0 for
        rows with no emitting triangle, which no query reaches).
    """

    center: Float[Array, "e 3"]
    radius: Float[Array, " e"]
    axis: Float[Array, "e 3"]
    theta_o: Float[Array, " e"]
    two_sided: Array
    area: Float[Array, " e"]
    radiance: Float[Array, " e"]
    omega_max: Float[Array, " e"]
    plane: Float[Array, " e"]
    power_prob: Float[Array, " e"]
    cdf_lo: Float[Array, " e"]
    first: Int[Array, " e"]
    last: Int[Array, " e"]
    slot: Int[Array, " r"]

    @classmethod
    def from_triangles(
        cls, corners, normal, area, emitter, prob, radiance, two_sided, spheres=None,
        dtype=jnp.float32,
    ) -> "EmitterBounds":  # fmt: skip
        """Bounds from the `l` light triangles (NumPy, once), ordered by emitter.

        **Arguments:**

        - `corners`: `(l, 3, 3)` the triangles' corners; `normal`: `(l, 3)` unit normals;
            `area`: `(l,)` areas. [scene units]
        - `emitter`: `(l,)` emitter row of each triangle, non-decreasing; `prob`: `(l,)`
            the power-based selection probabilities (sum 1).
        - `radiance`: `(R,)` mean radiance and `two_sided`: `(R,)` bool of every emitter row.
        - `spheres`: per emitter row `(center, radius)` of a sphere it lies on (its bounds
            then), or `None`.
        """
        rows, starts = np.unique(emitter, return_index=True)
        e_count = rows.size
        ends = np.concatenate([starts[1:], [emitter.size]])
        slot = np.zeros(len(radiance), np.int64)
        slot[rows] = np.arange(e_count)
        center, radius = np.zeros((e_count, 3)), np.zeros(e_count)
        axis, theta_o = np.zeros((e_count, 3)), np.zeros(e_count)
        flat = np.zeros(e_count, bool)
        plane = np.full(e_count, -np.inf)
        for e, (a, b) in enumerate(zip(starts, ends, strict=True)):
            pts = corners[a:b].reshape(-1, 3)
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            c = 0.5 * (lo + hi)
            r = float(np.sqrt(np.max(np.sum((pts - c) ** 2, axis=1))))
            sp = None if spheres is None else spheres[rows[e]]
            if sp is not None:
                c, r = np.asarray(sp[0], np.float64), max(r, float(sp[1]))
            center[e], radius[e] = c, r
            mean = (area[a:b, None] * normal[a:b]).sum(axis=0)
            norm = np.linalg.norm(mean)
            if norm <= 1e-6 * area[a:b].sum():
                axis[e], theta_o[e] = (0.0, 0.0, 1.0), np.pi
                continue
            axis[e] = mean / norm
            cos_min = float(np.min(normal[a:b] @ axis[e]))
            theta_o[e] = np.arccos(np.clip(cos_min, -1.0, 1.0))
            flat[e] = cos_min > 1.0 - 1e-6
            if flat[e] and not two_sided[rows[e]]:
                plane[e] = float(np.min(pts @ axis[e]))
                plane[e] -= 1e-4 * (1.0 + np.max(np.abs(pts)))  # float rounding: a margin
        cdf = np.cumsum(prob)
        power_prob = np.add.reduceat(prob, starts)
        e_area = np.add.reduceat(area, starts)

        def arr(x, dt=dtype):
            return device_array(x, dt)

        return cls(
            center=arr(center),
            radius=arr(radius),
            axis=arr(axis),
            theta_o=arr(theta_o),
            two_sided=device_array(np.asarray(two_sided)[rows], bool),
            area=arr(e_area),
            radiance=arr(np.asarray(radiance)[rows]),
            omega_max=arr(np.where(flat, 2.0 * np.pi, 4.0 * np.pi)),
            plane=arr(plane),
            power_prob=arr(power_prob),
            cdf_lo=arr(cdf[starts] - prob[starts]),
            first=arr(starts, jnp.int32),
            last=arr(ends - 1, jnp.int32),
            slot=arr(slot, jnp.int32),
        )

    def probabilities(self, p: Float[Array, "n 3"]) -> Float[Array, "n e"]:
        """`P_e(p)`, the selection probability of each emitter at the points `p` [scene
        units]; rows of 0 where no emitter faces the point. [1]"""
        return self._probabilities(p).T

    def _probabilities(self, p: Float[Array, "n 3"]) -> Float[Array, "e n"]:
        """`probabilities` laid out emitters by points, `(e, n)`, computed on components:
        XLA:CPU vectorises along the last axis only (the ray-sphere test of
        `radiometria.render._geometry._sphere._roots` measured 3-8x faster this way than on
        `(n, e, 3)` arrays)."""
        pc = [p[:, i][None, :] for i in range(3)]
        v = [pc[i] - self.center[:, i][:, None] for i in range(3)]
        axis = [self.axis[:, i][:, None] for i in range(3)]
        d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
        dist = jnp.sqrt(d2)
        cos_w = (v[0] * axis[0] + v[1] * axis[1] + v[2] * axis[2]) / jnp.where(dist > 0, dist, 1.0)
        cos_w = jnp.where(self.two_sided[:, None], jnp.abs(cos_w), cos_w)
        theta_w = acos_fast(jnp.clip(cos_w, -1.0, 1.0))
        r = self.radius[:, None]
        outside = d2 > r * r
        sin_b = jnp.where(outside, r / jnp.where(outside, dist, 1.0), 0.0)
        theta_b = jnp.where(outside, asin_fast(jnp.clip(sin_b, 0.0, 1.0)), jnp.pi)
        theta = jnp.maximum(theta_w - self.theta_o[:, None] - theta_b - _ANGLE_MARGIN, 0.0)
        cos_t = jnp.where(theta < 0.5 * jnp.pi, jnp.cos(theta), 0.0)
        omega_b = jnp.where(outside, 2.0 * jnp.pi * (1.0 - jnp.sqrt(1.0 - sin_b * sin_b)),
                            4.0 * jnp.pi)  # fmt: skip
        tiny = jnp.finfo(p.dtype).tiny
        omega = jnp.minimum(self.area[:, None] * cos_t / jnp.maximum(d2, tiny), omega_b)
        importance = self.radiance[:, None] * jnp.minimum(omega, self.omega_max[:, None])
        front = pc[0] * axis[0] + pc[1] * axis[1] + pc[2] * axis[2] > self.plane[:, None]
        importance = jnp.where((cos_t > 0) & front, importance, 0.0)
        total = jnp.sum(importance, axis=0, keepdims=True)
        return importance / jnp.where(total > 0, total, 1.0)

    def factor(self, row: Int[Array, " n"], p: Float[Array, "n 3"]) -> Float[Array, " n"]:
        """`P_e(p) / power_prob[e]` for the emitter `e` of scene emitter row `row[i]`: how much
        more (or less) likely it is picked at `p[i]` than by power, the factor on its
        triangles' densities. [1]"""
        e = self.slot[jnp.maximum(row, 0)]
        probs = self._probabilities(p)
        mine = jnp.take_along_axis(probs, e[None, :], axis=0)[0]
        return mine / self.power_prob[e]

    def pick(
        self, p: Float[Array, "n 3"], u: Float[Array, " n"], cdf: Float[Array, " l"]
    ) -> tuple[Int[Array, " n"], Float[Array, " n"]]:
        """`(j, factor)`: a light triangle `j` picked from `u` by emitter (`probabilities`) and
        then by power within it (the variate re-used, `cdf` the triangles' cumulative
        power-based probabilities), and `factor` as in `factor` (0 where no emitter faces
        `p`)."""
        probs = self._probabilities(p)
        cum = jnp.cumsum(probs, axis=0)
        e = jnp.sum(u[None, :] >= cum[:-1], axis=0).astype(jnp.int32)
        p_e = jnp.take_along_axis(probs, e[None, :], axis=0)[0]
        lo = jnp.take_along_axis(cum, e[None, :], axis=0)[0] - p_e
        u_in = jnp.clip((u - lo) / jnp.where(p_e > 0, p_e, 1.0), 0.0, 1.0)
        u_tri = self.cdf_lo[e] + u_in * self.power_prob[e]
        method = "compare_all" if cdf.shape[0] <= 64 else "scan_unrolled"
        j = jnp.searchsorted(cdf, u_tri, side="right", method=method)
        j = jnp.clip(j, self.first[e], self.last[e])
        return j, p_e / self.power_prob[e]
