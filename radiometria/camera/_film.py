r"""Film: spectral samples to XYZ, per-pixel accumulation, development to RGB (thesis 2.3.2).

A spectral sample of radiance $L(\lambda_j)$ at wavelengths $\lambda_j$ drawn with density
$p(\lambda_j)$ ($j = 1..n_\lambda$, e.g. hero wavelengths) gives the unbiased tristimulus estimate

$$\mathrm{XYZ} = \frac{1}{n_\lambda} \sum_j
\frac{L(\lambda_j)\,\bar{\mathbf{x}}(\lambda_j)}{p(\lambda_j)}
\Big/ \int \bar{y}(\lambda)\,\mathrm{d}\lambda$$

of $\int L \bar{\mathbf{x}} \,\mathrm{d}\lambda / \int \bar{y}\,\mathrm{d}\lambda$, with the CIE
colour-matching functions $\bar{\mathbf{x}} = (\bar{x}, \bar{y}, \bar{z})$ interpolated linearly
in the 1 nm table (0 outside it). The normalisation is Mitsuba 3's spectral film's: a constant
spectrum $L = 1$ gives $Y = 1$, so the film reports radiance-like numbers that compare with
Mitsuba's `scalar_spectral` renders (Mitsuba divides by its constant 106.7502, from its 5 nm
table; here $\int \bar{y}$ is taken over the table in use, 106.857 for CIE 1931 at 1 nm -- the
two differ by 0.1 %). $Y$ is therefore *not* luminance in cd m^-2 (that would be
$K_m \int L \bar{y}$); multiply by $683 \cdot 106.857$ lm W^-1 nm for that.

The film keeps per-pixel sums $\sum_i w_i \mathrm{XYZ}_i$ and $\sum_i w_i$ (thesis eq. 2.35);
`film_develop` divides them and converts to linear RGB. Accumulation is a scatter-add
(`.at[].add`) whose memory is the image's, whatever the number of samples.

**Spectral film.** `Film(..., spectral_bins=n)` also keeps $\sum_i w_i \hat L_{i,b}$ for $n$
equal bins $b$ of width $\Delta = (830 - 360)/n$ nm over [360, 830] nm (the range of the
renderer's wavelength sampling), where

$$\hat L_{i,b} = \frac{1}{n_\lambda} \sum_j \frac{L(\lambda_j)\,
\mathbb{1}[\lambda_j \in b]}{p(\lambda_j)\,\Delta}$$

is an unbiased estimate of the bin average $\frac1\Delta\int_b L\,\mathrm{d}\lambda$
($\mathrm{E}[L(\lambda_j)\mathbb{1}_b(\lambda_j)/p(\lambda_j)] = \int_b L$ for each
$\lambda_j \sim p$); `film_develop_spectral` divides by the same weight sums as the XYZ, so the
spectral image is the filtered, bin-averaged spectral radiance [W m^-2 sr^-1 nm^-1].
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._checks import as_float_array, check_last_axis, check_positive_int, device_array
from .._math import interp_table, uniform_grid
from .._types import Array, ArrayLike, Float
from ..colorimetry import get_cmfs, get_colourspace
from ._filters import AbstractFilter

DEFAULT_OBSERVER = "CIE 1931 2 Degree Standard Observer"
SPECTRAL_FILM_RANGE_NM = (360.0, 830.0)  # the renderer's wavelength sampling range [nm]
DEFAULT_SPECTRAL_BINS = 47  # 10 nm bins over [360, 830] nm


def spectral_bin_centres(n_bins: int = DEFAULT_SPECTRAL_BINS) -> np.ndarray:
    """Centres of the spectral film's `n_bins` equal bins over [360, 830] nm.

    **Arguments:**

    - `n_bins`: number of bins, >= 1 (default 47: 10 nm bins). [1]

    **Returns:**

    The centres (n_bins,) float64 [nm]; bin `b` spans centre +- width / 2, width
    `470 / n_bins` nm.

    !!! note "Thesis"
        Section 2.3.2 (the film).

    ??? cite "References"
        `Fichet2021` (spectral images); `Pharr2023` §5.4 (film; pbrt-v4's `SpectralFilm`).
    """
    n = check_positive_int(n_bins, "n_bins")
    lo, hi = SPECTRAL_FILM_RANGE_NM
    return lo + (hi - lo) * (np.arange(n, dtype=np.float64) + 0.5) / n


def _cmf_table(cmfs, observer: str) -> tuple[np.ndarray, np.ndarray]:
    if cmfs is None:
        cmfs = get_cmfs(observer)
    if isinstance(cmfs, tuple | list) and len(cmfs) == 2:
        wl, values = cmfs
    elif hasattr(cmfs, "wavelengths_nm") and hasattr(cmfs, "values"):
        wl, values = cmfs.wavelengths_nm, cmfs.values
    else:
        raise TypeError(
            "`cmfs` must be None, a TabulatedSpectra-like object with `wavelengths_nm` and "
            f"`values`, or a tuple (wavelengths_nm, values); got {type(cmfs).__name__}."
        )
    wl = np.asarray(wl, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    if wl.ndim != 1 or values.shape != (wl.shape[0], 3) or wl.shape[0] < 2:
        raise ValueError(
            "`cmfs` must hold wavelengths (n,) [nm] and values (n, 3) with n >= 2; got shapes "
            f"{wl.shape} and {values.shape}."
        )
    if np.any(np.diff(wl) <= 0):
        raise ValueError("`cmfs` wavelengths must increase strictly [nm].")
    return wl, values


def _normalised_cmfs(cmfs, observer: str, dtype) -> tuple[Array, Array, tuple | None]:
    r"""The CIE table and its values divided by $\int\bar y$, as arrays of `dtype`, and the
    table's `(start, step)` [nm] when its wavelengths are evenly spaced (`uniform_grid`)."""
    if dtype is None:
        dtype = jnp.zeros(()).dtype  # the default float (float64 under jax_enable_x64)
    if not jnp.issubdtype(dtype, jnp.floating):
        raise TypeError(f"`dtype` must be a floating dtype, got {dtype}.")
    wl, values = _cmf_table(cmfs, observer)
    y_integral = np.trapezoid(values[:, 1], wl)
    return device_array(wl, dtype), device_array(values / y_integral, dtype), uniform_grid(wl)


class SpectralResponse(eqx.Module):
    r"""The film's spectral response: colour-matching functions divided by $\int\bar y$.

    What `film_samples_to_XYZ` needs to turn spectral samples into XYZ, without a film's
    accumulators (the render driver's paths carry only this). `Film(...).response` is the
    response of a film.

    **Arguments:**

    Build one with `SpectralResponse.from_observer(cmfs=..., observer=..., dtype=...)`
    (arguments as `Film`).

    **Fields:**

    `cmf_wavelengths_nm` (n,) [nm], `cmf_values` (n, 3) [nm^-1] (normalised CMFs),
    `cmf_grid_nm`: `(start, step)` [nm] of evenly spaced CMF wavelengths (static; `None` when
    they are not), with which `film_samples_to_XYZ` finds a wavelength's row without a search.

    !!! note "Thesis"
        Eq. 2.12-2.14 (tristimulus integrals), section 2.3.2.

    ??? cite "References"
        `Jakob2022` (`spectrum_to_xyz`); `CIE2018`.
    """

    cmf_wavelengths_nm: Float[Array, " n"]
    cmf_values: Float[Array, "n 3"]
    cmf_grid_nm: tuple[float, float] | None = eqx.field(static=True, default=None)

    @classmethod
    def from_observer(
        cls, *, cmfs=None, observer: str = DEFAULT_OBSERVER, dtype=None
    ) -> "SpectralResponse":
        """The response of `cmfs` (default: the observer's CIE table), as `Film` builds it."""
        return cls(*_normalised_cmfs(cmfs, observer, dtype))


class Film(eqx.Module):
    r"""Per-pixel accumulators of weighted XYZ and weights (thesis eq. 2.34-2.35).

    `Film(width, height)` starts an empty film; the `film_*` functions return updated copies.
    The CIE table (divided by $\int \bar{y}$) travels with the film, so adding samples needs no
    other input. Normalisation (Mitsuba 3's spectral film): $\mathrm{XYZ} = \int L
    \bar{\mathbf{x}}\,\mathrm{d}\lambda / \int \bar{y}\,\mathrm{d}\lambda$, so a constant spectral
    radiance $L = 1$ gives $Y = 1$ (Mitsuba divides by its constant 106.7502; $\int\bar{y}$ of the
    1 nm CIE 1931 table is 106.857, 0.1 % apart). $Y$ is not luminance in cd m^-2.

    **Arguments:**

    - `width`, `height`: image size, integers >= 1. [px]
    - `cmfs`: colour-matching functions: `None` for
        `radiometria.colorimetry.get_cmfs(observer)`, or an object with `wavelengths_nm` (n,)
        [nm] and `values` (n, 3), or a tuple `(wavelengths_nm, values)`.
    - `observer`: the observer name used when `cmfs` is `None`.
    - `dtype`: floating dtype of the accumulators; `None` for JAX's default float.

    **Fields:**

    - `spectral_bins`: `None` (default) for an XYZ film; an integer n >= 1 to also accumulate
        spectral radiance in n equal bins over [360, 830] nm (module docstring;
        `spectral_bin_centres`). [1]

    **Fields:**

    `xyz_sum` (H, W, 3), `weight_sum` (H, W), `spectral_sum` (H, W, n) or `None`,
    `cmf_wavelengths_nm` (n,) [nm], `cmf_values` (n, 3) [nm^-1] (normalised CMFs), `width`,
    `height`, `spectral_bins`, `cmf_grid_nm` (static; as `SpectralResponse`'s).

    !!! note "Thesis"
        Thesis section 2.3.2, eq. 2.34-2.35; section 2.2 (XYZ).

    ??? cite "References"
        `Pharr2023` §5.4; `Jakob2022` (`hdrfilm`, `spectrum_to_xyz`); `CIE2018`.
    """

    width: int = eqx.field(static=True)
    height: int = eqx.field(static=True)
    xyz_sum: Float[Array, "H W 3"]
    weight_sum: Float[Array, "H W"]
    cmf_wavelengths_nm: Float[Array, " n"]
    cmf_values: Float[Array, "n 3"]
    spectral_sum: Float[Array, "H W bins"] | None
    spectral_bins: int | None = eqx.field(static=True)
    cmf_grid_nm: tuple[float, float] | None = eqx.field(static=True)

    def __init__(
        self,
        width: int,
        height: int,
        *,
        cmfs=None,
        observer: str = DEFAULT_OBSERVER,
        dtype=None,
        spectral_bins: int | None = None,
    ):
        self.width = check_positive_int(width, "width")
        self.height = check_positive_int(height, "height")
        self.cmf_wavelengths_nm, self.cmf_values, self.cmf_grid_nm = _normalised_cmfs(
            cmfs, observer, dtype
        )
        dtype = self.cmf_values.dtype
        self.xyz_sum = jnp.zeros((self.height, self.width, 3), dtype)
        self.weight_sum = jnp.zeros((self.height, self.width), dtype)
        if spectral_bins is None:
            self.spectral_bins, self.spectral_sum = None, None
        else:
            self.spectral_bins = check_positive_int(spectral_bins, "spectral_bins")
            self.spectral_sum = jnp.zeros((self.height, self.width, self.spectral_bins), dtype)

    @property
    def response(self) -> SpectralResponse:
        """The film's colour-matching functions as a `SpectralResponse`."""
        return SpectralResponse(self.cmf_wavelengths_nm, self.cmf_values, self.cmf_grid_nm)


def film_samples_to_XYZ(
    film: "Film | SpectralResponse", L_lambda: ArrayLike, wavelengths_nm: ArrayLike, pdf: ArrayLike
) -> Float[Array, "*batch 3"]:
    r"""Tristimulus estimate of spectral radiance samples, normalised so $L \equiv 1$ gives $Y = 1$.

    $\mathrm{XYZ} = \frac{1}{n_\lambda}\sum_j L_j \bar{\mathbf{x}}(\lambda_j) / p_j / \int\bar{y}$
    (module docstring). Samples with $p_j = 0$ contribute 0.

    **Arguments:**

    - `film`: the `Film` (or its `SpectralResponse`) whose colour-matching functions are used.
    - `L_lambda`: spectral radiance (..., n_lambda). [W m^-2 sr^-1 nm^-1]
    - `wavelengths_nm`: the sampled wavelengths, broadcastable to `L_lambda`. [nm]
    - `pdf`: wavelength density of each sample (the marginal of one wavelength), broadcastable
        to `L_lambda`. [nm^-1]

    **Returns:**

    XYZ (..., 3) in the units of `L_lambda` integrated over wavelength divided by
    $\int\bar{y}$ [W m^-2 sr^-1 / nm, i.e. radiance-like], in the dtype of `L_lambda`.

    !!! note "Thesis"
        Eq. 2.12-2.14 (tristimulus integrals) estimated by Monte Carlo, section 2.3.2.

    ??? cite "References"
        `Jakob2022` (`spectrum_to_xyz`); `Pharr2023` §4.6.
    """
    L = as_float_array(L_lambda, "L_lambda")
    if L.ndim == 0:
        raise ValueError("`L_lambda` must have a last (wavelength) axis, got a scalar.")
    wl = as_float_array(wavelengths_nm, "wavelengths_nm")
    p = as_float_array(pdf, "pdf")
    try:
        shape = np.broadcast_shapes(L.shape, wl.shape, p.shape)
    except ValueError:
        raise ValueError(
            f"`L_lambda` {L.shape}, `wavelengths_nm` {wl.shape} and `pdf` {p.shape} "
            "do not broadcast."
        ) from None
    if shape != L.shape:
        raise ValueError(
            f"`wavelengths_nm` {wl.shape} and `pdf` {p.shape} must broadcast to "
            f"`L_lambda` {L.shape}."
        )
    dtype = L.dtype
    wl = jnp.broadcast_to(wl.astype(dtype), L.shape)
    p = jnp.broadcast_to(p.astype(dtype), L.shape)
    table_wl = film.cmf_wavelengths_nm.astype(dtype)
    table = film.cmf_values.astype(dtype)
    cmf = interp_table(wl, table_wl, table, film.cmf_grid_nm, left=0.0, right=0.0)
    ok = p > 0
    inv_p = jnp.where(ok, 1.0 / jnp.where(ok, p, 1.0), 0.0)
    contrib = (L * inv_p)[..., None] * cmf  # (..., n_lambda, 3)
    return jnp.mean(contrib, axis=-2)


def film_samples_to_spectral_bins(
    L_lambda: ArrayLike, wavelengths_nm: ArrayLike, pdf: ArrayLike, n_bins: int
) -> Float[Array, "*batch bins"]:
    r"""Estimates of the bin-averaged spectral radiance from spectral radiance samples.

    Bin $b$ of the $n$ equal bins of width $\Delta$ over [360, 830] nm gets
    $\frac{1}{n_\lambda}\sum_j L_j \mathbb{1}[\lambda_j \in b] / (p_j \Delta)$, an unbiased
    estimate of $\frac1\Delta\int_b L\,\mathrm{d}\lambda$ (module docstring). Samples outside
    the range or with $p_j = 0$ contribute 0.

    **Arguments:**

    - `L_lambda`: spectral radiance (..., n_lambda). [W m^-2 sr^-1 nm^-1]
    - `wavelengths_nm`: the sampled wavelengths, broadcastable to `L_lambda`. [nm]
    - `pdf`: the density of each wavelength (marginal of one), broadcastable to
        `L_lambda`. [nm^-1]
    - `n_bins`: number of bins, >= 1. [1]

    **Returns:**

    (..., n_bins) in the dtype of `L_lambda`. [W m^-2 sr^-1 nm^-1]

    !!! note "Thesis"
        Section 2.3.2 (the film), Monte Carlo estimation (eq. 2.12-2.14 with box responses).

    ??? cite "References"
        `Pharr2023` §5.4 (film; pbrt-v4's `SpectralFilm`); `Wilkie2014` (hero wavelengths).
    """
    n = check_positive_int(n_bins, "n_bins")
    L = as_float_array(L_lambda, "L_lambda")
    if L.ndim == 0:
        raise ValueError("`L_lambda` must have a last (wavelength) axis, got a scalar.")
    dtype = L.dtype
    wl = jnp.broadcast_to(as_float_array(wavelengths_nm, "wavelengths_nm").astype(dtype), L.shape)
    p = jnp.broadcast_to(as_float_array(pdf, "pdf").astype(dtype), L.shape)
    lo, hi = SPECTRAL_FILM_RANGE_NM
    width = (hi - lo) / n
    ok = (p > 0) & (wl >= lo) & (wl <= hi)
    value = jnp.where(ok, L / (jnp.where(ok, p, 1.0) * width), 0.0)  # (..., n_lambda)
    b = jnp.clip(jnp.floor((wl - lo) / width).astype(jnp.int32), 0, n - 1)
    onehot = b[..., None] == jnp.arange(n, dtype=jnp.int32).reshape((1,) * b.ndim + (n,))
    return jnp.sum(jnp.where(onehot, value[..., None], 0.0), axis=-2) / L.shape[-1]


def _flat_pixel_index(film: Film, pixel, batch_shape: tuple[int, ...]) -> Array:
    """Flat pixel index (batch,) from flat ints, integer (x, y) or raster floats; H*W if outside."""
    pixel = jnp.asarray(pixel)
    n_pix = film.width * film.height
    if jnp.issubdtype(pixel.dtype, jnp.integer) and pixel.shape == batch_shape:
        idx = pixel.astype(jnp.int32)
        return jnp.where((idx >= 0) & (idx < n_pix), idx, n_pix)
    if pixel.shape != (*batch_shape, 2):
        raise ValueError(
            f"`pixel` must be flat integer indices of shape {batch_shape} or (x, y) pixel / "
            f"raster coordinates of shape {(*batch_shape, 2)} [px]; got shape {pixel.shape}."
        )
    if jnp.issubdtype(pixel.dtype, jnp.integer):
        ij = pixel.astype(jnp.int32)
    elif jnp.issubdtype(pixel.dtype, jnp.floating):
        ij = jnp.floor(pixel).astype(jnp.int32)
        ij = jnp.where(jnp.isfinite(pixel), ij, -1)
    else:
        raise TypeError(f"`pixel` must be an integer or floating array, got dtype {pixel.dtype}.")
    x, y = ij[..., 0], ij[..., 1]
    inside = (x >= 0) & (x < film.width) & (y >= 0) & (y < film.height)
    return jnp.where(inside, y * film.width + x, n_pix)


def film_add_XYZ(film: Film, pixel: ArrayLike, XYZ: ArrayLike, weight: ArrayLike = 1.0) -> Film:
    r"""Add weighted tristimulus samples to their pixels (scatter-add; the sums of eq. 2.35).

    **Arguments:**

    - `film`: the `Film` to add to (it is not modified; a new one is returned).
    - `pixel`: which pixel each sample belongs to: flat integer indices `y * W + x` (batch),
        integer pixel coordinates (batch, 2) as $(x, y)$, or floating raster positions
        (batch, 2) (floored). Samples outside the image are dropped. [px]
    - `XYZ`: tristimulus values (batch..., 3). [radiance-like, see `film_samples_to_XYZ`]
    - `weight`: sample weights, broadcastable to the batch shape, e.g. the filter weight
        $f/p$ from `AbstractFilter.sample`. [dimensionless]

    **Returns:**

    The updated `Film`.

    !!! note "Thesis"
        Eq. 2.35.

    ??? cite "References"
        `Pharr2023` §5.4.3.
    """
    xyz = check_last_axis(as_float_array(XYZ, "XYZ"), "XYZ", 3).astype(film.xyz_sum.dtype)
    batch = xyz.shape[:-1]
    w = as_float_array(weight, "weight").astype(film.xyz_sum.dtype)
    try:
        w = jnp.broadcast_to(w, batch)
    except ValueError:
        raise ValueError(
            f"`weight` {w.shape} does not broadcast to the batch shape {batch}."
        ) from None
    idx = _flat_pixel_index(film, pixel, batch).reshape(-1)
    n_pix = film.width * film.height
    xyz_sum = (
        film.xyz_sum.reshape(n_pix, 3).at[idx].add((w[..., None] * xyz).reshape(-1, 3), mode="drop")
    )
    weight_sum = film.weight_sum.reshape(n_pix).at[idx].add(w.reshape(-1), mode="drop")
    return eqx.tree_at(
        lambda f: (f.xyz_sum, f.weight_sum),
        film,
        (xyz_sum.reshape(film.height, film.width, 3), weight_sum.reshape(film.height, film.width)),
    )


def film_add_samples(
    film: Film,
    pixel: ArrayLike,
    L_lambda: ArrayLike,
    wavelengths_nm: ArrayLike,
    pdf: ArrayLike,
    weight: ArrayLike = 1.0,
) -> Film:
    r"""Add spectral radiance samples: `film_samples_to_XYZ` then `film_add_XYZ`.

    **Arguments:**

    - `film`: the `Film`.
    - `pixel`: flat indices (n,), pixel coordinates (n, 2) int or raster positions (n, 2)
        float. [px]
    - `L_lambda`: spectral radiance (n, n_lambda). [W m^-2 sr^-1 nm^-1]
    - `wavelengths_nm`: wavelengths (n, n_lambda) (or broadcastable). [nm]
    - `pdf`: per-wavelength sampling density (n, n_lambda) (or broadcastable). [nm^-1]
    - `weight`: per-sample weight (n,), e.g. the filter importance-sampling weight. [dimensionless]

    **Returns:**

    The updated `Film`.

    !!! note "Thesis"
        Eq. 2.35; eq. 2.12-2.14.

    ??? cite "References"
        `Pharr2023` §5.4; `Jakob2022`.
    """
    xyz = film_samples_to_XYZ(film, L_lambda, wavelengths_nm, pdf)
    return film_add_XYZ(film, pixel, xyz, weight)


def splat_samples(
    film: Film,
    raster_xy: ArrayLike,
    XYZ: ArrayLike,
    filter: AbstractFilter,
    weight: ArrayLike = 1.0,
) -> Film:
    r"""Splat samples into every pixel their filter footprint covers (thesis eq. 2.34).

    Sample $i$ at raster position $\vec{x}_i$ adds $f(\vec{c} - \vec{x}_i)\,\mathrm{XYZ}_i$ and
    $f(\vec{c} - \vec{x}_i)$ to every pixel with centre $\vec{c}$ within the filter radius, so
    `film_develop` returns $\sum_i f_i r_i / \sum_i f_i$. Memory is O(samples x footprint):
    a footprint of $(\lceil 2r \rceil + 1)^2$ pixels per sample; batch the samples for large
    counts. Pixels outside the image are dropped.

    **Arguments:**

    - `film`: the `Film`.
    - `raster_xy`: sample positions (batch..., 2), uniformly distributed over the film. [px]
    - `XYZ`: their tristimulus values (batch..., 3). [radiance-like]
    - `filter`: the reconstruction filter $f$.
    - `weight`: optional extra per-sample weight, broadcastable to the batch. [dimensionless]

    **Returns:**

    The updated `Film`.

    !!! note "Thesis"
        Eq. 2.34, section 2.3.2.

    ??? cite "References"
        `Pharr2023` §8.8; `Jakob2022` (`ImageBlock.put`).
    """
    if not isinstance(filter, AbstractFilter):
        raise TypeError(f"`filter` must be a reconstruction filter, got {type(filter).__name__}.")
    xy = check_last_axis(as_float_array(raster_xy, "raster_xy"), "raster_xy", 2)
    xyz = check_last_axis(as_float_array(XYZ, "XYZ"), "XYZ", 3)
    if xy.shape[:-1] != xyz.shape[:-1]:
        raise ValueError(f"`raster_xy` {xy.shape} and `XYZ` {xyz.shape} need the same batch shape.")
    dtype = film.xyz_sum.dtype
    batch = xy.shape[:-1]
    w = as_float_array(weight, "weight").astype(dtype)
    try:
        w = jnp.broadcast_to(w, batch).reshape(-1)
    except ValueError:
        raise ValueError(
            f"`weight` {w.shape} does not broadcast to the batch shape {batch}."
        ) from None
    xy, xyz = xy.reshape(-1, 2).astype(dtype), xyz.reshape(-1, 3).astype(dtype)
    r = float(filter.radius)
    k = int(np.ceil(2 * r)) + 1
    # First pixel whose centre i + 0.5 can lie within r of x: floor(x - r - 0.5) + 1.
    first = jnp.floor(xy - r - 0.5).astype(jnp.int32) + 1  # (n, 2)
    steps = jnp.arange(k, dtype=jnp.int32)
    px = first[:, None, None, 0] + steps[None, None, :]  # (n, 1, k)
    py = first[:, None, None, 1] + steps[None, :, None]  # (n, k, 1)
    px, py = jnp.broadcast_arrays(px, py)  # (n, k, k)
    cx = px.astype(dtype) + 0.5 - xy[:, None, None, 0]  # pixel centre minus sample position
    cy = py.astype(dtype) + 0.5 - xy[:, None, None, 1]
    f = filter.evaluate(jnp.stack([cx, cy], axis=-1)) * w[:, None, None]  # (n, k, k)
    ij = jnp.stack([px, py], axis=-1)
    idx = _flat_pixel_index(film, ij, f.shape).reshape(-1)
    n_pix = film.width * film.height
    xyz_sum = (
        film.xyz_sum.reshape(n_pix, 3)
        .at[idx]
        .add((f[..., None] * xyz[:, None, None, :]).reshape(-1, 3), mode="drop")
    )
    weight_sum = film.weight_sum.reshape(n_pix).at[idx].add(f.reshape(-1), mode="drop")
    return eqx.tree_at(
        lambda f_: (f_.xyz_sum, f_.weight_sum),
        film,
        (xyz_sum.reshape(film.height, film.width, 3), weight_sum.reshape(film.height, film.width)),
    )


def film_merge(a: Film, b: Film) -> Film:
    """Sum two films of the same size (e.g. from different devices or batches).

    **Arguments:**

    - `a`, `b`: films with equal `width`, `height` and colour-matching functions. [px]

    **Returns:**

    A `Film` whose sums are the sums of both.

    !!! note "Thesis"
        Eq. 2.35 (the sums are additive).
    """
    if (a.width, a.height) != (b.width, b.height):
        raise ValueError(
            f"Films differ in size: {a.width}x{a.height} and {b.width}x{b.height} [px]."
        )
    if a.spectral_bins != b.spectral_bins:
        raise ValueError(f"Films differ in spectral bins: {a.spectral_bins} and {b.spectral_bins}.")
    merged = eqx.tree_at(
        lambda f: (f.xyz_sum, f.weight_sum), a, (a.xyz_sum + b.xyz_sum, a.weight_sum + b.weight_sum)
    )
    if a.spectral_sum is None:
        return merged
    return eqx.tree_at(lambda f: f.spectral_sum, merged, a.spectral_sum + b.spectral_sum)


def _xyz_to_rgb_matrix(colourspace, dtype) -> Array:
    if isinstance(colourspace, str):
        colourspace = get_colourspace(colourspace)
    m = getattr(colourspace, "matrix_XYZ_to_RGB", colourspace)
    m = as_float_array(m, "colourspace")
    if m.shape != (3, 3):
        raise ValueError(
            "`colourspace` must be a colour-space name, an RGBColourspace or a 3x3 XYZ-to-RGB "
            f"matrix; got an array of shape {m.shape}."
        )
    return m.astype(dtype)


def film_develop(film: Film, colourspace="sRGB") -> Float[Array, "H W 3"]:
    r"""The filtered image: $\sum_i w_i \mathrm{XYZ}_i / \sum_i w_i$ per pixel, as linear RGB.

    Pixels with zero weight sum are black. No white balancing or tone mapping is applied:
    the XYZ are converted with the colour space's `matrix_XYZ_to_RGB` (its own white, Y = 1),
    so a spectrum with the chromaticity of D65 and $Y = 1$ gives linear sRGB (1, 1, 1).

    **Arguments:**

    - `film`: the `Film`.
    - `colourspace`: a name from `radiometria.colorimetry.RGB_COLOURSPACES` (default
        `"sRGB"`), an `RGBColourspace`, a 3x3 XYZ-to-RGB matrix, or `"XYZ"` for the XYZ
        image itself.

    **Returns:**

    Linear RGB (H, W, 3) in the film's dtype [radiance-like units of the samples].

    !!! note "Thesis"
        Eq. 2.34-2.35; section 2.2.2 (sRGB).

    ??? cite "References"
        `Pharr2023` §5.4; `IEC1999`.
    """
    ws = film.weight_sum
    nonzero = ws != 0
    xyz = jnp.where(nonzero[..., None], film.xyz_sum / jnp.where(nonzero, ws, 1.0)[..., None], 0.0)
    if isinstance(colourspace, str) and colourspace == "XYZ":
        return xyz
    m = _xyz_to_rgb_matrix(colourspace, xyz.dtype)
    return jnp.einsum("ij,...j->...i", m, xyz)


def film_develop_spectral(film: Film) -> Float[Array, "H W bins"]:
    r"""The filtered spectral image: $\sum_i w_i \hat L_{i,b} / \sum_i w_i$ per pixel and bin.

    The same weights as `film_develop`'s XYZ, so integrating the bins against the CMFs gives
    the XYZ image up to the binning error. Pixels with zero weight sum are 0.

    **Arguments:**

    - `film`: a `Film` made with `spectral_bins`.

    **Returns:**

    (H, W, n) bin-averaged spectral radiance at `spectral_bin_centres(n)`, in the film's
    dtype. [W m^-2 sr^-1 nm^-1]

    !!! note "Thesis"
        Eq. 2.34-2.35; section 2.3.2.

    ??? cite "References"
        `Pharr2023` §5.4; `Fichet2021`.
    """
    if film.spectral_sum is None:
        raise ValueError("`film` has no spectral bins; make it with Film(..., spectral_bins=n).")
    ws = film.weight_sum
    nonzero = ws != 0
    return jnp.where(
        nonzero[..., None], film.spectral_sum / jnp.where(nonzero, ws, 1.0)[..., None], 0.0
    )
