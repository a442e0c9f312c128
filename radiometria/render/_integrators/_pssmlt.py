r"""Primary-sample-space Metropolis light transport: the `PSSMLT` integrator (thesis ch. 9).

**Primary sample space** (`Kelemen2002`). One bidirectional sample (`BDPT`: a camera subpath,
a light subpath and every connection strategy, MIS-weighted) is a deterministic function of
a vector $u \in [0, 1)^D$ of uniform variates: the film position (here uniform over the whole
film, `u[0:2]` times the image size), the hero wavelength (`u[2]`), a lens sample if the
camera has one, then `BDPT`'s variates. Its contribution $g(u)$ is an image: the camera-ray
estimate in the pixel its film position falls in, plus the light-tracing splats ($t = 1$) in
theirs, all as CIE XYZ. With $P$ pixels the image is $I = P\,\mathbb{E}_u[g(u)]$ (the
driver's normalisation of `BDPT`, box filter). The chains target the scalar importance

$$i(u) = \sum_\text{pixels} (X + Y + Z)(g(u)),$$

the sum of the tristimulus values, not luminance $Y$ alone (pbrt's choice): it is positive
wherever $g$ is, so no colour is left out of the estimate (the colour-matching functions are
non-negative). **State of a chain: all strategies of one BDPT sample** (Kelemen's own use,
and Mitsuba's `pssmlt`), not pbrt-v3's one path length with one strategy per chain: every
chain then runs the same program (one vectorised BDPT sample per chain and mutation), needs
no per-length bootstrap, and keeps MIS's robustness inside each state.

**Algorithm** (`Veach1997` ch. 11, `Pharr2016` §16.4.5):

1. *Bootstrap*: $B$ = `bootstrap_samples` independent uniform $u_b$; the normalisation
   $c = \frac1B \sum_b i(u_b)$ (its standard error is the sample standard deviation of
   $i(u_b)$ over $\sqrt B$); each chain starts at a $u_b$ drawn with probability
   $\propto i(u_b)$ (a start from the stationary distribution, up to the bootstrap's error).
2. *Mutations*: with probability `large_step_probability` a *large step* (a fresh uniform
   $u$), else a *small step* $u_d \leftarrow u_d + \sigma \xi_d \bmod 1$ in every dimension,
   $\xi_d \sim \mathcal N(0, 1)$ (`sigma`); both are symmetric, so the Metropolis-Hastings
   acceptance is $a = \min(1, i(u')/i(u))$.
3. *Expected-value splatting* (`Veach1997` §11.5.1): each mutation deposits the current state
   with weight $(1 - a)$ and the proposal with weight $a$, each as $g / i$; then the proposal
   is accepted with probability $a$. The image is $I = P\,c\,\frac1N\sum g/i$ over all $N$
   deposits (chains x mutations per chain, each counted once).

**Vectorised.** All chains advance together: one `lax.fori_loop` over the mutations (its
trip count is a traced value, so one compiled program serves every sample count), each
iteration evaluating one BDPT sample per chain and scatter-adding both deposits into the
image; the bootstrap's batches (one sample per chain) are the loop's first iterations. The
image is a deterministic function of the seed (`jax.random.fold_in` per sample and mutation).
`sigma` and `large_step_probability` are traced values: changing them does not recompile.

**Film.** MLT splats every contribution into the pixel it lands in (the box filter): the
scene's reconstruction filter is not used (compare with `render(..., rfilter=BoxFilter())`).
The driver's independent steps cannot express a Markov chain (each step's variates are a
function of (seed, pixel, sample) and nothing carries from one step to the next), so `render`
hands the whole render to `PSSMLT.render_chains`.

**Not handled:** what `BDPT` does not (participating media).

!!! note "Thesis"
    Chapter 9 (bidirectional methods; title only in the text).

??? cite "References"
    `Kelemen2002` (primary sample space, large and small steps); `Veach1997` ch. 11
    (Metropolis light transport, §11.5.1 expected values); `Pharr2016` §16.4
    (`MLTIntegrator`: bootstrap, chains, `sigma`, `largestepprobability`).
"""

import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ...camera import Film, SpectralResponse, film_develop, film_samples_to_XYZ
from .._spectral import sample_hero_wavelengths
from ._base import AbstractIntegrator, check_path_fields, scene_flag, scene_max_depth
from ._bdpt import BDPT, HEURISTICS, bdpt_sample_dimensions

__all__ = ["PSSMLT", "pssmlt_sample_dimensions"]

_CAMERA_DIMENSIONS = 4  # [film x, film y, wavelength, unused], as the driver's
_MIN_MUTATIONS_PER_CHAIN = 32  # the default chain count leaves each chain at least this many


def _camera_dimensions(camera) -> int:
    extra = int(getattr(camera, "APERTURE_VARIATES", 0))
    return _CAMERA_DIMENSIONS + 4 * -(-extra // 4)


def pssmlt_sample_dimensions(max_depth: int, camera_dimensions: int = _CAMERA_DIMENSIONS) -> int:
    """Dimensions of a chain's state: the camera's (4, 8 with a lens) and `BDPT`'s. [1]"""
    return camera_dimensions + bdpt_sample_dimensions(max_depth)


class PSSMLT(AbstractIntegrator):
    """Primary-sample-space Metropolis light transport over bidirectional samples (module
    docstring; Mitsuba's and pbrt's `pssmlt` / `mlt`).

    **Arguments:**

    - `max_depth`: largest number of path segments (`BDPT`'s; 1 = emitters seen directly),
        a static int >= 1 (default 8).
    - `rr_depth`: segments of a subpath after which Russian roulette starts (default 5; the
        roulette's variates are part of the state, so it mutates with it).
    - `hide_emitters`: emitters seen directly are black.
    - `heuristic`: the MIS heuristic of the bidirectional strategies, `"power"` or
        `"balance"`.
    - `bootstrap_samples`: independent samples for the normalisation and the chains' starts,
        an int >= 1 (default 16384; rounded up to a multiple of the chains).
    - `chains`: Markov chains run in parallel, an int >= 1, or None (default) for as many as
        the batch holds, at most one per 32 mutations (so each chain makes at least 32).
    - `mutations_per_pixel`: mutations per pixel in all, an int >= 1, or None (default): the
        render's `spp`. Rounded up to whole mutations of every chain.
    - `sigma`: the small step's standard deviation in primary sample space, in (0, 1)
        (default 0.01, pbrt's).
    - `large_step_probability`: probability of a large step, in [0, 1] (default 0.3, pbrt's).

    Rendered through `radiometria.render.render` (which calls `render_chains`), not per ray.

    !!! note "Thesis"
        Chapter 9 (bidirectional methods; title only in the text).

    ??? cite "References"
        `Kelemen2002`; `Veach1997` ch. 11; `Pharr2016` §16.4.
    """

    NAME: ClassVar[str] = "pssmlt"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {
            "max_depth",
            "rr_depth",
            "hide_emitters",
            "heuristic",
            "bootstrap_samples",
            "chains",
            "mutations_per_pixel",
            "sigma",
            "large_step_probability",
        }
    )
    MARKOV_CHAINS: ClassVar[bool] = True  # `render` calls `render_chains`
    max_depth: int = eqx.field(static=True, default=8)
    rr_depth: int = eqx.field(static=True, default=5)
    hide_emitters: bool = eqx.field(static=True, default=False)
    heuristic: str = eqx.field(static=True, default="power")
    bootstrap_samples: int = eqx.field(static=True, default=16384)
    chains: int | None = eqx.field(static=True, default=None)
    mutations_per_pixel: int | None = eqx.field(static=True, default=None)
    sigma: float = eqx.field(static=True, default=0.01)
    large_step_probability: float = eqx.field(static=True, default=0.3)

    def __check_init__(self):
        check_path_fields(self)
        if not isinstance(self.heuristic, str) or self.heuristic not in HEURISTICS:
            raise ValueError(
                f"`heuristic` must be one of {list(HEURISTICS)}, got {self.heuristic!r}."
            )
        for name, optional in (
            ("bootstrap_samples", False),
            ("chains", True),
            ("mutations_per_pixel", True),
        ):
            value = getattr(self, name)
            if optional and value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise ValueError(
                    f"`{name}` must be an int >= 1{' or None' if optional else ''}, got {value!r}."
                )
        sigma = self.sigma
        if isinstance(sigma, bool) or not isinstance(sigma, int | float) or not 0 < sigma < 1:
            raise ValueError(f"`sigma` must be a number in (0, 1) (primary sample space), got "
                             f"{sigma!r}.")  # fmt: skip
        p = self.large_step_probability
        if isinstance(p, bool) or not isinstance(p, int | float) or not 0 <= p <= 1:
            raise ValueError(f"`large_step_probability` must be a number in [0, 1], got {p!r}.")

    @classmethod
    def from_properties(cls, params: dict, *, where: str = "scene") -> "PSSMLT":
        """From a scene file's parameters (the class's, with its defaults; `max_depth` -1 =
        unbounded, taken as `DEFAULT_UNBOUNDED_DEPTH`); errors name `where`."""
        unknown = set(params) - cls.PARAMETERS
        if unknown:
            raise ValueError(
                f"{where}: unknown pssmlt parameter(s) {sorted(unknown)}; valid: "
                f"{sorted(cls.PARAMETERS)}."
            )
        try:
            kwargs = {k: v for k, v in params.items() if k not in ("max_depth", "hide_emitters")}
            return cls(
                max_depth=scene_max_depth(params),
                hide_emitters=scene_flag(params, "hide_emitters", False, where),
                **kwargs,
            )
        except (ValueError, TypeError) as e:
            raise type(e)(f"{where}: pssmlt: {e}") from None

    def sample_dimensions(self) -> int:
        return bdpt_sample_dimensions(self.max_depth)

    def radiance(self, scene, origins, directions, wavelength_nm, variates, active):
        """Not available: a Markov chain is not a per-ray estimator; render through
        `radiometria.render.render`, which calls `render_chains`."""
        raise TypeError(
            "PSSMLT runs Markov chains over whole images: render it with "
            "radiometria.render.render (which calls PSSMLT.render_chains), not through "
            "`radiance`."
        )

    def _bdpt(self) -> BDPT:
        return BDPT(
            max_depth=self.max_depth,
            rr_depth=self.rr_depth,
            hide_emitters=self.hide_emitters,
            heuristic=self.heuristic,
        )

    def _steps(self):
        return jnp.float32(self.sigma), jnp.float32(self.large_step_probability)

    def plan(self, n_pixels: int, spp: int, batch: int) -> tuple[int, int, int]:
        """`(chains, mutations per chain, bootstrap batches)` for a render of `n_pixels`
        pixels at `spp` (used when `mutations_per_pixel` is None) with `batch` paths per step
        (the bootstrap evaluates one sample per chain at a time)."""
        total = n_pixels * (self.mutations_per_pixel or spp)
        chains = self.chains or max(1, min(batch, total // _MIN_MUTATIONS_PER_CHAIN))
        steps = -(-total // chains)
        return chains, steps, -(-self.bootstrap_samples // chains)

    def render_chains(
        self, scene, camera, *, spp: int, seed: int, batch: int, return_xyz: bool = False
    ):
        """Render `scene` (a `RenderScene`) seen by `camera` (module docstring).

        **Arguments:**

        - `scene`, `camera`: the compiled scene and its camera (with `sample_wi`).
        - `spp`: mutations per pixel when `mutations_per_pixel` is None. [1]
        - `seed`: the seed of `jax.random.key`; the image is a deterministic function of it.
        - `batch`: the most BDPT samples evaluated at once (chains, bootstrap batch).
        - `return_xyz`: return CIE XYZ instead of linear sRGB.

        **Returns:**

        The image `(height, width, 3)` float32, as `render`'s (box filter). [radiance-like]
        """
        if getattr(scene, "media", None) is not None:
            raise ValueError(
                "pssmlt does not handle participating media (the scene has media); render it "
                "with the 'volpath' integrator."
            )
        width, height = int(camera.width), int(camera.height)
        chains, steps, boot_batches = self.plan(width * height, spp, batch)
        response = SpectralResponse.from_observer(dtype=jnp.float32)
        xyz, _ = _run(
            self._bdpt(), scene, camera, response, jax.random.key(int(seed)), jnp.int32(steps),
            *self._steps(), chains=chains, boot_batches=boot_batches,
        )  # fmt: skip
        film = Film(width, height, dtype=jnp.float32)
        film = eqx.tree_at(
            lambda f: (f.xyz_sum, f.weight_sum),
            film,
            (xyz.reshape(height, width, 3), jnp.ones((height, width), jnp.float32)),
        )
        return np.asarray(film_develop(film, "XYZ" if return_xyz else "sRGB"))

    def bootstrap(self, scene, camera, *, spp: int, seed: int, batch: int):
        """The bootstrap of `render_chains` with the same arguments: `(c, standard error of
        c)`, the mean importance and its standard error (module docstring); the mean of an
        image's X + Y + Z over its pixels is $c$. [XYZ units]"""
        chains, _, boot_batches = self.plan(int(camera.width * camera.height), spp, batch)
        response = SpectralResponse.from_observer(dtype=jnp.float32)
        _, importance = _run(
            self._bdpt(), scene, camera, response, jax.random.key(int(seed)), jnp.int32(0),
            *self._steps(), chains=chains, boot_batches=boot_batches,
        )  # fmt: skip
        importance = np.asarray(importance, np.float64)
        return importance.mean(), importance.std(ddof=1) / math.sqrt(importance.size)


def _contributions(bdpt: BDPT, scene, camera, response, u):
    """One BDPT sample per row of `u (n, D)`: the film pixel (flat index, `P` = dropped) and
    XYZ of its camera estimate and splats, `(n, 1 + max_depth)` and `(n, 1 + max_depth, 3)`,
    and the importance $i(u)$ `(n,)`."""
    n = u.shape[0]
    dtype = u.dtype
    width, height = int(camera.width), int(camera.height)
    n_pix = width * height
    cam_dims = _camera_dimensions(camera)
    raster = u[:, 0:2] * jnp.asarray([[width, height]], dtype)
    n_aperture = int(getattr(camera, "APERTURE_VARIATES", 0))
    aperture = u[:, _CAMERA_DIMENSIONS : _CAMERA_DIMENSIONS + n_aperture] if n_aperture else None
    origins, directions = camera.sample_ray(raster, aperture)
    wl, pdf = sample_hero_wavelengths(u[:, 2])

    def variates(first, n_dims, paths):
        rows = u[jnp.minimum(paths, n - 1)]
        return jax.lax.dynamic_slice_in_dim(rows, cam_dims + first, n_dims, axis=1)

    radiance, sp = bdpt.radiance_and_splats(
        scene, camera, origins.astype(dtype), directions.astype(dtype), wl.astype(dtype),
        variates, jnp.ones((n,), bool),
    )  # fmt: skip
    xyz_c = film_samples_to_XYZ(response, radiance, wl, pdf)[:, None]  # (n, 1, 3)
    xyz_s = jnp.moveaxis(film_samples_to_XYZ(response, sp.value, wl[None], pdf[None]), 0, 1)
    rasters = jnp.concatenate([raster[:, None], jnp.moveaxis(sp.raster, 0, 1)], axis=1)
    valid = jnp.concatenate([jnp.ones((n, 1), bool), jnp.moveaxis(sp.valid, 0, 1)], axis=1)
    xyz = jnp.concatenate([xyz_c, xyz_s], axis=1).astype(dtype)
    px = jnp.floor(rasters).astype(jnp.int32)
    inside = valid & (px[..., 0] >= 0) & (px[..., 0] < width) & (px[..., 1] >= 0)
    inside = inside & (px[..., 1] < height) & jnp.all(jnp.isfinite(xyz), axis=-1)
    xyz = jnp.where(inside[..., None], jnp.maximum(xyz, 0.0), 0.0)
    idx = jnp.where(inside, px[..., 1] * width + px[..., 0], n_pix)
    importance = jnp.sum(xyz, axis=(1, 2))
    return idx, xyz, importance


@eqx.filter_jit
def _run(bdpt, scene, camera, response, key, steps, sigma, p_large, *, chains, boot_batches):
    """The bootstrap and `steps` mutations of every chain: the XYZ image `(P, 3)` and the
    bootstrap importances `(B,)`.

    One `lax.fori_loop` does everything, so that the program holds one copy of the BDPT
    sample: iterations `0 .. boot_batches - 1` evaluate bootstrap samples (one per chain),
    iteration `boot_batches` evaluates the chains' starts (accepted, nothing deposited), and
    the `steps` after it are the mutations."""
    dtype = jnp.float32
    n_pix = int(camera.width) * int(camera.height)
    dims = pssmlt_sample_dimensions(bdpt.max_depth, _camera_dimensions(camera))
    k_boot, k_start, k_mut = jax.random.split(key, 3)
    one_minus = 1.0 - jnp.finfo(dtype).eps
    rows = jnp.arange(chains, dtype=jnp.int32)

    def uniform(k, shape):
        return jnp.minimum(jax.random.uniform(k, shape, dtype), one_minus)

    def bootstrap_sample(b):  # bootstrap sample b's state, regenerated from its index
        return uniform(jax.random.fold_in(k_boot, b), (dims,))

    def starts(importance):  # each chain starts at a bootstrap sample drawn by importance
        logits = jnp.log(jnp.where(importance > 0, importance, jnp.finfo(dtype).tiny))
        return jax.vmap(bootstrap_sample)(jax.random.categorical(k_start, logits, shape=(chains,)))

    def body(i, carry):
        u, idx, xyz, imp, image, boot = carry
        in_boot, at_start = i < boot_batches, i == boot_batches
        k_large, k_normal, k_fresh, k_accept = jax.random.split(jax.random.fold_in(k_mut, i), 4)
        large = jax.random.uniform(k_large, (chains,), dtype) < p_large
        small = u + sigma * jax.random.normal(k_normal, (chains, dims), dtype)
        small = jnp.minimum(small - jnp.floor(small), one_minus)
        proposal = jnp.where(large[:, None], uniform(k_fresh, (chains, dims)), small)
        proposal = jnp.where(at_start, jax.lax.cond(at_start, starts, lambda _: u, boot), proposal)
        first = jnp.minimum(i, boot_batches - 1) * chains
        proposal = jnp.where(in_boot, jax.vmap(bootstrap_sample)(first + rows), proposal)
        idx_p, xyz_p, imp_p = _contributions(bdpt, scene, camera, response, proposal)
        boot = jnp.where(in_boot, jax.lax.dynamic_update_slice(boot, imp_p, (first,)), boot)
        # Metropolis-Hastings acceptance and expected-value splatting (mutations only).
        a = jnp.where(imp > 0, jnp.minimum(1.0, imp_p / jnp.where(imp > 0, imp, 1.0)), 1.0)
        a = jnp.where(at_start, 1.0, jnp.where(imp_p > 0, a, 0.0))
        deposit = jnp.where(in_boot | at_start, 0.0, 1.0)
        w_cur = deposit * (1.0 - a) / jnp.where(imp > 0, imp, 1.0)
        w_prop = deposit * a / jnp.where(imp_p > 0, imp_p, 1.0)
        image = image.at[idx.reshape(-1)].add((xyz * w_cur[:, None, None]).reshape(-1, 3))
        image = image.at[idx_p.reshape(-1)].add((xyz_p * w_prop[:, None, None]).reshape(-1, 3))
        accept = ((jax.random.uniform(k_accept, (chains,), dtype) < a) & ~in_boot) | at_start

        def pick(new, old):
            return jnp.where(accept.reshape((chains,) + (1,) * (new.ndim - 1)), new, old)

        new = (pick(proposal, u), pick(idx_p, idx), pick(xyz_p, xyz), pick(imp_p, imp))
        return new + (image, boot)

    slots = 1 + bdpt.max_depth
    carry = (
        jnp.zeros((chains, dims), dtype),
        jnp.full((chains, slots), n_pix, jnp.int32),
        jnp.zeros((chains, slots, 3), dtype),
        jnp.zeros((chains,), dtype),
        jnp.zeros((n_pix + 1, 3), dtype),
        jnp.zeros((boot_batches * chains,), dtype),
    )
    *_, image, importance = jax.lax.fori_loop(0, boot_batches + 1 + steps, body, carry)
    c = jnp.mean(importance)
    deposits = jnp.maximum(steps, 1).astype(dtype) * chains
    return image[:n_pix] * (n_pix * c / deposits), importance
