"""Figures for `radiometria.camera` (thesis section 2.3)."""

import jax
import jax.numpy as jnp
import numpy as np

from ..camera import (
    BoxFilter,
    GaussianFilter,
    LanczosFilter,
    MitchellFilter,
    PinholeCamera,
    TentFilter,
    generate_ray,
    look_at,
    perspective,
    project,
)
from ._registry import figure, save

_FILTER_EXTENT = 3.0  # the filter figure plots offsets on [-3, 3] px in both axes [px]


@jax.jit
def _sample_in_chunks(filt, u):
    """`filt.sample(u)` in 8 chunks: the tabulated filters' inversion of all 10^6 variates at
    once held ~0.2 GB of intermediates. Float32 offsets (n, 2) and weights (n,)."""
    offset, weight = jax.lax.map(filt.sample, u.reshape(8, -1, 2))
    return offset.reshape(-1, 2), weight.reshape(-1)


def filters_figure_data(*, smoke: bool = False) -> dict:
    """What the reconstruction-filter figure plots, from the filters of `radiometria.camera`.

    `n`, the samples per filter (20 000 in smoke mode, else 10^6); `x` (1201,) on [-3, 3] [px];
    `bins` (121,), the 1D histogram's edges [px]; and `filters`, one dict per filter (box,
    tent, Gaussian, Mitchell-Netravali, Lanczos, default parameters) with `title`, `filter`,
    `profile` = `evaluate_1d(x)` in float32 [px^-1], `offset` (n, 2) and `weight` (n,) =
    `sample(u)` in float32 for uniforms `u` from key 0 (split per filter) [px],
    [dimensionless], `hist` (120,), the histogram of `offset[:, 0]` weighted by `weight` and
    divided by n times the bin width (an estimate of $f_1$) [px^-1], and `h2` (80, 80) with edges
    `xe`, `ye`, the density of the sampled offsets ($\\propto |f|$) [px^-2].
    """
    filters = [
        ("box", BoxFilter()),
        ("tent", TentFilter()),
        (r"Gaussian ($\sigma$ = 0.5)", GaussianFilter()),
        ("Mitchell-Netravali (B = C = 1/3)", MitchellFilter()),
        (r"Lanczos ($\tau$ = 3)", LanczosFilter()),
    ]
    n = 20_000 if smoke else 1_000_000
    extent = _FILTER_EXTENT
    keys = jax.random.split(jax.random.key(0), len(filters))
    x = np.linspace(-extent, extent, 1201)
    bins = np.linspace(-extent, extent, 121)
    out = []
    for (title, filt), key in zip(filters, keys, strict=True):
        u = jax.random.uniform(key, (n, 2), dtype=jnp.float32)
        offset, weight = _sample_in_chunks(filt, u)
        hist, _ = np.histogram(offset[:, 0], bins=bins, weights=weight)
        hist /= n * np.diff(bins)  # the weighted histogram estimates the marginal of f: f_1
        h2, xe, ye = np.histogram2d(
            offset[:, 0], offset[:, 1], bins=80, range=[[-extent, extent], [-extent, extent]]
        )
        h2 /= n * np.diff(xe)[0] * np.diff(ye)[0]
        out.append(
            {
                "title": title,
                "filter": filt,
                "profile": np.asarray(filt.evaluate_1d(jnp.asarray(x, jnp.float32))),
                "offset": offset,
                "weight": weight,
                "hist": hist,
                "h2": h2,
                "xe": xe,
                "ye": ye,
            }
        )
    return {"n": n, "x": x, "bins": bins, "filters": out}


@figure("fig_2_filters")
def fig_2_filters(out_dir, *, smoke: bool = False):
    """Reconstruction filters and their importance-sampled footprints (thesis eq. 2.31-2.35).

    Top row: the normalised 1D profile $f_1(x)$ of each filter and the histogram of sampled
    x-offsets weighted by $w = f/p$, which reconstructs $f_1$ including its negative lobes (the
    estimator of eq. 2.35 is unbiased). Bottom row: the 2D histogram of the sampled offsets,
    i.e. the sampling density $p \\propto |f|$ (the footprint of one pixel's samples). The data
    are `filters_figure_data()`.
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import PowerNorm

    data = filters_figure_data(smoke=smoke)
    extent, x, bins = _FILTER_EXTENT, data["x"], data["bins"]
    fig, axes = plt.subplots(2, len(data["filters"]), figsize=(15.0, 6.0), layout="constrained")
    for col, d in enumerate(data["filters"]):
        title, filt, profile, hist = d["title"], d["filter"], d["profile"], d["hist"]
        ax = axes[0, col]
        ax.stairs(
            hist,
            bins,
            color="tab:orange",
            fill=True,
            alpha=0.45,
            label="sampled, weighted by $f/p$",
        )
        ax.plot(x, profile, color="k", lw=1.2, label="$f_1(x)$")
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("offset x [px]")
        ax.set_xlim(-extent, extent)
        ax.grid(True, alpha=0.3)
        if col == 0:
            ax.set_ylabel("filter value [px$^{-1}$]")
            ax.legend(fontsize=7, loc="upper left")
        ax2 = axes[1, col]
        h2 = d["h2"]
        im = ax2.imshow(
            h2.T, origin="lower", extent=(-extent, extent, -extent, extent), cmap="magma",
            interpolation="nearest", norm=PowerNorm(0.5),  # square-root scale shows the lobes
        )  # fmt: skip
        ax2.set_xlabel("offset x [px]")
        if col == 0:
            ax2.set_ylabel("offset y [px]")
        ax2.set_title(f"samples $\\propto |f|$, radius {filt.radius:g} px", fontsize=9)
        fig.colorbar(im, ax=ax2, shrink=0.8, label="density [px$^{-2}$]")
    fig.suptitle("Pixel reconstruction filters and filter importance sampling (eq. 2.35)")
    return save(fig, out_dir, "fig_2_filters")


# --------------------------------------------------------------------------------------------
# Pinhole camera and perspective projection (thesis fig. 2.5 and 2.6)

_FIG_CAMERA = {
    "origin": (4.0, 2.5, 5.0),
    "target": (0.0, 0.6, 0.0),
    "up": (0.0, 1.0, 0.0),
    "fov_x_deg": 40.0,
    "width": 64,
    "height": 48,
    "near": 2.0,
    "far": 12.0,
}
_FRUSTUM_DRAW_DEPTH = 9.0  # fig. 2.5 draws the frustum up to this camera depth [scene units]
_CUBE_EDGES = [(0, 1), (1, 3), (3, 2), (2, 0), (4, 5), (5, 7), (7, 6), (6, 4)]
_CUBE_EDGES += [(0, 4), (1, 5), (2, 6), (3, 7)]


def _cube_vertices(centre, side: float) -> np.ndarray:
    """The 8 vertices of an axis-aligned cube, vertex k = (k & 1, k & 2, k & 4) ones. [units]"""
    bits = np.array([[(k >> b) & 1 for b in range(3)] for k in range(8)], float)
    return np.asarray(centre, float) + side * (bits - 0.5)


def pinhole_figure_data() -> dict:
    """Everything fig. 2.5 and 2.6 plot, computed with `radiometria.camera` (world space data).

    A `PinholeCamera` built by `look_at` looks at a wireframe cube. The dict holds:
    `camera`; `to_world` (4, 4); `points` (8, 3), the cube's vertices [scene units]; `raster`
    (8, 2) = `project(camera, points)` [px]; `ray_origin`, `ray_direction` (8, 3) =
    `generate_ray(camera, raster)`; `film_points` (8, 3), where each ray crosses the near
    (film) plane [scene units]; `corner_raster` (4, 2), the image corners, and `near_corners`,
    `far_corners` (4, 3), the frustum's corners on the near and far planes (from
    `generate_ray` at the image corners); `camera_points` (8, 3), the cube in camera space
    (`inverse(look_at(...))`); `projection` (4, 4) = `perspective(...)` (eq. 2.30);
    `ndc_points` (8, 3), the cube after `projection` and the perspective divide; `depth_z`
    and `depth_ndc` (n,), the depth map $z \\mapsto z_\\mathrm{ndc}$ of eq. 2.29-2.30 on
    $[n, f]$ for this camera's clip planes (from `perspective`).
    """
    c = _FIG_CAMERA
    camera = PinholeCamera.from_look_at(
        np.array(c["origin"]),
        np.array(c["target"]),
        np.array(c["up"]),
        c["fov_x_deg"],
        c["width"],
        c["height"],
        "x",
        near_clip=c["near"],
        far_clip=c["far"],
    )
    to_world = np.asarray(look_at(np.array(c["origin"]), np.array(c["target"]), np.array(c["up"])))
    points = _cube_vertices(c["target"], 1.6)
    raster = np.asarray(project(camera, points))
    o, d = (np.asarray(x) for x in generate_ray(camera, raster))
    forward = to_world[:3, 2]

    def at_depth(direction, depth):  # the point of the ray o + s d with camera z = depth
        return o[:1] + direction * (depth / (direction @ forward))[..., None]

    film = at_depth(d, c["near"])
    w, h = float(c["width"]), float(c["height"])
    corner_raster = np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]])
    _, dc = (np.asarray(x) for x in generate_ray(camera, corner_raster))
    camera_points = (np.linalg.inv(to_world) @ np.c_[points, np.ones(8)].T).T[:, :3]
    projection = np.asarray(perspective(c["fov_x_deg"], w / h, c["near"], c["far"]))
    clip = (projection @ np.c_[camera_points, np.ones(8)].T).T
    depth_z = np.linspace(c["near"], c["far"], 200)
    depth_clip = (projection @ np.stack([0 * depth_z, 0 * depth_z, depth_z, 1 + 0 * depth_z])).T
    return {
        "camera": camera,
        "to_world": to_world,
        "points": points,
        "raster": raster,
        "ray_origin": o,
        "ray_direction": d,
        "film_points": film,
        "corner_raster": corner_raster,
        "near_corners": at_depth(dc, c["near"]),
        "far_corners": at_depth(dc, c["far"]),
        "camera_points": camera_points,
        "projection": projection,
        "ndc_points": clip[:, :3] / clip[:, 3:],
        "depth_z": depth_z,
        "depth_ndc": depth_clip[:, 2] / depth_clip[:, 3],
    }


@figure("fig_2_5_pinhole")
def fig_2_5_pinhole(out_dir, *, smoke: bool = False):
    """The pinhole camera model: world-space geometry and the image on the film.

    Left: a camera built by `look_at` (its camera-space axes drawn at the pinhole $\\vec{o}$:
    $+x$ towards the image's left, $+y$ up, $+z$ forward, Mitsuba's convention) looks at a
    wireframe cube. Each vertex $\\vec{p}$ is joined to the pinhole by the primary ray that
    `generate_ray` casts through its raster position `project(camera, p)`; the ray crosses
    the film (near) plane at distance $n$ in $\\vec{q}$, the projection of $\\vec{p}$. The
    frustum's edges are the rays through the four image corners. Right: the raster image of
    the cube, `project(camera, p)` in pixels, $(0, 0)$ at the top-left corner. The data are
    `pinhole_figure_data()`.

    !!! note "Thesis"
        Fig. 2.5, section 2.3.1 (pinhole camera model; points $\\vec{p}$, $\\vec{q}$).
    """
    import matplotlib.pyplot as plt

    data = pinhole_figure_data()
    o, m = data["ray_origin"][0], data["to_world"]
    fig = plt.figure(figsize=(12.5, 4.8))
    fig.subplots_adjust(wspace=0.35)
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    ax.set_proj_type("persp")
    for a, b in _CUBE_EDGES:
        ax.plot(*data["points"][[a, b]].T, color="tab:blue", lw=1.4)
    for p, q in zip(data["points"], data["film_points"], strict=True):
        ax.plot(*np.stack([p, o]).T, color="tab:orange", lw=0.7, ls="--")
        ax.scatter(*q, color="tab:red", s=8)
    near = data["near_corners"]
    far = o + (data["far_corners"] - o) * (_FRUSTUM_DRAW_DEPTH / _FIG_CAMERA["far"])
    for k in range(4):
        ax.plot(*np.stack([o, far[k]]).T, color="0.45", lw=0.8)
    ax.plot(*np.vstack([far, far[:1]]).T, color="0.6", lw=1.0)
    ax.plot(*np.vstack([near, near[:1]]).T, color="tab:red", lw=1.2)
    quad = near[[0, 1, 3, 2]].reshape(2, 2, 3)  # the film plane as a 2 x 2 surface
    ax.plot_surface(*np.moveaxis(quad, -1, 0), color="tab:red", alpha=0.15, shade=False)
    for k, (name, colour) in enumerate(zip(("x", "y", "z"), ("r", "g", "b"), strict=True)):
        tip = o + 1.5 * m[:3, k]
        ax.plot(*np.stack([o, tip]).T, color=colour, lw=1.8)
        ax.text(*tip, f"${name}_\\mathrm{{cam}}$", color=colour, fontsize=8)
    ax.scatter(*o, color="k", s=18)
    ax.text(*o, r"  $\vec{o}$", fontsize=10)
    ax.text(*data["points"][7], r" $\vec{p}$", fontsize=10, color="tab:blue")
    ax.text(*data["film_points"][7], r" $\vec{q}$", fontsize=10, color="tab:red")
    ax.set_xlabel("x (world)")
    ax.set_ylabel("y (world)")
    ax.set_zlabel("z (world)")
    ax.view_init(elev=22, azim=-25, vertical_axis="y")
    ax.set_title("world space: rays from the pinhole (generate_ray)", fontsize=10)

    ax2 = fig.add_subplot(1, 2, 2)
    cam = data["camera"]
    r = data["raster"]
    for a, b in _CUBE_EDGES:
        ax2.plot(*r[[a, b]].T, color="tab:blue", lw=1.4)
    ax2.plot(*r.T, "o", color="tab:red", ms=4)
    ax2.add_patch(plt.Rectangle((0, 0), cam.width, cam.height, fill=False, ec="k", lw=1.2))
    ax2.set_xticks(np.arange(0, cam.width + 1, 8))
    ax2.set_yticks(np.arange(0, cam.height + 1, 8))
    ax2.grid(True, alpha=0.3)
    ax2.set_xlim(-2, cam.width + 2)
    ax2.set_ylim(cam.height + 2, -2)  # raster y points down
    ax2.set_aspect("equal")
    ax2.set_xlabel("raster x [px]")
    ax2.set_ylabel("raster y [px]")
    ax2.set_title(f"raster space: project(camera, p), {cam.width} x {cam.height} px", fontsize=10)
    fig.suptitle("Pinhole camera model (thesis fig. 2.5)")
    return save(fig, out_dir, "fig_2_5_pinhole")


@figure("fig_2_6_projection")
def fig_2_6_projection(out_dir, *, smoke: bool = False):
    """Perspective projection: camera space, normalised device coordinates and the depth map.

    (a) Camera space seen along the $x$ axis: the frustum between the near plane $z = n$ (the
    film plane) and the far plane $z = f$, the cube of fig. 2.5 and each vertex's projection
    $q_y = n\\,y/z$ on the film plane. (b) The same points in NDC, after the matrix of eq. 2.30
    (`perspective`) and the perspective divide: the frustum becomes the square $[-1, 1]^2$.
    (c) The nonlinear depth map $z \\mapsto z_\\mathrm{ndc}$ of eq. 2.29-2.30: $n \\mapsto -1$,
    $f \\mapsto 1$, and the harmonic mean $2fn/(f + n)$ of the clip distances maps to 0. The
    data are `pinhole_figure_data()`.

    !!! note "Thesis"
        Fig. 2.6 (a) and (b), eq. 2.28-2.30, section 2.3.1.
    """
    import matplotlib.pyplot as plt

    data = pinhole_figure_data()
    c = _FIG_CAMERA
    n, f = c["near"], c["far"]
    tan_y = np.asarray(data["camera"].tan_half_fov()[1])
    p, ndc = data["camera_points"], data["ndc_points"]
    fig, axes = plt.subplots(1, 3, figsize=(14.0, 4.2), layout="constrained")
    ax = axes[0]
    ax.fill([0, f, f], [0, f * tan_y, -f * tan_y], color="0.92", zorder=0)
    ax.plot([0, f], [0, f * tan_y], color="0.4", lw=0.8)
    ax.plot([0, f], [0, -f * tan_y], color="0.4", lw=0.8)
    ax.plot([n, n], [-n * tan_y, n * tan_y], color="tab:red", lw=2, label="near (film) plane")
    ax.plot([f, f], [-f * tan_y, f * tan_y], color="0.3", lw=2, label="far plane")
    for a, b in _CUBE_EDGES:
        ax.plot(p[[a, b], 2], p[[a, b], 1], color="tab:blue", lw=1.2)
    q_y = n * p[:, 1] / p[:, 2]
    for k in range(8):
        ax.plot([0, p[k, 2]], [0, p[k, 1]], color="tab:orange", lw=0.6, ls="--")
    ax.plot(np.full(8, n), q_y, "o", color="tab:red", ms=3, label=r"$q_y = n\,y/z$")
    ax.plot(0, 0, "ko", ms=4)
    ax.annotate(r"$\vec{o}$", (0, 0), textcoords="offset points", xytext=(3, 6))
    ax.set_xlabel(r"$z_\mathrm{cam}$ [scene units]")
    ax.set_ylabel(r"$y_\mathrm{cam}$ [scene units]")
    ax.set_title("(a) camera space, seen along $x$", fontsize=10)
    ax.legend(fontsize=7, loc="lower left")
    ax = axes[1]
    ax.add_patch(plt.Rectangle((-1, -1), 2, 2, color="0.92", zorder=0))
    ax.axvline(-1, color="tab:red", lw=2)
    ax.axvline(1, color="0.3", lw=2)
    for a, b in _CUBE_EDGES:
        ax.plot(ndc[[a, b], 2], ndc[[a, b], 1], color="tab:blue", lw=1.2)
    ax.plot(ndc[:, 2], ndc[:, 1], "o", color="tab:red", ms=3)
    ax.set_xlim(-1.15, 1.15)
    ax.set_ylim(-1.15, 1.15)
    ax.set_aspect("equal")
    ax.set_xlabel(r"$z_\mathrm{ndc}$")
    ax.set_ylabel(r"$y_\mathrm{ndc}$")
    ax.set_title("(b) NDC: eq. 2.30 and the perspective divide", fontsize=10)
    ax = axes[2]
    z, zn = data["depth_z"], data["depth_ndc"]
    ax.plot(z, zn, color="k", lw=1.6, label=rf"$n$ = {n:g}, $f$ = {f:g}")
    ax.plot(z, -1 + 2 * (z - n) / (f - n), color="0.6", ls=":", label="linear map")
    h = 2 * f * n / (f + n)
    ax.plot([h, h, n], [-1.1, 0, 0], color="tab:red", lw=0.8, ls="--")
    ax.annotate(
        rf"$2fn/(f+n)$ = {h:.2f}",
        (h, 0),
        textcoords="offset points",
        xytext=(6, -14),
        fontsize=8,
        color="tab:red",
    )
    ax.plot(p[:, 2], ndc[:, 2], "o", color="tab:blue", ms=3, label="cube vertices")
    ax.set_xlim(0, f * 1.02)
    ax.set_ylim(-1.1, 1.1)
    ax.set_xlabel(r"$z_\mathrm{cam}$ [scene units]")
    ax.set_ylabel(r"$z_\mathrm{ndc}$")
    ax.set_title("(c) nonlinear depth map (eq. 2.29)", fontsize=10)
    ax.legend(fontsize=7, loc="lower right")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    fig.suptitle("Perspective projection of the pinhole camera (thesis fig. 2.6)")
    return save(fig, out_dir, "fig_2_6_projection")
