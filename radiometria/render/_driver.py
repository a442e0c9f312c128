r"""The render driver: batches of camera paths, spread over devices, into a film.

`render` estimates the filtered spectral radiance of every pixel (thesis section 2.3.2) and
converts it to linear sRGB:

1. **Work layout.** The image's $P = W H$ pixels are cut into tiles of `t` pixels; one *step*
   traces `k` samples (passes) of every pixel of one tile, `n = t k` paths at once, so memory
   is bounded by the batch, never by $W H \cdot \mathrm{spp}$. The film's memory is checked
   against the available memory before anything is allocated. `k` does not depend on spp
   (passes past spp are inactive paths, which cost nothing), so one compiled step serves any
   sample count.
2. **Samples.** Pass `s` of pixel `p` draws its variates from the sampler plugin
   (`AbstractSampler`: independent or padded Owen-scrambled Sobol); they depend only on
   `(seed, s, p)`, so the image depends neither on the batching nor on the number of
   devices. The film position is uniform in the pixel (splatting) or the pixel centre plus
   an offset drawn from the filter (filter importance sampling); four hero wavelengths come
   from `sample_hero_wavelengths`.
3. **Integrator.** The integrator plugin (`AbstractIntegrator`: `Path`, `Direct`) gives
   $L(\lambda_i)$, drawing its variates from the sampler.
4. **Film.** `radiometria.camera.film_samples_to_XYZ` turns the four radiances into one XYZ
   estimate, $\frac14\sum_i L(\lambda_i)\bar{\mathbf{x}}(\lambda_i)/p(\lambda_i)/\int\bar y$
   (a constant spectrum $L$ gives $Y = L$; the D65 white of $Y = 1$ gives linear sRGB
   (1, 1, 1), as in Mitsuba and PBRT). Samples are splatted into every pixel within the filter
   radius with weight $f$ (eq. 2.34, Mitsuba's `hdrfilm`) or added to their own pixel with
   weight $f/p$ (eq. 2.35, pbrt-v4): each pixel's samples are first reduced to one
   footprint per pixel, then scatter-added into the film (`radiometria.camera.Film`), which
   divides the weighted sums at the end (`film_develop`) and converts XYZ to linear sRGB.

**Devices.** The pixel axis of every step is sharded over a 1-D mesh of the local devices
(`jax.shard_map`): each device traces its share of the tile, with no communication; the
samples are then added into the film's accumulators (a gather across the devices). On several
hosts, call `jax.distributed.initialize(coordinator_address, num_processes, process_id)` on
every host before rendering (on CPUs also
`jax.config.update("jax_cpu_collectives_implementation", "gloo")`) and run the same
`render` call everywhere: process `i` of `m` renders the steps `i, i + m, i + 2m, ...` on its
own devices, and the films' sums are added across processes with
`jax.experimental.multihost_utils.process_allgather`, so every process returns the whole
image (tested with two CPU processes in `tests/render/test_driver.py`). For a given seed and
batch size the image is the same on any number of devices or hosts, up to float rounding of
the sums (on GPUs, splatting's scatter-add uses atomics, so the last bits may vary unless
XLA's deterministic ops are enabled).
"""

import functools
import math
import os
import sys
import time
from dataclasses import dataclass

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.experimental import multihost_utils
from jax.sharding import Mesh, NamedSharding, PartitionSpec as P
from tqdm import tqdm

from .._checks import check_choice, check_positive_int, device_array
from .._timing import mark
from .._warmstart import (
    Interrupts as _Interrupts,
    exported_caller,
    exported_step_caller,
    tile_order,
    uses_lapack,
)
from .._xla import jit_options
from ..camera import (
    AbstractCamera,
    AbstractFilter,
    Film,
    GaussianFilter,
    SpectralResponse,
    film_develop,
    film_develop_spectral,
    film_samples_to_spectral_bins,
    film_samples_to_XYZ,
    spectral_bin_centres,
)
from ._cache import checks_without_callbacks
from ._checkpoint import CheckpointError, load_checkpoint, render_identity, save_checkpoint
from ._geometry import _native
from ._integrators import AbstractIntegrator, Path
from ._registry import INTEGRATORS, SAMPLERS
from ._render_scene import RenderScene
from ._samplers import AbstractSampler, Independent, sampler_seed
from ._scenes import (
    SceneDescription,
    compile_scene_cached,
    load_scene,
    scene_integrator,
    scene_sampler,
)
from ._spectral import sample_hero_wavelengths

__all__ = ["RECONSTRUCTIONS", "RenderInterrupted", "render"]


RECONSTRUCTIONS = ("splat", "importance")
CAMERA_DIMENSIONS = 4  # [film x, film y, wavelength, unused]: keeps the bounce pairs aligned
_MAX_PIXELS = 2**31 - 2**20  # pixel indices are int32
_FILM_BYTES_PER_PIXEL = 4 * 4 * 3  # float32 sums (H, W, 4), the developed image, a host copy


def _camera_dimensions(camera: AbstractCamera) -> int:
    """Sampler dimensions of the camera: 4, and 4 more ([aperture u, aperture v, unused,
    unused], a stratified pair) for a camera with a lens; the integrator's follow."""
    extra = int(getattr(camera, "APERTURE_VARIATES", 0))
    return CAMERA_DIMENSIONS + 4 * -(-extra // 4)


def _read_int(path: str) -> int | None:
    try:
        with open(path) as f:
            text = f.read().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None  # cgroup v2 writes "max" for no limit


def _available_host_memory() -> int:
    """Bytes of host memory a render may still allocate: Linux's `MemAvailable` (free memory
    plus reclaimable caches; `SC_AVPHYS_PAGES`, the free pages only, where it is missing),
    within the process's cgroup (container) limit; 8 GiB when neither is known."""
    available = None
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    available = int(line.split()[1]) * 1024  # kB
                    break
    except (OSError, ValueError, IndexError):
        pass
    if available is None:
        try:
            available = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (ValueError, OSError, AttributeError):
            available = 8 * 2**30
    limit = _read_int("/sys/fs/cgroup/memory.max")
    if limit is not None:
        used = _read_int("/sys/fs/cgroup/memory.current") or 0
        available = min(available, max(limit - used, 0))
    return available


_PATH_BYTES = 4 * 512  # generous: a path's state, variates, footprint and temporaries (float32)


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
    """Tiles of pixels x passes per step for `spp` samples of `n_pixels` pixels."""
    # Tiles are multiples of 128 pixels where possible (so 1, 2, 4, ..., 128 devices share
    # one layout: the same steps of the same pixels and passes, images equal to float
    # rounding), and of the device count in any case.
    quantum = math.lcm(128, n_devices) if n_pixels >= 128 else n_devices
    tile = min(batch, n_pixels)
    tile = max(quantum, -(-tile // quantum) * quantum)
    # The passes per step do not depend on spp, so one compiled step serves every sample
    # count; passes past spp are inactive paths, which the integrator does not trace.
    passes = max(1, batch // tile)
    return _Plan(n_pixels, tile, passes, -(-n_pixels // tile), -(-spp // passes))


class _Kernel(eqx.Module):
    """Everything the paths of a step read (one pytree, replicated over the devices)."""

    scene: RenderScene
    camera: AbstractCamera
    rfilter: AbstractFilter
    response: SpectralResponse  # the film's colour-matching functions
    integrator: AbstractIntegrator
    sampler: AbstractSampler


@dataclass(frozen=True)
class _Config:
    """The static configuration of a render: it fixes the compiled step."""

    n_pixels: int
    tile: int  # pixels per step
    passes: int  # samples per pixel per step
    width: int
    reconstruction: str
    devices: tuple
    spectral_bins: int = 0  # 0: an XYZ film only


_UNROLLED_PASSES = 64
"""Up to this many passes per step, a step's filter footprints are summed over the passes as
an unrolled sum of elementwise products (one fused loop over the pixels with no reduction in
it) rather than a `dot_general`. Measured on XLA:CPU (2 cores, 5 x 5 footprints, 4 channels)
for pixels x passes 32768 x 2, 8192 x 8, 4096 x 16, 1024 x 64: 0.66, 0.66, 0.88, 0.74 ms
against the dot's 9.2, 2.0, 1.5, 1.1 ms and a fused `jnp.sum` over the passes' axis's 13.1,
7.8, 6.8, 6.2 ms (XLA:CPU's reduction loop inside a fusion does not vectorise; in a profile
of a 128 x 128 render of the textured benchmark scene it held 11 % of the time). Past 64
passes the program grows with the passes, and the dot is used."""


def _footprint_radius(cfg: _Config, rfilter) -> int:
    """Pixels a sample reaches on each side of its own: 0 for filter importance sampling;
    for splatting, every d with |d| < r + 1/2 (a sample lies inside its pixel)."""
    if cfg.reconstruction == "importance":
        return 0
    return max(math.ceil(float(rfilter.radius) + 0.5) - 1, 0)


def _trace(kernel: _Kernel, key, spp, pass_start, pixel, *, cfg: _Config):
    """Trace the step's paths of (a device's share of) a tile of pixels, and reduce them to
    per-pixel footprints.

    Returns `(t, F, F, 4)` sums over the step's `k` passes of each pixel: entry `[p, j, i]`
    is what pixel `p`'s samples add to the pixel at offset `(i - R, j - R)` from it, as
    `[w X, w Y, w Z, w]` with `w` the filter weight (F = 2R + 1; R = 0 for filter importance
    sampling, whose samples stay in their pixel). The filters are separable, so a sample's
    weights are an outer product of two 1D rows, and the sum over a pixel's samples is one
    small contraction: the scatter into the film then has `t F^2` entries, not `t k F^2`.
    """
    dtype = jnp.float32
    t, k = pixel.shape[0], cfg.passes
    valid_pixel = pixel < cfg.n_pixels
    pix = jnp.repeat(jnp.where(valid_pixel, pixel, 0), k)  # (n,): pixel-major
    passes = jnp.tile(pass_start + jnp.arange(k, dtype=jnp.int32), t)
    seed = sampler_seed(key)
    sample = functools.partial(kernel.sampler.sample, seed, dtype=dtype)
    camera_dims = _camera_dimensions(kernel.camera)
    u = sample(pix, passes, 0, camera_dims)

    def variates(first, n_dims, paths):
        # the integrator's dimensions follow the camera's
        paths = jnp.minimum(paths, t * k - 1)
        return sample(pix[paths], passes[paths], camera_dims + first, n_dims)

    corner = jnp.stack([pix % cfg.width, pix // cfg.width], axis=-1).astype(dtype)
    if cfg.reconstruction == "importance":
        # Filter importance sampling (thesis eq. 2.35): offset ~ |f|, weight f / p.
        offset, weight = kernel.rfilter.sample(u[:, 0:2])
        raster = corner + 0.5 + offset.astype(dtype)
    else:
        # Splatting (eq. 2.34): uniform positions in the pixel, filter weights below.
        raster = corner + u[:, 0:2]
        weight = jnp.ones((t * k,), dtype)
    n_aperture = int(getattr(kernel.camera, "APERTURE_VARIATES", 0))
    aperture = u[:, CAMERA_DIMENSIONS : CAMERA_DIMENSIONS + n_aperture] if n_aperture else None
    origins, directions = kernel.camera.sample_ray(raster, aperture)
    wavelength_nm, pdf = sample_hero_wavelengths(u[:, 2])
    active = jnp.repeat(valid_pixel, k) & (passes < spp)
    if _splats_only(kernel.integrator):
        return _trace_splats(kernel, pix, wavelength_nm, pdf, variates, active, cfg=cfg)
    bidirectional = _bidirectional(kernel.integrator)
    if bidirectional:  # camera-ray radiance and light-path splats from the same paths (`BDPT`)
        radiance, sp = kernel.integrator.radiance_and_splats(
            kernel.scene,
            kernel.camera,
            origins.astype(dtype),
            directions.astype(dtype),
            wavelength_nm.astype(dtype),
            variates,
            active,
        )
    else:
        radiance = kernel.integrator.radiance(
            kernel.scene,
            origins.astype(dtype),
            directions.astype(dtype),
            wavelength_nm.astype(dtype),
            variates,
            active,
        )
    xyz = film_samples_to_XYZ(kernel.response, radiance, wavelength_nm, pdf)
    ok = active & jnp.all(jnp.isfinite(xyz), axis=-1)
    if cfg.spectral_bins:  # the spectral film's bins travel after [wX, wY, wZ, w]
        bins = film_samples_to_spectral_bins(radiance, wavelength_nm, pdf, cfg.spectral_bins)
        ok = ok & jnp.all(jnp.isfinite(bins), axis=-1)
        xyz = jnp.concatenate([xyz, bins.astype(dtype)], axis=-1)
    w = jnp.where(ok, weight.astype(dtype), 0.0)
    values = jnp.concatenate([jnp.where(ok[:, None], xyz, 0.0) * w[:, None], w[:, None]], axis=-1)
    if cfg.spectral_bins:  # [wX, wY, wZ, w, w L_1, ..., w L_n]
        values = jnp.concatenate([values[:, :3], values[:, -1:], values[:, 3:-1]], axis=-1)
    channels = values.shape[-1]
    values = values.reshape(t, k, channels)
    radius = _footprint_radius(cfg, kernel.rfilter)
    if radius == 0:
        footprints = jnp.sum(values, axis=1).reshape(t, 1, 1, channels)
    else:
        d = jnp.arange(-radius, radius + 1, dtype=dtype)
        # Offset of each footprint pixel's centre from the sample: f1(c - x) per axis, laid
        # out (2, F, n) with the paths last: XLA:CPU vectorises along the minor axis, and the
        # filter's exponentials on (n, F, 2) measured 63 ns per path against 8 ns (Gaussian,
        # 65536 paths, F = 5).
        to_centre = (corner + 0.5 - raster).T[:, None, :] + d[None, :, None]  # (2, F, n)
        f1 = kernel.rfilter.evaluate_1d(to_centre).astype(dtype)
        fx, fy = (jnp.moveaxis(f1[a], 0, -1).reshape(t, k, 2 * radius + 1) for a in (0, 1))
        if k <= _UNROLLED_PASSES:  # one fused elementwise loop (`_UNROLLED_PASSES`)
            footprints = sum(
                fy[:, i, :, None, None] * fx[:, i, None, :, None] * values[:, i, None, None, :]
                for i in range(k)
            )
        else:
            footprints = jnp.einsum("tkj,tki,tkc->tjic", fy, fx, values)
    if not bidirectional:
        return footprints
    # Camera-ray and splat estimates share one normalisation: with splatting reconstruction
    # the pixel's weight is the filter's film integral F_j per slot (pbrt's 1/spp splat scale;
    # the camera part is then the unbiased filtered estimate sum f L / (spp F_j)); with filter
    # importance sampling the usual weights (whose expectation per slot is F_j) are kept.
    sp_footprints, sp_raster, sp_xyz = _splats_to_xyz(
        kernel, sp, pix, wavelength_nm, pdf, active, cfg=cfg
    )
    if cfg.reconstruction != "importance":
        footprints = footprints.at[..., 3].set(0.0)
        footprints = footprints.at[:, radius, radius, 3].set(sp_footprints[:, 0, 0, 3])
    return footprints, sp_raster, sp_xyz


def _splats_only(integrator) -> bool:
    """The integrator estimates nothing per camera ray and splats everything (`PTracer`)."""
    return bool(getattr(integrator, "SPLATS_ONLY", False))


def _bidirectional(integrator) -> bool:
    """The integrator estimates radiance per camera ray and splats light-path vertices too
    (`BDPT`: its `radiance_and_splats`)."""
    return bool(getattr(integrator, "BIDIRECTIONAL", False))


def _film_filter_integral(rfilter, centre, size: int):
    r"""$\int_0^{size} f_1(x - c)\,dx$ for pixel centres `c` [px]: the 1D filter's integral
    over the film (midpoint rule on 512 cells; exact for the box filter)."""
    r = float(rfilter.radius)
    cells = 512
    h = 2.0 * r / cells
    x = -r + h * (jnp.arange(cells, dtype=centre.dtype) + 0.5)
    fx = rfilter.evaluate_1d(x).astype(centre.dtype) * h
    pos = centre[:, None] + x[None, :]
    inside = (pos >= 0) & (pos < size)
    return jnp.sum(jnp.where(inside, fx[None, :], 0.0), axis=-1)


def _trace_splats(kernel: _Kernel, pix, wavelength_nm, pdf, variates, active, *, cfg: _Config):
    r"""A splatting integrator's part of a step (`PTracer`): one light path per (pixel, pass)
    slot, its vertices' splats as XYZ, and per pixel the weight $F_j$ per active slot, so that
    the film's division by its weight sums gives pbrt's $1/\mathrm{spp}$ splat scale over the
    filter's integral $F_j$ (`radiometria.render._integrators._ptracer`, "Normalisation").

    Returns `(footprints (t, 1, 1, 4), raster (m, 2), xyz (m, 3))`, `m` = vertices x paths.
    """
    sp = kernel.integrator.splats(
        kernel.scene, kernel.camera, wavelength_nm.astype(jnp.float32), variates, active
    )
    return _splats_to_xyz(kernel, sp, pix, wavelength_nm, pdf, active, cfg=cfg)


def _splats_to_xyz(kernel: _Kernel, sp, pix, wavelength_nm, pdf, active, *, cfg: _Config):
    """`Splats` as XYZ at their raster positions, and per pixel the weight $F_j$ per active
    slot (`_trace_splats`)."""
    dtype = jnp.float32
    t, k = pix.shape[0] // cfg.passes, cfg.passes
    xyz = film_samples_to_XYZ(kernel.response, sp.value, wavelength_nm[None], pdf[None])
    ok = sp.valid & jnp.all(jnp.isfinite(xyz), axis=-1)
    xyz = jnp.where(ok[..., None], xyz, 0.0).astype(dtype).reshape(-1, 3)
    raster = jnp.where(ok[..., None], sp.raster, -1.0).astype(dtype).reshape(-1, 2)
    height = cfg.n_pixels // cfg.width
    cx = (pix % cfg.width).astype(dtype) + 0.5
    cy = (pix // cfg.width).astype(dtype) + 0.5
    f = _film_filter_integral(kernel.rfilter, cx, cfg.width)
    f = f * _film_filter_integral(kernel.rfilter, cy, height)
    w = jnp.sum(jnp.where(active, f, 0.0).reshape(t, k), axis=1)
    footprints = jnp.zeros((t, 1, 1, 4), dtype).at[:, 0, 0, 3].set(w)
    return footprints, raster, xyz


def _add_splats(film: Film, raster, xyz, rfilter, width: int, height: int) -> Film:
    r"""Scatter-add splats `xyz (m, 3)` at raster positions `(m, 2)` [px] into the film's XYZ
    sums, each into every pixel within the filter's radius with weight $f$ (no weight sum:
    `_trace_splats` gives the normalisation). Positions outside the film are dropped. On CPUs
    the scatter-add runs in a fixed order: the image is deterministic for a seed."""
    radius = max(math.ceil(float(rfilter.radius) + 0.5) - 1, 0)
    d = jnp.arange(-radius, radius + 1, dtype=jnp.int32)
    base = jnp.floor(raster).astype(jnp.int32)  # (m, 2)
    px = base[:, None, 0] + d[None, :]  # (m, F)
    py = base[:, None, 1] + d[None, :]
    fx = rfilter.evaluate_1d(px.astype(raster.dtype) + 0.5 - raster[:, 0:1]).astype(xyz.dtype)
    fy = rfilter.evaluate_1d(py.astype(raster.dtype) + 0.5 - raster[:, 1:2]).astype(xyz.dtype)
    weight = fy[:, :, None] * fx[:, None, :]  # (m, F, F)
    inside = (
        ((px >= 0) & (px < width))[:, None, :]
        & ((py >= 0) & (py < height))[:, :, None]
        & (raster[:, 0] >= 0)[:, None, None]
    )
    idx = jnp.where(inside, py[:, :, None] * width + px[:, None, :], width * height)
    values = (weight[..., None] * xyz[:, None, None, :]).reshape(-1, 3)
    xyz_sum = film.xyz_sum.reshape(-1, 3).at[idx.reshape(-1)].add(values, mode="drop")
    return eqx.tree_at(lambda f: f.xyz_sum, film, xyz_sum.reshape(film.xyz_sum.shape))


def _add_footprints(film: Film, pixel, footprints, width: int, height: int) -> Film:
    """Scatter-add `(t, F, F, 4)` footprints of the pixels `pixel` into the film's sums
    (`(t, F, F, 4 + n)` with a spectral film's n bins after the weight)."""
    radius = (footprints.shape[1] - 1) // 2
    d = jnp.arange(-radius, radius + 1, dtype=jnp.int32)
    x = (pixel % width)[:, None, None] + d[None, None, :]
    y = (pixel // width)[:, None, None] + d[None, :, None]
    inside = (
        (x >= 0) & (x < width) & (y >= 0) & (y < height) & (pixel < width * height)[:, None, None]
    )
    idx = jnp.where(inside, y * width + x, width * height).reshape(-1)  # out of range: dropped
    return _scatter_into_film(film, idx, footprints.reshape(-1, footprints.shape[-1]))


def _scatter_into_film(film: Film, idx, values) -> Film:
    """Add `values` `(m, 4 + n)` (`[wX, wY, wZ, w]`, then a spectral film's n bins) to the
    film's pixels `idx` `(m,)` (flat; indices past the image are dropped)."""
    xyz_sum = film.xyz_sum.reshape(-1, 3).at[idx].add(values[:, :3], mode="drop")
    weight_sum = film.weight_sum.reshape(-1).at[idx].add(values[:, 3], mode="drop")
    if film.spectral_sum is not None:
        n_bins = film.spectral_sum.shape[-1]
        spectral_sum = film.spectral_sum.reshape(-1, n_bins).at[idx].add(values[:, 4:], mode="drop")
        film = eqx.tree_at(
            lambda f: f.spectral_sum, film, spectral_sum.reshape(film.spectral_sum.shape)
        )
    return eqx.tree_at(
        lambda f: (f.xyz_sum, f.weight_sum),
        film,
        (xyz_sum.reshape(film.xyz_sum.shape), weight_sum.reshape(film.weight_sum.shape)),
    )


def render(
    scene,
    *,
    spp: int | None = None,
    seed: int | None = None,
    width: int | None = None,
    height: int | None = None,
    integrator=None,  # AbstractIntegrator | None; checked below with a message for strings
    sampler=None,  # AbstractSampler | None
    batch: int | None = None,
    progress: bool = True,
    devices=None,
    camera: AbstractCamera | None = None,
    rfilter: AbstractFilter | None = None,
    reconstruction: str = "splat",
    return_xyz: bool = False,
    spectral_bins: int | None = None,
    checkpoint=None,
    checkpoint_every: float = 60.0,
    resume: bool = False,
    preview=None,
    preview_every: float = 60.0,
    _step_cache=None,
):
    r"""Render a scene spectrally into a linear sRGB image (thesis ch. 8-9; eq. 2.35).

    Strategies are objects: `render(scene, integrator=Path(max_depth=8), sampler=OwenSobol())`
    (`radiometria.render.Path`, `Direct`, `Independent`, `OwenSobol`, or any subclass of
    `AbstractIntegrator` / `AbstractSampler`; see "Extending the renderer" in the docs).

    **Arguments:**

    - `scene`: a built-in scene name (`"cornell-box"`, `"cornell-box-measured"`), a scene
        file path, a loaded scene description (`load_scene`), or a `RenderScene` together with
        `camera`.
    - `spp`: samples (camera paths) per pixel, >= 1; default: the scene file's
        `sample_count` (a `ValueError` where there is none).
    - `seed`: the seed of `jax.random.key`; the image is a deterministic function of it.
        Default: the scene file's sampler `seed`, else 0.
    - `width`, `height`: image size [px]; default: the scene's film.
    - `integrator`: an `AbstractIntegrator`; default: the one the scene file asks for (its
        `max_depth` and `rr_depth`), else `Path()` (NEE + MIS + Russian roulette, 8 segments).
    - `sampler`: an `AbstractSampler`; default: the one the scene file asks for (Mitsuba's
        `independent` is `Independent()`; `stratified`, `multijitter`, `ldsampler`, `sobol`
        are `OwenSobol()`), else `Independent()`. `OwenSobol()` (padded Owen-scrambled
        Sobol) reaches a given error sooner on the Cornell box.
    - `batch`: paths traced per step (bounds memory); default: about 2^16 per CPU device,
        2^20 per GPU, within the device memory.
    - `progress`: show a tqdm progress bar on stderr.
    - `devices`: the devices to shard the pixels over; default `jax.local_devices()`. On a
        CPU, XLA has one device unless told otherwise, and one device runs on about one core:
        set `XLA_FLAGS=--xla_force_host_platform_device_count=<cores>` before JAX is imported
        to get one device per core (2.4x faster on 2 cores; `benchmarks/bench_render.py`
        does this).
    - `camera`, `rfilter`: an `radiometria.camera.AbstractCamera` (e.g. `PinholeCamera`) and
        reconstruction filter, for a `RenderScene` (default filter: Gaussian, stddev 0.5 px,
        radius 2 px); a loaded scene has its own camera, and `rfilter` overrides its filter.
    - `reconstruction`: how samples become pixels (thesis 2.3.2): `"splat"` (default; samples
        uniform in their pixel, each added to every pixel within the filter radius with weight
        $f$, eq. 2.34, as Mitsuba's `hdrfilm`) or `"importance"` (filter importance sampling:
        offsets drawn from the filter, each sample in its own pixel with weight $f/p$, eq. 2.35,
        as pbrt-v4). Both estimate the same filtered image; splatting reuses each sample in up
        to $(2r+1)^2$ pixels, which for the Gaussian of the Cornell box divides the pixel
        variance by about $4\pi\sigma^2 \approx 3$ at the cost of correlated noise.
    - `return_xyz`: return CIE XYZ instead of linear sRGB.
    - `spectral_bins`: `None` (default) for an RGB/XYZ image only; an integer n in
        [1, 4710] for a spectral film as well: n equal bins over [360, 830] nm (47 gives the
        10 nm of the CIE's tables; `radiometria.camera.spectral_bin_centres`), each sample's
        hero wavelengths added to their bins with weight $L/(p\,\Delta)$ over the 4
        wavelengths and the same filter weights as the XYZ, so each bin is an unbiased estimate
        of the filtered, bin-averaged spectral radiance (`radiometria.camera.Film`). The render
        then returns `(image, spectral, wavelengths_nm)`; `preview` receives that tuple as its
        image. Costs n floats per pixel (checked against memory) and a footprint of n values
        per pixel in each step (the default `batch` shrinks to match); off, nothing changes.
        Not with `checkpoint` nor a splatting-only integrator (`PTracer`).
    - `checkpoint`: a file path: every `checkpoint_every` seconds [s] (and when interrupted)
        the film's sums, the steps done and the render's identity are written there
        atomically (`radiometria.render._checkpoint`). With `resume=True` the render continues
        from that file, and the image is the same, bit for bit, as an uninterrupted render
        with the same arguments; a checkpoint of another scene, spp, size, seed or version is
        refused (`CheckpointError`). Single-process renders only.
    - `preview`: a function `preview(image, spp_reached)` called with the partial image every
        `preview_every` seconds [s] (e.g. to rewrite an image file during a long render).

    Interrupts: SIGINT (Ctrl-C) and SIGTERM, when `render` runs in the main thread, stop the
    render after the step in flight, write the checkpoint (if any), and raise
    `RenderInterrupted` (a `KeyboardInterrupt`) carrying the partial image and the samples per
    pixel every pixel has reached.

    **Returns:**

    The image `(height, width, 3)` float32: linear sRGB (D65 white, no tone mapping) or XYZ,
    in the unit of the scene's radiance (a radiance spectrum $L$ gives
    $Y = \int L \bar y / \int \bar y$). With `spectral_bins=n`: `(image, spectral,
    wavelengths_nm)`, `spectral` `(height, width, n)` float32 [W m^-2 sr^-1 nm^-1 for a
    scene in those units] at the bin centres `wavelengths_nm` (n,) [nm].

    Memory stays bounded by `batch`, never by `width x height x spp`; absurd image sizes are
    refused with a `ValueError` before anything is allocated. See the module docstring for the
    sharding over devices and hosts.

    !!! note "Thesis"
        Chapters 8-9 (light transport, titles only in the text); eq. 2.35 (filter importance
        sampling and the weighted pixel estimate); section 2.2 (XYZ, sRGB).

    ??? cite "References"
        `Pharr2023` ch. 5, 8, 13; `Jakob2022`; `Wilkie2014`; `Ernst2006` (filter importance
        sampling).
    """
    _check_plugin(integrator, "integrator", AbstractIntegrator, INTEGRATORS, "Path(max_depth=8)")
    _check_plugin(sampler, "sampler", AbstractSampler, SAMPLERS, "OwenSobol()")
    check_choice(reconstruction, "reconstruction", RECONSTRUCTIONS)
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int | np.integer)):
        raise TypeError(f"`seed` must be an int, got {type(seed).__name__} {seed!r}.")
    if spp is not None:
        spp = check_positive_int(spp, "spp")
    with checks_without_callbacks():  # the loader has checked the values (see _cache.py)
        scene, camera, rfilter, scene_integrator_, scene_sampler_, file_spp, file_seed = (
            _resolve_scene(scene, camera, rfilter, width, height)
        )
    if spp is None:
        if file_spp is None:
            raise ValueError(
                "`spp` is required: the scene names no sampler `sample_count` (samples per "
                "pixel, >= 1)."
            )
        spp = file_spp
    seed = (0 if file_seed is None else file_seed) if seed is None else seed
    integrator = scene_integrator_ if integrator is None else integrator
    sampler = scene_sampler_ if sampler is None else sampler
    if getattr(integrator, "MARKOV_CHAINS", False):  # `PSSMLT`: chains, not independent steps
        _check_markov_chain_options(integrator, locals())
        batch = _default_batch(list(jax.local_devices())) if batch is None else batch
        return integrator.render_chains(
            scene, camera, spp=spp, seed=seed, batch=check_positive_int(batch, "batch"),
            return_xyz=return_xyz,
        )  # fmt: skip
    n_bins = _check_spectral_bins(spectral_bins, integrator, checkpoint)
    width, height = int(camera.width), int(camera.height)
    n_pixels = width * height
    if n_pixels > _MAX_PIXELS:
        raise ValueError(
            f"Image of {width} x {height} = {n_pixels} pixels is too large; at most {_MAX_PIXELS}."
        )
    devices = list(jax.local_devices() if devices is None else devices)
    if not devices:
        raise ValueError("`devices` must name at least one device.")
    if batch is None:
        batch = _default_batch(devices)
        if n_bins:  # a step's footprints hold n more values per pixel and filter offset
            footprint = 2 * _footprint_radius(_Config(1, 1, 1, 1, reconstruction, ()), rfilter) + 1
            per_path = _PATH_BYTES + 4 * n_bins * (footprint**2 + 4)
            batch = max(len(devices), batch * _PATH_BYTES // per_path)
    else:
        batch = check_positive_int(batch, "batch")
    per_pixel = _FILM_BYTES_PER_PIXEL + 4 * 3 * n_bins
    film_bytes = n_pixels * per_pixel
    available = _available_host_memory()
    if film_bytes > available // 2:
        raise ValueError(
            f"A {width} x {height} film needs about {film_bytes / 2**30:.1f} GiB of memory "
            f"({per_pixel} bytes per pixel"
            + (f", {n_bins} spectral bins" if n_bins else "")
            + f"), more than half of the {available / 2**30:.1f} GiB available; render a "
            "smaller image" + (" or use fewer spectral bins." if n_bins else ".")
        )
    plan = _plan(n_pixels, spp, batch, len(devices))
    response = SpectralResponse.from_observer(dtype=jnp.float32)
    kernel = _Kernel(scene, camera, rfilter, response, integrator, sampler)
    cfg = _Config(n_pixels, plan.tile, plan.passes, width, reconstruction, tuple(devices), n_bins)
    key = jax.random.key(int(seed))
    spp_arr = device_array(np.int32(spp))
    # The film lives where the step leaves it (replicated over the mesh), so that the first
    # step and the later ones share one compiled program (an uncommitted first film would be
    # a different jit signature and compile the step twice).
    mesh = Mesh(np.asarray(cfg.devices), ("pixels",))
    film = Film(width, height, dtype=jnp.float32, spectral_bins=n_bins or None)
    film = jax.device_put(film, NamedSharding(mesh, P()))

    # Multi-host: process i of m takes steps i, i + m, ...; the films are summed at the end.
    n_proc, proc = jax.process_count(), jax.process_index()
    identity, start = None, 0
    if checkpoint is not None:
        if n_proc > 1:
            raise ValueError("`checkpoint` supports single-process renders only.")
        identity = render_identity(
            kernel, seed=seed, spp=spp, width=width, height=height, layout=_layout(plan, cfg)
        )
        if resume:
            xyz, w, start = load_checkpoint(checkpoint, identity)
            if start > plan.n_steps:
                raise CheckpointError(f"{checkpoint}: {start} steps done of {plan.n_steps}.")
            film = eqx.tree_at(
                lambda f: (f.xyz_sum, f.weight_sum),
                film,
                tuple(jax.device_put(x, NamedSharding(mesh, P())) for x in (xyz, w)),
            )
    elif resume:
        raise ValueError("`resume=True` needs `checkpoint`, the file to resume from.")
    step, develop = _step_program(devices[0].platform), _develop
    if _step_cache is not None and n_proc == 1 and not n_bins:  # the command line's warm start
        step, develop = _exported_step(_step_cache, kernel, cfg, plan, film, key, return_xyz)
    steps = range(proc + start, plan.n_steps, n_proc)
    bar = _progress_bar(progress, total=n_pixels * spp if n_proc == 1 else None)
    if bar is not None and start:
        bar.update(sum(_paths_of_step(plan, i, spp) for i in range(start)))
    # Several XLA:CPU host devices: wait for each step before dispatching the next. Queued
    # multi-device steps can occupy every thread of the small CPU thread pool at a cross-device
    # rendezvous while the other device's part waits for a thread, which deadlocked on 2 cores.
    serialise = len(devices) > 1 and devices[0].platform == "cpu"
    now = time.monotonic()
    last_checkpoint = last_preview = now
    done = start
    with _Interrupts() as interrupts:
        for i in steps:
            group, tile = divmod(i, plan.n_tiles)
            # Host indices: no device program per step to make them.
            pixel = tile_order(plan.tile, len(devices)) + np.int32(tile * plan.tile)
            # No host callbacks in the step: it stays cacheable on disk (`_cache.py`).
            with checks_without_callbacks():
                film = step(
                    film, kernel, key, spp_arr, jnp.int32(group * plan.passes), pixel, cfg=cfg
                )
            if i == steps[0]:
                mark("first step dispatched")  # `radiometria --timing`
            if serialise or checkpoint is not None or preview is not None:
                film = jax.block_until_ready(film)
            done = i + 1
            if bar is not None:  # the step's paths: its pixels in the image x passes below spp
                bar.update(_paths_of_step(plan, i, spp))
            now = time.monotonic()
            stop = interrupts.received is not None
            if checkpoint is not None and (stop or now - last_checkpoint >= checkpoint_every):
                if done < plan.n_steps:
                    save_checkpoint(checkpoint, film.xyz_sum, film.weight_sum, done, identity)
                last_checkpoint = now
            if preview is not None and not stop and now - last_preview >= preview_every:
                preview(_result(film, return_xyz), _spp_reached(plan, done, spp))
                last_preview = now
            if stop:
                break
    if bar is not None:
        bar.close()
    if interrupts.received is not None and done < plan.n_steps:
        image = _result(film, return_xyz)
        raise RenderInterrupted(
            interrupts.received, image, _spp_reached(plan, done, spp), checkpoint
        )
    if n_proc > 1:
        parts = multihost_utils.process_allgather((film.xyz_sum, film.weight_sum))
        film = eqx.tree_at(
            lambda f: (f.xyz_sum, f.weight_sum), film, tuple(jnp.sum(p, axis=0) for p in parts)
        )
        if n_bins:
            part = multihost_utils.process_allgather(film.spectral_sum)
            film = eqx.tree_at(lambda f: f.spectral_sum, film, jnp.sum(part, axis=0))
    if n_bins:
        return _result(film, return_xyz)
    return develop(film, "XYZ" if return_xyz else "sRGB")


def _result(film: Film, return_xyz: bool):
    """What `render` returns for the film so far: the image, and with a spectral film the
    tuple `(image, spectral, wavelengths_nm)` (NumPy arrays)."""
    image = np.asarray(_develop(film, "XYZ" if return_xyz else "sRGB"))
    if film.spectral_sum is None:
        return image
    spectral = np.asarray(_develop_spectral(film))
    return image, spectral, spectral_bin_centres(film.spectral_bins)


MAX_SPECTRAL_BINS = 4710  # 0.1 nm bins: finer than any renderer's spectral detail


def _check_spectral_bins(spectral_bins, integrator, checkpoint) -> int:
    """`spectral_bins` as an int (0 for none); refused where the film cannot keep them."""
    if spectral_bins is None:
        return 0
    if isinstance(spectral_bins, bool) or not isinstance(spectral_bins, int | np.integer):
        raise TypeError(
            f"`spectral_bins` must be None or an int in [1, {MAX_SPECTRAL_BINS}], got "
            f"{type(spectral_bins).__name__} {spectral_bins!r}."
        )
    if not 1 <= spectral_bins <= MAX_SPECTRAL_BINS:
        raise ValueError(
            f"`spectral_bins` must be in [1, {MAX_SPECTRAL_BINS}] (bins over [360, 830] nm), "
            f"got {spectral_bins}."
        )
    if _splats_only(integrator) or _bidirectional(integrator):
        raise ValueError(
            f"`spectral_bins` is not supported with the splatting integrator "
            f"{type(integrator).__name__}; use an RGB render or another integrator."
        )
    if checkpoint is not None:
        raise ValueError(
            "`spectral_bins` cannot be combined with `checkpoint` (checkpoints hold the XYZ "
            "film only); render without a checkpoint."
        )
    return int(spectral_bins)


def _check_markov_chain_options(integrator, options: dict) -> None:
    """A Markov-chain integrator (`PSSMLT`) renders its own film in one program: the step
    loop's options that would change the image are refused (`checkpoint` and `preview` are
    not written: there is no step to save or show)."""
    unsupported = {
        "resume": False, "spectral_bins": None, "devices": None, "reconstruction": "splat",
    }  # fmt: skip
    for name, default in unsupported.items():
        if options[name] != default:
            raise ValueError(
                f"`{name}`={options[name]!r} is not supported with {type(integrator).__name__} "
                "(its Markov chains render their own box-filtered film); leave it out."
            )


class RenderInterrupted(KeyboardInterrupt):
    """A render stopped by SIGINT or SIGTERM after a completed step (thesis ch. 8: long renders).

    **Attributes:**

    - `signal_name`: `"SIGINT"` or `"SIGTERM"`.
    - `image`: the partial image `(H, W, 3)`, as `render` would return it, with each pixel's
        samples so far. [radiance-like]
    - `spp_reached`: samples per pixel that every pixel has reached. [1]
    - `checkpoint`: the checkpoint written, or `None`.
    """

    def __init__(self, signal_name: str, image, spp_reached: int, checkpoint):
        super().__init__(f"render interrupted by {signal_name} at {spp_reached} spp")
        self.signal_name, self.image = signal_name, image
        self.spp_reached, self.checkpoint = spp_reached, checkpoint


def _layout(plan: _Plan, cfg: _Config) -> tuple[int, ...]:
    """The step layout a checkpoint's step count refers to."""
    recon = RECONSTRUCTIONS.index(cfg.reconstruction)
    return (plan.tile, plan.passes, plan.n_tiles, plan.n_groups, recon)


def _paths_of_step(plan: _Plan, i: int, spp: int) -> int:
    """Paths traced by step `i`: its pixels in the image x its passes below spp."""
    group, tile = divmod(i, plan.n_tiles)
    pixels = min(plan.tile, plan.n_pixels - tile * plan.tile)
    return pixels * max(0, min(plan.passes, spp - group * plan.passes))


def _spp_reached(plan: _Plan, steps_done: int, spp: int) -> int:
    """Samples per pixel every pixel has after `steps_done` steps (whole pass groups)."""
    return min(spp, (steps_done // plan.n_tiles) * plan.passes)


def _check_plugin(value, name: str, base: type, registry: dict, example: str) -> None:
    """A strategy must be an object (`None` for the default); strings name plugins only in
    scene files and on the command line."""
    if value is None or isinstance(value, base):
        return
    hint = ""
    if isinstance(value, str):
        known = {k: v.__name__ for k, v in registry.items()}
        cls = known.get(value)
        hint = (
            f" Pass an object, e.g. {cls}()"
            if cls
            else f" Known names (for scene files and the command line): {known}."
        )
    raise TypeError(
        f"`{name}` must be a {base.__name__} such as {example}, got "
        f"{type(value).__name__} {value!r}.{hint}"
    )


def _resolve_scene(scene, camera, rfilter, width, height):
    """(RenderScene, camera, filter, default integrator, default sampler, the file's spp, the
    file's seed) from what `render` got."""
    if isinstance(scene, str | os.PathLike):
        scene = load_scene(scene)
    if isinstance(scene, SceneDescription):
        if camera is not None:
            raise ValueError("`camera` is for a RenderScene; a loaded scene has its own camera.")
        rs, cam, filt = compile_scene_cached(scene, width=width, height=height)
        filt = filt if rfilter is None else rfilter
        return rs, cam, filt, scene_integrator(scene), scene_sampler(scene), scene.spp, scene.seed
    if isinstance(scene, RenderScene):
        if camera is None:
            raise ValueError("Rendering a `RenderScene` needs `camera` (an AbstractCamera).")
        if not isinstance(camera, AbstractCamera):
            raise TypeError(f"`camera` must be an AbstractCamera, got {type(camera).__name__}.")
        for name, value, have in (
            ("width", width, camera.width),
            ("height", height, camera.height),
        ):
            if value is not None and value != have:
                raise ValueError(
                    f"`{name}`={value} differs from the camera's {have} [px]; build the camera "
                    "with the image size you want."
                )
        filt = GaussianFilter() if rfilter is None else rfilter
        return scene, camera, filt, Path(), Independent(), None, None
    raise TypeError(
        f"`scene` must be a scene name, a path, a loaded scene or a RenderScene, got "
        f"{type(scene).__name__}."
    )


def _default_batch(devices) -> int:
    """Paths per step: about 2^16 per CPU device, 2^20 per accelerator, within memory."""
    if devices[0].platform == "cpu":
        budget = min(2**30, _available_host_memory() // 4)
        target = 2**16
    else:
        stats = devices[0].memory_stats() or {}
        budget = int(stats.get("bytes_limit", 8 * 2**30)) // 4
        target = 2**20
    per_device = max(1024, min(target, budget // _PATH_BYTES))
    return per_device * len(devices)


def _program(fun, platform: str, **jit_kw):
    """`fun` under `jax.jit(**jit_kw)` with the renderer's XLA options for `platform`
    (`radiometria._xla`), made once per function and platform, so that JAX's jit cache compiles
    it once per static configuration."""
    key = (fun, platform)
    if key not in _PROGRAMS:
        _PROGRAMS[key] = jax.jit(fun, **jit_kw, **jit_options(platform))
    return _PROGRAMS[key]


_PROGRAMS: dict = {}


def _step_program(platform: str):
    """`_step` compiled for `platform` (`_program`), donating the film."""
    return _program(_step, platform, static_argnames="cfg", donate_argnums=0)


def _develop(film: Film, space: str):
    """`film_develop` as one compiled program (op by op, each of its operations would
    compile), on the film's platform."""
    return _program(film_develop, _platform(film), static_argnums=1)(film, space)


def _develop_spectral(film: Film):
    """`film_develop_spectral` as one compiled program, on the film's platform."""
    return _program(film_develop_spectral, _platform(film))(film)


def _platform(film: Film) -> str:
    return next(iter(film.xyz_sum.devices())).platform


def _step(film, kernel, key, spp, pass_start, pixel, *, cfg: _Config):
    """One step `(film, kernel, key, spp, pass_start, pixel) -> film` (under `jax.jit`:
    `_step_program`).

    The paths are traced under `jax.shard_map` over a 1-D mesh of `cfg.devices`, each device
    taking its share of the tile's pixels (`tile_order`); each device adds its pixels' filter
    footprints into a band of the film around the tile (`_band`), the bands are summed over
    the devices, and the sum is added to the film (replicated accumulators). Splatting
    integrators (`PTracer`, `BDPT`) gather their splats and footprints from the devices and
    scatter them into the film.
    """
    splats = _splats_only(kernel.integrator) or _bidirectional(kernel.integrator)
    mesh = Mesh(np.asarray(cfg.devices), ("pixels",))
    in_specs = (P(), P(), P(), P(), P("pixels"))
    if not splats:  # each device's footprints as a band of the film, summed over the devices

        def trace_band(kernel, key, spp, pass_start, pixel):
            footprints = _trace(kernel, key, spp, pass_start, pixel, cfg=cfg)
            return jax.lax.psum(_band(footprints, pixel, cfg), "pixels")

        band = jax.shard_map(
            trace_band, mesh=mesh, in_specs=in_specs, out_specs=P(), check_vma=False
        )(kernel, key, spp, pass_start, pixel)
        return _add_band(film, pixel[0], band, cfg, _footprint_radius(cfg, kernel.rfilter))
    trace = jax.shard_map(
        functools.partial(_trace, cfg=cfg),
        mesh=mesh,
        in_specs=in_specs,
        out_specs=(P("pixels"),) * 3,
        check_vma=False,
    )
    # The devices' splats in device order, then the per-pixel weights.
    footprints, raster, xyz = trace(kernel, key, spp, pass_start, pixel)
    film = _add_splats(film, raster, xyz, kernel.rfilter, cfg.width, film.height)
    return _add_footprints(film, pixel, footprints, cfg.width, film.height)


def _band_halo(cfg: _Config, radius: int) -> int:
    """Film pixels a band reaches before (and after) its tile: `radius` rows and pixels."""
    return radius * cfg.width + radius


def _band(footprints, pixel, cfg: _Config):
    """One device's `(t, F, F, C)` footprints as a band of the film, `(L, C)`: slot `q` is
    the film's pixel `p0 - halo + q`, with `p0` the tile's first pixel and `halo =
    _band_halo(cfg, R)` (F = 2R + 1).

    The device's pixels are `p0 + d + n m` (`tile_order`: device `d` of `n`, m = 0 .. t - 1),
    so the footprint entry `(j, i)` of every pixel lands at slot `n m + d + j W + i`: for each
    of the F^2 offsets, one dense add into the band viewed as `(L / n, n, C)` (a column of n,
    at a row offset the same for all pixels), instead of a scatter of `t F^2` entries (which
    on XLA:CPU took more time than the footprints themselves). Entries that would wrap past a
    row's end, and those of pixels past the image, are zero."""
    t, f, _, c = footprints.shape
    radius, n, w = (f - 1) // 2, len(cfg.devices), cfg.width
    rows = -(-(cfg.tile + 2 * _band_halo(cfg, radius)) // n)
    first = pixel[0]
    d = first % cfg.tile  # the device's index: its first pixel is p0 + d
    x = pixel % w
    valid = pixel < cfg.n_pixels
    band = jnp.zeros((rows, n, c), footprints.dtype)
    for j in range(f):
        for i in range(f):
            inside = valid & (x + (i - radius) >= 0) & (x + (i - radius) < w)
            plane = jnp.where(inside[:, None], footprints[:, j, i], 0.0)[:, None, :]
            o = d + j * w + i
            start = (o // n, o % n, jnp.zeros_like(o))
            here = jax.lax.dynamic_slice(band, start, (t, 1, c))
            band = jax.lax.dynamic_update_slice(band, here + plane, start)
    return band.reshape(rows * n, c)


def _add_band(film: Film, first, band, cfg: _Config, radius: int) -> Film:
    """Add a step's band `(L, C)` (`_band`, summed over the devices; footprints of radius
    `radius`) into the film's sums: slot `q` to pixel `first - halo + q`, slots outside the
    image dropped."""
    n_film = film.width * film.height
    halo = _band_halo(cfg, radius)
    idx = first - halo + jnp.arange(band.shape[0], dtype=jnp.int32)
    idx = jnp.where((idx >= 0) & (idx < n_film), idx, n_film)  # out of range: dropped
    return _scatter_into_film(film, idx, band)


def _exported_step(save, kernel: _Kernel, cfg: _Config, plan: _Plan, film: Film, key, xyz: bool):
    """The step and the film's development serialised with `jax.export` (the command line's
    warm start, `radiometria._warmstart`): both are exported, handed to `save(step=...,
    develop=..., kernel=..., film=..., meta=...)` and returned deserialised, as
    `(step, develop)` with the signatures of `_step` and `_develop`, so that this render and
    a later process that loads the entry run the same programs."""
    kernel_leaves, kernel_def = jax.tree_util.tree_flatten(kernel)
    film_leaves, film_def = jax.tree_util.tree_flatten(film)
    kernel_leaves = [jnp.asarray(x) for x in kernel_leaves]
    n_film, n_kernel = len(film_leaves), len(kernel_leaves)
    key_data = jax.random.key_data(key)

    def flat_step(*args):
        f = jax.tree_util.tree_unflatten(film_def, args[:n_film])
        k = jax.tree_util.tree_unflatten(kernel_def, args[n_film : n_film + n_kernel])
        kd, spp, pass_start, pixel = args[n_film + n_kernel :]
        key_ = jax.random.wrap_key_data(kd)
        out = _step(f, k, key_, spp, pass_start, pixel, cfg=cfg)
        return tuple(jax.tree_util.tree_leaves(out))

    def flat_develop(*leaves):
        space = "XYZ" if xyz else "sRGB"
        return film_develop(jax.tree_util.tree_unflatten(film_def, leaves), space)

    replicated = NamedSharding(Mesh(np.asarray(cfg.devices), ("pixels",)), P())
    pixel = jax.ShapeDtypeStruct((plan.tile,), jnp.int32)
    scalar = jax.ShapeDtypeStruct((), jnp.int32)
    film_avals = [jax.ShapeDtypeStruct(x.shape, x.dtype, sharding=replicated) for x in film_leaves]
    kernel_avals = [jax.ShapeDtypeStruct(x.shape, x.dtype) for x in kernel_leaves]
    key_aval = jax.ShapeDtypeStruct(key_data.shape, key_data.dtype)
    native = _native._load()
    targets = sorted(_native._SYMBOLS.values()) if native.ok else []
    checks = [jax.export.DisabledSafetyCheck.custom_call(t) for t in targets]
    step_jit = jax.jit(
        flat_step,
        in_shardings=(replicated,) * n_film + (None,) * (n_kernel + 4),
        out_shardings=(replicated,) * n_film,
    )
    with checks_without_callbacks():
        exported = jax.export.export(step_jit, disabled_checks=checks)(
            *film_avals, *kernel_avals, key_aval, scalar, scalar, pixel
        )
        developed = jax.export.export(
            jax.jit(flat_develop, in_shardings=(replicated,) * n_film), disabled_checks=checks
        )(*film_avals)
    module = exported.mlir_module() + developed.mlir_module()
    used = [t for t in targets if t in module]
    lapack = uses_lapack(module)
    meta = {
        "n_pixels": cfg.n_pixels,
        "tile": plan.tile,
        "passes": plan.passes,
        "n_tiles": plan.n_tiles,
        "width": cfg.width,
        "height": cfg.n_pixels // cfg.width,
        "xyz": bool(xyz),
        "lapack": lapack,
        "film_xyz_sum": next(i for i, x in enumerate(film_leaves) if x is film.xyz_sum),
        "film_weight_sum": next(i for i, x in enumerate(film_leaves) if x is film.weight_sum),
        "identity": render_identity(
            kernel, seed=0, spp=1, width=cfg.width, height=film.height, layout=_layout(plan, cfg)
        ),
        "native": {"library": native.lib._name, "targets": used} if used else None,
    }
    step_blob, develop_blob = bytes(exported.serialize()), bytes(developed.serialize())
    save(
        step=step_blob,
        develop=develop_blob,
        kernel=[np.asarray(x) for x in kernel_leaves],
        film=[np.asarray(x) for x in film_leaves],
        meta=meta,
    )
    platform = cfg.devices[0].platform
    call_step = exported_step_caller(step_blob, n_film, lapack=lapack, platform=platform)
    call_develop = exported_caller(develop_blob, lapack=lapack, platform=platform)

    def step(film, kernel, key, spp, pass_start, pixel, *, cfg):
        leaves = jax.tree_util.tree_leaves(film)
        out = call_step(*leaves, *kernel_leaves, key_data, spp, pass_start, pixel)
        return jax.tree_util.tree_unflatten(film_def, out)

    def develop(film, space):
        return call_develop(*jax.tree_util.tree_leaves(film))

    return step, develop


def _progress_bar(progress: bool, total: int | None):
    if not progress:
        return None
    return tqdm(total=total, desc="render", unit="path", unit_scale=True, file=sys.stderr)
