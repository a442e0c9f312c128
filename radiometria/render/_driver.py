r"""The render driver: batches of camera paths, spread over devices, into a film.

`render` estimates, for every pixel, the filtered spectral radiance of thesis eq. 2.35 and
converts it to linear sRGB:

1. **Work layout.** The image's $P = W H$ pixels are cut into tiles of `t` pixels; one *step*
   renders `k` samples (passes) of every pixel of one tile, `n = t k` paths at once, so memory
   stays bounded by the batch, never by $W H \cdot \mathrm{spp}$. The estimate of the bytes a
   batch and the film need is checked before anything is allocated.
2. **Samples.** Pixel `p`, pass `s` draws its variates from `pixel_samples` (independent or
   padded Owen-scrambled Sobol), which depend only on `(seed, s, p)`: the image does not
   depend on the batch layout or on the number of devices. Filter importance sampling puts the
   film position at the pixel centre plus an offset drawn from the reconstruction filter, with
   weight $w = f/p$ (thesis eq. 2.35); four hero wavelengths (`sample_hero_wavelengths`).
3. **Integrator.** `path_radiance` (or `direct_radiance`) gives $L(\lambda_i)$.
4. **Film.** Each path contributes $w \cdot \frac{1}{4}\sum_i L(\lambda_i)\,\bar{\mathbf{x}}(\lambda_i)
   / p(\lambda_i) / \int \bar y$ to its pixel's XYZ sum and $w$ to its weight sum (CIE 1931 2°
   observer; a radiance of the D65 white with $Y = 1$ gives XYZ of the D65 white point, as in
   Mitsuba and PBRT). The sums are accumulated on the host in float64; at the end
   $\mathrm{XYZ} = \sum w\,\mathrm{xyz} / \sum w$ becomes linear sRGB (D65).

**Devices.** The pixel axis of every step is sharded over a 1-D mesh of the local devices
(`jax.shard_map`): each device traces its share of the tile and no data moves between devices
during a step. On several hosts (`jax.distributed.initialize()` first, on every host), process
`i` of `m` renders the steps `i, i + m, i + 2m, ...` on its own devices, and the films are
summed across processes with `jax.experimental.multihost_utils.process_allgather` at the end,
so every process returns the whole image. A render is deterministic for a seed on any number
of devices or hosts (up to float rounding of the per-step sums, which is identical for the
same `batch`).
"""

import functools
import math
import os
from dataclasses import dataclass

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import check_choice, check_positive_int
from ..camera import Film, film_develop, film_samples_to_XYZ
from ._integrators import DIMENSIONS_PER_BOUNCE, path_radiance
from ._render_scene import RenderScene
from ._samplers import SAMPLERS, pixel_samples
from ._spectral import sample_hero_wavelengths

__all__ = ["INTEGRATORS", "estimate_render_memory", "render"]


INTEGRATORS = ("path", "direct")
CAMERA_DIMENSIONS = 4  # [filter x, filter y, wavelength, unused]: keeps bounce pairs aligned
_MAX_PIXELS = 2**31 - 2**20  # pixel indices are int32
_FILM_BYTES_PER_PIXEL = 4 * 4 * 3  # float32 sums (H, W, 4), the developed image, a host copy


def _available_host_memory() -> int:
    """Bytes of host memory currently available (Linux sysconf; 8 GiB when unknown)."""
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 8 * 2**30


def _path_bytes(n_triangles: int, n_dims: int) -> int:
    """A generous estimate of the device bytes one path of a batch needs while it is traced."""
    # variates, path state and temporaries (float32), plus the (rays, triangles) temporaries
    # of brute-force intersection.
    return 4 * (2 * n_dims + 256 + 12 * n_triangles)


def estimate_render_memory(
    width: int, height: int, batch: int, n_triangles: int, max_depth: int
) -> tuple[int, int]:
    """Estimated `(host_bytes, device_bytes)` of a render: the film, and one batch of paths."""
    n_dims = CAMERA_DIMENSIONS + DIMENSIONS_PER_BOUNCE * (max_depth - 1)
    return width * height * _FILM_BYTES_PER_PIXEL, batch * _path_bytes(n_triangles, n_dims)


@dataclass(frozen=True)
class _Plan:
    n_pixels: int
    tile: int  # pixels per step (a multiple of the device count)
    passes: int  # samples per pixel per step
    n_tiles: int
    n_groups: int  # pass groups

    @property
    def n_steps(self) -> int:
        return self.n_tiles * self.n_groups


def _plan(n_pixels: int, spp: int, batch: int, n_devices: int) -> _Plan:
    # Tiles are multiples of 128 pixels where possible (so 1, 2, 4, ..., 128 devices share
    # one layout and render bit-identical images), and of the device count in any case.
    quantum = math.lcm(128, n_devices) if n_pixels >= 128 else n_devices
    tile = min(batch, n_pixels)
    tile = max(quantum, -(-tile // quantum) * quantum)
    passes = max(1, min(spp, batch // tile))
    n_groups = -(-spp // passes)
    passes = -(-spp // n_groups)  # balance the groups: fewer wasted passes in the last one
    return _Plan(n_pixels, tile, passes, -(-n_pixels // tile), n_groups)


class _Kernel(eqx.Module):
    """Everything the paths of a step read: scene, camera, filter (one pytree, replicated)."""

    scene: RenderScene
    camera: object
    rfilter: object
    cmfs: Film  # a 1 x 1 film: only its colour-matching functions are used here


def _paths_xyz(kernel: _Kernel, key, pass_start, pixel, *, plan: _Plan, spp, width, max_depth,
               rr_depth, integrator, sampler):
    """Per pixel of one device's share of a tile: `(t, 4)` = [sum w X, sum w Y, sum w Z, sum w]
    over the step's passes."""
    dtype = jnp.float32
    n_dims = CAMERA_DIMENSIONS + DIMENSIONS_PER_BOUNCE * (max_depth - 1)
    t = pixel.shape[0]
    k = plan.passes
    passes = pass_start + jnp.arange(k, dtype=jnp.int32)
    valid_pixel = pixel < plan.n_pixels
    pix = jnp.where(valid_pixel, pixel, 0)
    u = pixel_samples(key, sampler, passes, pix, n_dims, spp=spp, dtype=dtype)  # (t, k, d)
    u = u.reshape(t * k, n_dims)
    px = jnp.repeat((pix % width).astype(dtype), k)
    py = jnp.repeat((pix // width).astype(dtype), k)
    offset, weight = kernel.rfilter.sample(u[:, 0:2])
    raster = jnp.stack([px + 0.5 + offset[:, 0], py + 0.5 + offset[:, 1]], axis=-1)
    origins, directions = kernel.camera.generate_ray(raster.astype(dtype))
    wavelength_nm, pdf = sample_hero_wavelengths(u[:, 2])
    radiance = path_radiance(
        kernel.scene,
        origins.astype(dtype),
        directions.astype(dtype),
        wavelength_nm.astype(dtype),
        u[:, CAMERA_DIMENSIONS:],
        max_depth=max_depth,
        rr_depth=rr_depth if integrator == "path" else max_depth,
    )
    xyz = film_samples_to_XYZ(kernel.cmfs, radiance, wavelength_nm, pdf)
    ok = jnp.repeat(valid_pixel, k) & (jnp.tile(passes, t) < spp)
    ok = ok & jnp.all(jnp.isfinite(xyz), axis=-1)
    w = jnp.where(ok, weight.astype(dtype), 0.0)
    contrib = jnp.concatenate([xyz * w[:, None], w[:, None]], axis=-1)
    contrib = jnp.where(ok[:, None], contrib, 0.0)
    return contrib.reshape(t, k, 4).sum(axis=1)


def render(
    scene,
    *,
    spp: int,
    seed: int = 0,
    width: int | None = None,
    height: int | None = None,
    max_depth: int | None = None,
    integrator: str = "path",
    sampler: str = "independent",
    batch: int | None = None,
    progress: bool = True,
    devices=None,
    camera=None,
    rfilter=None,
    rr_depth: int = 5,
    return_xyz: bool = False,
):
    r"""Render a scene spectrally into a linear sRGB image (thesis ch. 8-9; eq. 2.35).

    **Arguments:**

    - `scene`: a built-in scene name (`"cornell-box"`, `"cornell-box-measured"`), a scene
        file path, a loaded scene description (`load_scene`), or a `RenderScene` together with
        `camera`.
    - `spp`: samples (camera paths) per pixel, >= 1.
    - `seed`: the seed of `jax.random.key`; the image is a deterministic function of it.
    - `width`, `height`: image size [px]; default: the scene's film.
    - `max_depth`: largest number of path segments (Mitsuba's meaning: 1 = emitters seen
        directly, 2 = direct illumination); default: the scene's, else 8.
    - `integrator`: `"path"` (NEE + MIS + Russian roulette) or `"direct"`.
    - `sampler`: `"independent"` or `"sobol"` (padded Owen-scrambled Sobol).
    - `batch`: paths traced per step (bounds memory); default: about 2^16 per CPU device,
        2^20 per GPU, within the device memory.
    - `progress`: show a tqdm progress bar on stderr.
    - `devices`: the devices to shard the pixels over; default `jax.local_devices()`.
    - `camera`, `rfilter`: a `radiometria.camera.PinholeCamera` and reconstruction filter, for
        a `RenderScene` (default filter: Gaussian, stddev 0.5 px, radius 2 px).
    - `rr_depth`: path segments before Russian roulette starts (Mitsuba's `rr_depth`, 5).
    - `return_xyz`: return CIE XYZ instead of linear sRGB.

    **Returns:**

    The image `(height, width, 3)` float32: linear sRGB (D65 white, no tone mapping) or XYZ,
    in the unit of the scene's radiance (a radiance spectrum $L$ gives
    $Y = \int L \bar y / \int \bar y$).

    Memory stays bounded by `batch`, never by `width x height x spp`; absurd image sizes are
    refused with a `ValueError` before anything is allocated. See the module docstring for the
    sharding over devices and hosts.

    !!! note "Thesis"
        Chapters 8-9 (light transport, titles only in the text); eq. 2.35 (filter importance
        sampling and the weighted pixel estimate); section 2.2 (XYZ, sRGB).

    ??? cite "References"
        `Pharr2023` ch. 5, 13; `Jakob2022`; `Wilkie2014`.
    """
    spp = check_positive_int(spp, "spp")
    scene, camera, rfilter, scene_depth = _resolve_scene(scene, camera, rfilter, width, height)
    max_depth = scene_depth if max_depth is None else max_depth
    spp = check_positive_int(spp, "spp")
    max_depth = check_positive_int(max_depth, "max_depth")
    rr_depth = check_positive_int(rr_depth, "rr_depth")
    check_choice(integrator, "integrator", INTEGRATORS)
    check_choice(sampler, "sampler", SAMPLERS)
    if integrator == "direct":
        max_depth = min(max_depth, 2)
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise TypeError(f"`seed` must be an int, got {type(seed).__name__} {seed!r}.")
    width, height = int(camera.width), int(camera.height)
    n_pixels = width * height
    if n_pixels > _MAX_PIXELS:
        raise ValueError(
            f"Image of {width} x {height} = {n_pixels} pixels is too large; at most {_MAX_PIXELS}."
        )
    devices = list(jax.local_devices() if devices is None else devices)
    if not devices:
        raise ValueError("`devices` must name at least one device.")
    n_triangles = int(scene.p0.shape[0])
    if batch is None:
        batch = _default_batch(devices, n_triangles, max_depth)
    batch = check_positive_int(batch, "batch")
    film_bytes, _ = estimate_render_memory(width, height, batch, n_triangles, max_depth)
    available = _available_host_memory()
    if film_bytes > available // 2:
        raise ValueError(
            f"A {width} x {height} film needs about {film_bytes / 2**30:.1f} GiB of memory "
            f"({_FILM_BYTES_PER_PIXEL} bytes per pixel), more than half of the "
            f"{available / 2**30:.1f} GiB available; render a smaller image."
        )
    plan = _plan(n_pixels, spp, batch, len(devices))
    kernel = _Kernel(scene, camera, rfilter, Film(1, 1, dtype=jnp.float32))
    step = _compiled_step(plan, spp, width, max_depth, rr_depth, integrator, sampler, tuple(devices))
    key = jax.random.key(int(seed))
    film = Film(width, height, dtype=jnp.float32)

    # Multi-host: process i of m takes steps i, i + m, ...; the films are summed at the end.
    n_proc, proc = jax.process_count(), jax.process_index()
    steps = range(proc, plan.n_steps, n_proc)
    bar = _progress_bar(progress, total=len(steps) * plan.tile * plan.passes)
    for i in steps:
        group, tile = divmod(i, plan.n_tiles)
        pixel = jnp.arange(plan.tile, dtype=jnp.int32) + np.int32(tile * plan.tile)
        film = step(film, kernel, key, jnp.int32(group * plan.passes), pixel)
        if bar is not None:
            bar.update(plan.tile * plan.passes)
    if bar is not None:
        bar.close()
    if n_proc > 1:
        from jax.experimental import multihost_utils

        parts = multihost_utils.process_allgather((film.xyz_sum, film.weight_sum))
        film = eqx.tree_at(
            lambda f: (f.xyz_sum, f.weight_sum), film, tuple(jnp.sum(p, axis=0) for p in parts)
        )
    return film_develop(film, "XYZ" if return_xyz else "sRGB")


def _resolve_scene(scene, camera, rfilter, width, height):
    """(RenderScene, camera, filter, default max_depth) from what `render` was given."""
    from ..camera import GaussianFilter

    if isinstance(scene, RenderScene):
        if camera is None:
            raise ValueError("Rendering a `RenderScene` needs `camera` (a PinholeCamera).")
        for name, value, have in (("width", width, camera.width), ("height", height, camera.height)):
            if value is not None and value != have:
                raise ValueError(
                    f"`{name}`={value} differs from the camera's {have} [px]; build the camera "
                    "with the image size you want."
                )
        return scene, camera, GaussianFilter() if rfilter is None else rfilter, 8
    raise TypeError(
        f"`scene` must be a scene name, a path, a loaded scene or a RenderScene, got "
        f"{type(scene).__name__}."
    )


def _default_batch(devices, n_triangles: int, max_depth: int) -> int:
    """Paths per step: about 2^16 per CPU device, 2^20 per accelerator, within memory."""
    n_dims = CAMERA_DIMENSIONS + DIMENSIONS_PER_BOUNCE * (max_depth - 1)
    per_path = _path_bytes(n_triangles, n_dims)
    if devices[0].platform == "cpu":
        budget = min(2**30, _available_host_memory() // 4)
        target = 2**16
    else:
        stats = devices[0].memory_stats() or {}
        budget = int(stats.get("bytes_limit", 8 * 2**30)) // 4
        target = 2**20
    per_device = max(1024, min(target, budget // per_path))
    return per_device * len(devices)


_STEP_CACHE: dict = {}


def _compiled_step(plan, spp, width, max_depth, rr_depth, integrator, sampler, devices):
    """The jitted step for one configuration, sharded over `devices` (cached)."""
    cache_key = (plan, spp, width, max_depth, rr_depth, integrator, sampler, devices)
    if cache_key in _STEP_CACHE:
        return _STEP_CACHE[cache_key]
    from jax.sharding import Mesh, PartitionSpec as P

    mesh = Mesh(np.asarray(devices), ("pixels",))

    def local(kernel, key, pass_start, pixel):
        return _paths_xyz(
            kernel,
            key,
            pass_start,
            pixel,
            plan=plan,
            spp=spp,
            width=width,
            max_depth=max_depth,
            rr_depth=rr_depth,
            integrator=integrator,
            sampler=sampler,
        )

    paths = jax.shard_map(
        local,
        mesh=mesh,
        in_specs=(P(), P(), P(), P("pixels")),
        out_specs=P("pixels"),
        check_vma=False,
    )

    @functools.partial(jax.jit, donate_argnums=0)
    def step(film, kernel, key, pass_start, pixel):
        # Each device traces its share of the tile; the per-pixel sums (already weighted, one
        # entry per pixel, so the scatter has no duplicates and is deterministic everywhere)
        # are added to the film's accumulators; indices past the image are dropped.
        contrib = paths(kernel, key, pass_start, pixel)
        xyz_sum = film.xyz_sum.reshape(-1, 3).at[pixel].add(contrib[:, :3], mode="drop")
        weight_sum = film.weight_sum.reshape(-1).at[pixel].add(contrib[:, 3], mode="drop")
        return eqx.tree_at(
            lambda f: (f.xyz_sum, f.weight_sum),
            film,
            (xyz_sum.reshape(film.xyz_sum.shape), weight_sum.reshape(film.weight_sum.shape)),
        )

    if len(_STEP_CACHE) > 16:
        _STEP_CACHE.clear()
    _STEP_CACHE[cache_key] = step
    return step


def _progress_bar(progress: bool, total: int):
    if not progress:
        return None
    import sys

    from tqdm import tqdm

    return tqdm(total=total, desc="render", unit="path", unit_scale=True, file=sys.stderr)
