r"""Round-trip accuracy of a coefficient table: RGB -> coefficients -> spectrum -> RGB.

The measure the issue and the thesis's accuracy goal use: a linear RGB colour is looked up in
the table, its sigmoid-polynomial spectrum is integrated against the CIE 1931 2° CMFs under the
colour space's illuminant (the same forward model as the fit, 1 nm), and the reproduced colour
is compared with the input by CIEDE2000 (`colorimetry.delta_E_CIE2000`), both in CIELAB
relative to the space's white.

Two standard test sets (pbrt-v4's sRGB table at res 64 scores mean 0.044 / p99 0.215 / max 11.7
on the first and max 0.39 on the second):

- `roundtrip_grid_rgb(n)`: the n^3 grid of *encoded* values i / (n - 1) decoded with the
  space's transfer function (sRGB EOTF for sRGB), so dark colours are sampled densely;
- `roundtrip_random_rgb(n, key)`: n uniform random *linear* colours in [0, 1]^3.
"""

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from .._checks import as_float_array, check_last_axis, check_positive_int
from ..colorimetry import delta_E_CIE2000, get_colourspace
from ._forward import XYZ_to_Lab_white, forward_model
from ._lut import RGBToSpectrumLUT, _check_rgb_values, lookup
from ._sigmoid_polynomial import _evaluate


def roundtrip_grid_rgb(n: int = 33, colourspace="sRGB") -> np.ndarray:
    """Linear RGB (n^3, 3) of the n^3 grid of encoded values decoded with the space's
    transfer function (float64 NumPy), the test set of thesis section 2.2.3's table. [-]"""
    n = check_positive_int(n, "grid", minimum=2)
    cs = get_colourspace(colourspace)
    v = np.linspace(0.0, 1.0, n)
    with jax.enable_x64(True):
        lin = np.asarray(cs.cctf_decoding(jnp.asarray(v)), dtype=np.float64)
    lin = np.clip(lin, 0.0, 1.0)
    g = np.stack(np.meshgrid(lin, lin, lin, indexing="ij"), axis=-1)
    return g.reshape(-1, 3)


def roundtrip_random_rgb(n: int = 100_000, seed: int = 0) -> np.ndarray:
    """n uniform random linear RGB colours in [0, 1]^3 (float64 NumPy, PCG64 `seed`). [-]

    The second test set for the table of thesis section 2.2.3.
    """
    n = check_positive_int(n, "random", minimum=1)
    return np.random.default_rng(seed).random((n, 3))


def _roundtrip_chunk(coeffs, scale, res, colourspace, rgb, lam_nm, weights, to_xyz, white):
    lut = RGBToSpectrumLUT(scale, coeffs, colourspace)
    c = lookup(lut, rgb)
    spectrum = _evaluate(c, lam_nm)  # (n, n_lambda)
    xyz = spectrum @ weights
    lab_out = XYZ_to_Lab_white(xyz, white)
    lab_in = XYZ_to_Lab_white(rgb @ to_xyz.T, white)
    return delta_E_CIE2000(lab_in, lab_out), xyz


_roundtrip_jit = jax.jit(_roundtrip_chunk, static_argnums=(2, 3))


def roundtrip_delta_E(
    lut: RGBToSpectrumLUT, rgb: ArrayLike, *, chunk: int = 16384, dtype=None
) -> tuple[np.ndarray, np.ndarray]:
    r"""CIEDE2000 round-trip error of linear RGB colours through a coefficient table.

    RGB -> `lut.coefficients` -> $S(\lambda)$ on the 1 nm grid -> XYZ under the space's
    illuminant (`forward_model`) -> CIELAB, compared with the input's CIELAB by CIEDE2000.

    **Arguments:**

    - `lut`: the table.
    - `rgb`: linear RGB (n, 3) of the table's colour space, in [0, 1]. [-]
    - `chunk`: colours per vectorised batch.
    - `dtype`: evaluation dtype; default float64 where x64 is enabled (the table is cast), so
        the figure measures the table, not float32 rounding.

    **Returns:**

    `(delta_E, rgb_out)`: (n,) CIEDE2000 [-] and the reproduced linear RGB (n, 3) [-], NumPy.

    !!! note "Thesis"
        Eq. 2.25-2.27 and the lookup table of section 2.2.3.

    ??? cite "References"
        `Jakob2019` section 6; `Sharma2005` (CIEDE2000).
    """
    rgb = check_last_axis(as_float_array(rgb, "rgb"), "rgb", 3)
    _check_rgb_values(rgb)
    if dtype is None:
        dtype = jnp.float64 if jax.config.jax_enable_x64 else jnp.float32
    model = forward_model(lut.colourspace)
    rgb_np = np.asarray(rgb, dtype=np.float64).reshape(-1, 3)
    args = (
        jnp.asarray(model.wavelengths_nm, dtype),
        jnp.asarray(model.weights_XYZ, dtype),
        jnp.asarray(model.matrix_RGB_to_XYZ, dtype),
        jnp.asarray(model.white_XYZ, dtype),
    )
    coeffs = lut.coeffs.astype(dtype)
    scale = lut.scale.astype(dtype)
    out_de, out_rgb = [], []
    n = rgb_np.shape[0]
    for i in range(0, n, chunk):
        part = rgb_np[i : i + chunk]
        pad = chunk - part.shape[0] if n > chunk else 0
        x = np.concatenate([part, np.full((pad, 3), 0.5)]) if pad else part
        de, xyz = _roundtrip_jit(
            coeffs, scale, lut.resolution, lut.colourspace, jnp.asarray(x, dtype), *args
        )
        out_de.append(np.asarray(de)[: part.shape[0]])
        out_rgb.append(np.asarray(xyz)[: part.shape[0]] @ model.matrix_XYZ_to_RGB.T)
    return np.concatenate(out_de), np.concatenate(out_rgb)


def roundtrip_statistics(delta_E: ArrayLike, rgb: ArrayLike | None = None) -> dict:
    """Mean, median, p99, max of a CIEDE2000 array, and the worst colour (plain Python).

    **Arguments:**

    - `delta_E`: (n,) CIEDE2000 values. [-]
    - `rgb`: the (n, 3) linear RGB the values belong to, to name the worst one. [-]

    **Returns:**

    dict with `n`, `mean`, `median`, `p99`, `max` [-] and `worst_rgb` (or None).

    !!! note "Thesis"
        Section 2.2.3 (accuracy of the lookup table).

    ??? cite "References"
        `Sharma2005`.
    """
    d = np.asarray(delta_E, dtype=np.float64).ravel()
    worst = int(np.argmax(d))
    return {
        "n": int(d.size),
        "mean": float(d.mean()),
        "median": float(np.median(d)),
        "p99": float(np.quantile(d, 0.99)),
        "max": float(d.max()),
        "worst_rgb": None
        if rgb is None
        else [float(v) for v in np.asarray(rgb).reshape(-1, 3)[worst]],
    }


# --- Which colours a reflectance can have: the object-colour solid -------------------------


def _zonotope_halfspaces(generators: np.ndarray, chunk: int = 4096):
    """Facet normals (m, 3) and offsets (m,) of the zonotope {sum_i s_i g_i : s in [0, 1]^n}.

    Every facet of a 3-D zonotope is spanned by two generators, so its normals are the cross
    products u = g_i x g_j (i < j) and -u, with support value h(u) = sum_k max(0, u . g_k).
    Pairs of (numerically) parallel generators span no facet and are dropped.
    """
    g = np.asarray(generators, np.float64)
    g = g[np.linalg.norm(g, axis=1) > 0]
    i, j = np.triu_indices(g.shape[0], k=1)
    u = np.cross(g[i], g[j])
    norm = np.linalg.norm(u, axis=1)
    keep = norm > 1e-12 * np.max(norm)
    u = u[keep] / norm[keep, None]
    u = np.concatenate([u, -u])
    h = np.empty(u.shape[0])
    for a in range(0, u.shape[0], chunk):
        h[a : a + chunk] = np.maximum(u[a : a + chunk] @ g.T, 0.0).sum(axis=1)
    return u, h


def object_colour_scale(rgb: ArrayLike, colourspace="sRGB", *, chunk: int = 64) -> np.ndarray:
    r"""The largest $t$ with $t\cdot\mathrm{rgb}$ the colour of a reflectance in [0, 1].

    The colours of reflectances $0 \le S(\lambda) \le 1$ under the space's illuminant (the
    forward model of eq. 2.27, 1 nm) form the *object-colour solid* $\{\sum_i S_i W_i\}$, a
    zonotope whose boundary is the Rösch-MacAdam optimal colours. It contains black, so each
    direction of RGB is reachable up to a brightness factor $t^*$: a colour has a reflectance
    spectrum iff $t^* \ge 1$, and colours with a chromaticity outside the spectral locus have
    $t^* = 0$. Computed exactly from the zonotope's facets ($t^* = \min h(u) / (u\cdot x)$
    over facet normals $u$ with $u \cdot x > 0$); NumPy float64, offline use (tests and
    `_make_data`), about 1 s per 1000 colours.

    **Arguments:**

    - `rgb`: linear RGB (n, 3) of `colourspace`, components >= 0. [-]
    - `colourspace`: name or alias in `colorimetry.RGB_COLOURSPACES`. [-]
    - `chunk`: colours per vectorised block.

    **Returns:**

    (n,) $t^*$ (`inf` for black). [-]

    !!! note "Thesis"
        Section 2.2.3 (the reflectances the sigmoid model represents).

    ??? cite "References"
        `Wyszecki2000` (optimal object-colour stimuli); `Jakob2019` section 4.
    """
    model = forward_model(colourspace)
    u, h = _object_colour_facets(model.colourspace)
    x = np.asarray(rgb, np.float64).reshape(-1, 3) @ model.matrix_RGB_to_XYZ.T
    return _scale_from_facets(x, u, h, chunk)


_FACETS: dict = {}


def _object_colour_facets(name: str, group: int = 1):
    """Facets of the object-colour solid of a space; with `group` > 1, of the smaller solid
    whose reflectances are constant over runs of `group` samples (an inner approximation)."""
    if (name, group) not in _FACETS:
        w = np.asarray(forward_model(name).weights_XYZ, np.float64)
        if group > 1:
            pad = (-w.shape[0]) % group
            w = np.concatenate([w, np.zeros((pad, 3))]).reshape(-1, group, 3).sum(axis=1)
        _FACETS[name, group] = _zonotope_halfspaces(w)
    return _FACETS[name, group]


def _scale_from_facets(x: np.ndarray, u: np.ndarray, h: np.ndarray, chunk: int) -> np.ndarray:
    out = np.empty(x.shape[0])
    for a in range(0, x.shape[0], chunk):
        d = x[a : a + chunk] @ u.T  # (c, m)
        pos = d > 0
        t = np.where(pos, h[None, :] / np.where(pos, d, 1.0), np.inf)
        out[a : a + chunk] = np.maximum(t.min(axis=1), 0.0)
    return out


def has_reflectance(
    rgb: ArrayLike, colourspace="sRGB", *, headroom: float = 1.0, rtol: float = 1e-9
) -> np.ndarray:
    """Boolean (n,): the linear RGB colour is the colour of some reflectance in [0, 1].

    `object_colour_scale(rgb) >= headroom * (1 - rtol)` (`headroom` > 1 asks that the colour
    stay reachable when brightened by that factor, i.e. lie that far inside the solid),
    computed faster: an inner approximation of the solid (reflectances constant over 5 nm
    runs) settles the colours well inside, a subset of the exact facets settles those well
    outside, and the exact facets decide the thin shell in between. Offline use.
    """
    model = forward_model(colourspace)
    x = np.asarray(rgb, np.float64).reshape(-1, 3) @ model.matrix_RGB_to_XYZ.T
    limit = headroom * (1.0 - rtol)
    u_in, h_in = _object_colour_facets(model.colourspace, 5)
    inside = _scale_from_facets(x, u_in, h_in, 512) >= limit
    u, h = _object_colour_facets(model.colourspace)
    sub = slice(None, None, 97)  # a subset of the exact facets: an outer approximation
    rest = np.flatnonzero(~inside)
    t_hi = _scale_from_facets(x[rest], u[sub], h[sub], 512)
    unsure = rest[t_hi >= limit]
    out = inside.copy()
    out[unsure] = _scale_from_facets(x[unsure], u, h, 64) >= limit
    return out
