r"""Von Kries-type chromatic adaptation transforms (XYZ Scaling, Von Kries, Bradford, CAT02, CAT16).

$$XYZ_a = M^{-1}\,\mathrm{diag}\!\left(\frac{M\,XYZ_{wr}}{M\,XYZ_w}\right) M\,XYZ$$

with the cone-like response matrix $M$ of the chosen transform.
"""

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._checks import as_float_array, check_broadcastable, check_last_axis, lookup

# Published sharpened cone-response matrices (rows: L, M, S from X, Y, Z).
CHROMATIC_ADAPTATION_TRANSFORMS: dict[str, np.ndarray] = {
    "XYZ Scaling": np.eye(3),
    # Von Kries / Hunt-Pointer-Estevez, equal-energy normalised (Fairchild 2013, eq. 9.2).
    "Von Kries": np.array(
        [[0.40024, 0.70760, -0.08081], [-0.22630, 1.16532, 0.04570], [0.00000, 0.00000, 0.91822]]
    ),
    # Lam (1985), linearised Bradford (Lindbloom; Fairchild 2013 section 9.5).
    "Bradford": np.array(
        [[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367], [0.0389, -0.0685, 1.0296]]
    ),
    # CIECAM02 (CIE 159:2004; Moroney et al. 2002).
    "CAT02": np.array(
        [[0.7328, 0.4296, -0.1624], [-0.7036, 1.6975, 0.0061], [0.0030, 0.0136, 0.9834]]
    ),
    # CAM16 (Li et al. 2017).
    "CAT16": np.array(
        [
            [0.401288, 0.650173, -0.051461],
            [-0.250268, 1.204414, 0.045854],
            [-0.002079, 0.048952, 0.953127],
        ]
    ),
}


def _cat_matrix(method: str) -> np.ndarray:
    if not isinstance(method, str):
        raise TypeError(f"`method` must be a str, got {type(method).__name__}.")
    return lookup(CHROMATIC_ADAPTATION_TRANSFORMS, method, "chromatic adaptation method")


def matrix_chromatic_adaptation(
    XYZ_w: Float[ArrayLike, "*#batch 3"],
    XYZ_wr: Float[ArrayLike, "*#batch 3"],
    method: str = "CAT02",
) -> Float[Array, "... 3 3"]:
    """The (..., 3, 3) von Kries adaptation matrix from white `XYZ_w` to white `XYZ_wr`.

    ??? cite "References"
        `Fairchild2013` chapter 9; `Lam1985`; `Moroney2002`; `Li2017`.

    Arguments: whites (..., 3) [dimensionless, Y = 1]. Returns (..., 3, 3) [dimensionless].
    """
    w = check_last_axis(as_float_array(XYZ_w, "XYZ_w"), "XYZ_w", 3)
    wr = check_last_axis(as_float_array(XYZ_wr, "XYZ_wr"), "XYZ_wr", 3)
    M_np = _cat_matrix(method)
    check_broadcastable(("XYZ_w", w), ("XYZ_wr", wr))
    w, wr = jnp.broadcast_arrays(w, wr.astype(w.dtype))
    dtype = w.dtype
    M = jnp.asarray(M_np, dtype=dtype)
    M_inv = jnp.asarray(np.linalg.inv(M_np), dtype=dtype)
    gain = (wr @ M.T) / (w @ M.T)  # (..., 3) LMS_wr / LMS_w
    return M_inv @ (gain[..., :, None] * M)


def chromatic_adaptation(
    XYZ: Float[ArrayLike, "*#batch 3"],
    XYZ_w: Float[ArrayLike, "*#batch 3"],
    XYZ_wr: Float[ArrayLike, "*#batch 3"],
    method: str = "CAT02",
) -> Float[Array, "... 3"]:
    """Adapt `XYZ` seen under the white `XYZ_w` to the reference white `XYZ_wr` (von Kries).

    **Arguments:**

    - `XYZ`: stimulus (..., 3). [dimensionless, same scale as the whites]
    - `XYZ_w`: white of the test condition (..., 3).
    - `XYZ_wr`: white of the reference condition (..., 3).
    - `method`: "CAT02" (default), "CAT16", "Bradford", "Von Kries" or "XYZ Scaling".

    **Returns:**

    Corresponding colour (..., 3); `XYZ_w` maps to `XYZ_wr` exactly.

    ??? cite "References"
        `Fairchild2013` chapter 9; `Lam1985` (Bradford); `Moroney2002` (CAT02); `Li2017` (CAT16).
    """
    XYZ = check_last_axis(as_float_array(XYZ, "XYZ"), "XYZ", 3)
    w = check_last_axis(as_float_array(XYZ_w, "XYZ_w"), "XYZ_w", 3).astype(XYZ.dtype)
    wr = check_last_axis(as_float_array(XYZ_wr, "XYZ_wr"), "XYZ_wr", 3).astype(XYZ.dtype)
    check_broadcastable(("XYZ", XYZ), ("XYZ_w", w), ("XYZ_wr", wr))
    XYZ, w, wr = jnp.broadcast_arrays(XYZ, w, wr)
    M_np = _cat_matrix(method)
    M = jnp.asarray(M_np, dtype=XYZ.dtype)
    M_inv = jnp.asarray(np.linalg.inv(M_np), dtype=XYZ.dtype)
    lms = XYZ @ M.T
    gain = (wr @ M.T) / (w @ M.T)
    return (lms * gain) @ M_inv.T
