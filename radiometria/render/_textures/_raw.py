"""Images looked up as numbers, not spectra: normal maps and bump maps (Mitsuba's `eval_3` and
`eval_1` of a `bitmap`, with `eval_1_grad`, the gradient of the interpolation in uv)."""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..._checks import device_array
from ._bitmap import FILTER_TYPES, WRAP_MODES, _wrap, uv_transform

__all__ = ["RawImage"]


class RawImage(eqx.Module):
    r"""An image of `c` numbers per texel, looked up at uv (`to_uv` first) with Mitsuba's
    `bitmap` conventions: texel $(i, j)$ (column, row 0 at the top) centred at
    $((i + 1/2)/w, (j + 1/2)/h)$, `bilinear` or `nearest`, `repeat`/`mirror`/`clamp`.

    `grad(uv)` is the derivative of the bilinear interpolation with respect to the surface's
    $(u, v)$ [1 per uv unit], as Mitsuba's `eval_1_grad` computes it: the per-texel
    differences mapped by the transposed `to_uv`, then scaled by the resolution (the chain
    rule exactly when the image is square or `to_uv` diagonal; 0 for `nearest`).

    **Fields:**

    - `values`: `(h, w, c)` texel values [1].
    - `to_uv`: `(3, 3)` affine map of `(u, v, 1)`.
    - `filter_type`, `wrap_mode`: static strings.

    ??? cite "References"
        `Jakob2022` (`bitmap`: `eval_1_grad`); `Pharr2023` §10.4.
    """

    values: Float[Array, "h w c"]
    to_uv: Float[Array, "3 3"]
    filter_type: str = eqx.field(static=True, default="bilinear")
    wrap_mode: str = eqx.field(static=True, default="repeat")

    @classmethod
    def from_array(cls, values, *, filter_type="bilinear", wrap_mode="repeat", to_uv=None,
                   dtype=jnp.float32) -> "RawImage":  # fmt: skip
        """From `(h, w, c)` finite texel values (NumPy)."""
        x = np.asarray(values, np.float64)
        if x.ndim != 3 or min(x.shape) < 1 or not np.all(np.isfinite(x)):
            raise ValueError(f"texel values must be a finite (h, w, c) array, got {x.shape}.")
        if filter_type not in FILTER_TYPES or wrap_mode not in WRAP_MODES:
            raise ValueError(f"filter_type must be one of {FILTER_TYPES} and wrap_mode one of "
                             f"{WRAP_MODES}, got {filter_type!r}, {wrap_mode!r}.")  # fmt: skip
        return cls(device_array(x, dtype), device_array(uv_transform(to_uv), dtype),
                   filter_type, wrap_mode)  # fmt: skip

    def _setup(self, uv):
        uv = uv.astype(self.to_uv.dtype)
        u = self.to_uv[0, 0] * uv[..., 0] + self.to_uv[0, 1] * uv[..., 1] + self.to_uv[0, 2]
        v = self.to_uv[1, 0] * uv[..., 0] + self.to_uv[1, 1] * uv[..., 1] + self.to_uv[1, 2]
        h, w = self.values.shape[:2]

        def texel(i, j):
            return self.values[_wrap(j, h, self.wrap_mode), _wrap(i, w, self.wrap_mode)]

        return u, v, w, h, texel

    def __call__(self, uv: Float[Array, "n _"]) -> Float[Array, "n c"]:
        """The texel values at `uv` [1]."""
        u, v, w, h, texel = self._setup(uv)
        if self.filter_type == "nearest":
            return texel(jnp.floor(u * w).astype(jnp.int32), jnp.floor(v * h).astype(jnp.int32))
        x, y = u * w - 0.5, v * h - 0.5
        x0, y0 = jnp.floor(x), jnp.floor(y)
        wx, wy = (x - x0)[..., None], (y - y0)[..., None]
        i, j = x0.astype(jnp.int32), y0.astype(jnp.int32)
        top = (1 - wx) * texel(i, j) + wx * texel(i + 1, j)
        bottom = (1 - wx) * texel(i, j + 1) + wx * texel(i + 1, j + 1)
        return (1 - wy) * top + wy * bottom

    def grad(self, uv: Float[Array, "n _"]) -> Float[Array, "n c 2"]:
        """d(value)/d(u, v) at `uv` [1 per uv unit]."""
        u, v, w, h, texel = self._setup(uv)
        if self.filter_type == "nearest":
            return jnp.zeros(uv.shape[:-1] + (self.values.shape[2], 2), self.values.dtype)
        x, y = u * w - 0.5, v * h - 0.5
        x0, y0 = jnp.floor(x), jnp.floor(y)
        wx, wy = (x - x0)[..., None], (y - y0)[..., None]
        i, j = x0.astype(jnp.int32), y0.astype(jnp.int32)
        f00, f10 = texel(i, j), texel(i + 1, j)
        f01, f11 = texel(i, j + 1), texel(i + 1, j + 1)
        dx = (1 - wy) * (f10 - f00) + wy * (f11 - f01)  # per texel
        dy = (1 - wx) * (f01 - f00) + wx * (f11 - f10)
        # Mitsuba's order: the transposed to_uv on the per-texel differences, then the
        # resolution (the chain rule when the image is square or to_uv is diagonal).
        a = self.to_uv
        du = (a[0, 0] * dx + a[1, 0] * dy) * w
        dv = (a[0, 1] * dx + a[1, 1] * dy) * h
        return jnp.stack([du, dv], axis=-1)
