r"""Per-strategy images of bidirectional path tracing (pbrt's `visualizestrategies` and
`visualizeweights`; thesis ch. 9).

`bdpt_strategy_images` renders, for every strategy $(s, t)$ of `BDPT` ($s$ light and $t$
camera vertices, $s + t - 1$ segments), the image of that strategy alone, through the normal
`render` driver: `BDPT(select=[s, t, weighted])` evaluates the one strategy per sample (the
camera-ray part for $t \ge 2$, splats for $t = 1$, normalised as the full image's). The
strategy is a traced value, so one compiled step serves every strategy of an image size.

- MIS-weighted (`weighted=True`): the images of all strategies sum to the `bdpt` image of the
  same samples, and those of one path length $k$ ($s + t - 1 = k$) sum to the image of the
  paths of exactly $k$ segments (`Veach1997` eq. 10.9: the weights of a path's strategies sum
  to 1).
- Unweighted (`weighted=False`): each image is an unbiased estimate, alone, of that same
  length-$k$ image wherever the strategy can sample the paths (not through specular vertices,
  not hitting point or spot lights): `Veach1997` fig. 10.3 shows why they differ in noise.
"""

import jax.numpy as jnp
import numpy as np

from ._driver import render
from ._integrators import BDPT

__all__ = ["bdpt_strategy_images"]


def bdpt_strategy_images(
    scene,
    *,
    max_depth: int,
    spp: int,
    weighted: bool = True,
    heuristic: str = "power",
    strategies=None,
    **render_kwargs,
) -> dict[tuple[int, int], np.ndarray]:
    r"""The image of each bidirectional strategy $(s, t)$ alone (module docstring).

    **Arguments:**

    - `scene`: what `radiometria.render.render` takes (a built-in name, a file, a scene).
    - `max_depth`: largest number of path segments (`BDPT`'s), a static int >= 1.
    - `spp`: samples per pixel, >= 1 (the same samples for every strategy: with the same
        `seed` and sampler the weighted images sum to the `bdpt` image of that render).
    - `weighted`: multiply each strategy by its MIS weight (default), or not (each image is
        then an unbiased estimate of its path length's image on its own).
    - `heuristic`: `"power"` or `"balance"` (`BDPT`'s).
    - `strategies`: the `(s, t)` pairs to render; default every pair of `BDPT.strategies()`.
    - `render_kwargs`: passed to `render` (`seed`, `width`, `height`, `sampler`, `rfilter`,
        `return_xyz`, `progress`, ...), not `integrator`.

    **Returns:**

    `{(s, t): image (H, W, 3)}` in `render`'s unit (linear sRGB or XYZ). [radiance-like]

    ??? cite "References"
        `Veach1997` §10.2-10.3 (fig. 10.3); `Pharr2016` §16.3.4 (`visualizestrategies`,
        `visualizeweights`).
    """
    if "integrator" in render_kwargs:
        raise TypeError("bdpt_strategy_images renders BDPT itself; do not pass `integrator`.")
    if not isinstance(weighted, bool):
        raise TypeError(f"`weighted` must be a bool, got {type(weighted).__name__} {weighted!r}.")
    base = BDPT(max_depth=max_depth, heuristic=heuristic)
    cam, light = base.strategies()
    valid = set(cam + light)
    pairs = sorted(valid) if strategies is None else [tuple(int(v) for v in p) for p in strategies]
    bad = [p for p in pairs if p not in valid]
    if bad:
        raise ValueError(
            f"strategies {bad} are not strategies of BDPT(max_depth={max_depth}): (s, t) with "
            f"t >= 1, s >= 0 and 2 <= s + t <= max_depth + 1."
        )
    render_kwargs.setdefault("progress", False)
    images = {}
    for s, t in pairs:  # one compiled step for all: the strategy is a traced value
        select = jnp.asarray([s, t, int(weighted)], jnp.int32)
        integrator = BDPT(max_depth=max_depth, heuristic=heuristic, select=select)
        images[(s, t)] = np.asarray(render(scene, spp=spp, integrator=integrator, **render_kwargs))
    return images
