"""Figures for the bidirectional methods (thesis ch. 9): path tracing, light tracing,
bidirectional path tracing and Metropolis light transport on one hard scene at equal time, and
the image of each bidirectional strategy (s, t)."""

import json
import tempfile
import time
from importlib import resources
from pathlib import Path

import jax
import numpy as np

from ..camera import BoxFilter
from ..render import (
    BDPT,
    PSSMLT,
    OwenSobol,
    Path as PathTracer,
    PTracer,
    bdpt_strategy_images,
    compile_scene,
    load_scene,
    render,
)
from ._registry import figure, save
from ._render import _display

__all__ = ["bidirectional_data", "glass_panel_scene", "rel_mse", "strategies_data"]

DEPTH = 4  # path segments of fig. 9 (bidirectional): one compiled program per integrator
STRATEGY_DEPTH = 3  # path segments of the strategy grid


def rel_mse(image: np.ndarray, reference: np.ndarray, eps: float = 1e-2) -> float:
    """Relative MSE: the mean of (x - ref)^2 / (ref^2 + eps) over pixels and channels. [1]"""
    image, reference = np.asarray(image, np.float64), np.asarray(reference, np.float64)
    return float(np.mean((image - reference) ** 2 / (reference**2 + eps)))


def glass_panel_scene(folder: Path | str) -> Path:
    """The built-in Cornell box with a thin glass panel (`thindielectric`) 2 cm below its
    light, covering it (|x|, |z - 0.01| <= 0.3 at y = 0.97; the light is |x| <= 0.23,
    -0.18 <= z <= 0.2 at y = 0.99): next-event estimation's shadow rays stop at the panel, so
    the path tracer finds the light only through BSDF samples that cross it. Written as a
    JSON scene into `folder`; returns its path (`benchmarks/bench_bidirectional.py`'s hard
    scene)."""
    text = resources.files("radiometria.render").joinpath("data", "cornell_box.json")
    scene = json.loads(text.read_text("utf-8"))
    scene["materials"]["panel"] = {"type": "thindielectric"}
    y, x0, x1, z0, z1 = 0.97, -0.3, 0.3, -0.29, 0.31
    scene["shapes"].append({
        "name": "glass-panel",
        "material": "panel",
        "vertices": [[x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]],
        "faces": [[0, 1, 2], [0, 2, 3]],
    })  # fmt: skip
    path = Path(folder) / "cornell_glass_panel.json"
    path.write_text(json.dumps(scene))
    return path


def _timed(fn):
    t0 = time.perf_counter()
    image = np.asarray(fn(), np.float64)
    return image, time.perf_counter() - t0


def bidirectional_data(
    *, smoke: bool = False, size: int | None = None, ref_spp: int | None = None,
    bdpt_spp: int | None = None,
) -> dict:  # fmt: skip
    """What fig. 9 (bidirectional) plots: the glass-panel Cornell box (`glass_panel_scene`)
    rendered by `path`, `ptracer`, `bdpt` and `pssmlt` at about equal time.

    `size` (16 px in smoke mode, else 32), `max_depth` `DEPTH`, box filter. The reference is
    `path` at `ref_spp` (512 or 4096 spp, seed 1000). `bdpt` renders `bdpt_spp` (8 or 32)
    samples per pixel; each other integrator's sample count (mutations per pixel for
    `pssmlt`) is set from timed 16- and 64-spp renders after its compiling warm-up (time =
    fixed + per-spp cost), so that its time matches bdpt's, then it is rendered and timed
    again. Returns `size`, `reference`, and for
    each integrator name `images[name]` (linear sRGB), `spp[name]`, `seconds[name]` [s] and
    `rel_mse[name]` against the reference.
    """
    size = size if size is not None else (16 if smoke else 32)
    ref_spp = ref_spp if ref_spp is not None else (512 if smoke else 4096)
    bdpt_spp = bdpt_spp if bdpt_spp is not None else (8 if smoke else 32)
    with tempfile.TemporaryDirectory() as tmp:
        description = load_scene(glass_panel_scene(tmp))
    scene, camera, _ = compile_scene(description, width=size, height=size)
    box = BoxFilter()
    quantum = 4  # samples per pixel per step: one compiled step for every sample count
    integrators = {
        "path": PathTracer(max_depth=DEPTH),
        "ptracer": PTracer(max_depth=DEPTH),
        "bdpt": BDPT(max_depth=DEPTH),
        "pssmlt": PSSMLT(max_depth=DEPTH, chains=4 * size, bootstrap_samples=2 * size * size),
    }

    def run(name, spp, seed):
        return render(
            scene, camera=camera, rfilter=box, spp=spp, seed=seed, integrator=integrators[name],
            sampler=OwenSobol(), batch=size * size * quantum, progress=False,
        )  # fmt: skip

    # bdpt first: its time at bdpt_spp is the budget. Each integrator's time is fitted as
    # fixed + per_spp x spp from timed renders at 16 and 64 spp after its compiling warm-up
    # (pssmlt's bootstrap is a fixed cost), and its sample count set to fit the budget.
    # Compiled programs are dropped after each integrator (memory: four integrators' programs
    # in one figure; the heap they freed serves the next one).
    images, spp, seconds = {}, {}, {}
    budget = reference = None
    lo, hi = 4 * quantum, 16 * quantum  # long enough to time on a busy CPU
    for i, name in enumerate(["bdpt", "path", "ptracer", "pssmlt"]):
        run(name, quantum, 7)  # compiles
        t1 = _timed(lambda n=name: run(n, lo, 8))[1]
        t2 = _timed(lambda n=name: run(n, hi, 9))[1]
        per_spp = max((t2 - t1) / (hi - lo), 0.1 * t2 / hi)
        fixed = max(t1 - lo * per_spp, 0.0)
        if budget is None:
            budget = fixed + per_spp * bdpt_spp
        n = bdpt_spp if name == "bdpt" else (budget - fixed) / per_spp
        spp[name] = max(quantum, quantum * round(n / quantum))
        images[name], seconds[name] = _timed(lambda n=name, i=i: run(n, spp[n], 100 + i))
        if name == "path":
            reference = np.asarray(run("path", ref_spp, 1000), np.float64)
        jax.clear_caches()
    errors = {name: rel_mse(image, reference) for name, image in images.items()}
    return {
        "size": size,
        "reference": reference,
        "ref_spp": ref_spp,
        "images": images,
        "spp": spp,
        "seconds": seconds,
        "rel_mse": errors,
    }


@figure("fig_9_bidirectional")
def fig_9_bidirectional(out_dir, *, smoke: bool = False):
    """A Cornell box lit through a thin glass panel below its light, rendered by path tracing,
    light tracing, bidirectional path tracing and primary-sample-space MLT at about equal time
    (the data are `bidirectional_data()`); relative MSE against a high-spp path-traced
    reference in the captions. Light tracing cannot show the light seen through the panel
    (no camera connection crosses a specular surface), so its ceiling stays dark there; MLT
    spends its mutations where the image is bright (the light and the lit ceiling)."""
    import matplotlib.pyplot as plt

    data = bidirectional_data(smoke=smoke)
    names = ["path", "ptracer", "bdpt", "pssmlt"]
    fig, axes = plt.subplots(1, 5, figsize=(13.0, 3.3), layout="constrained")
    exposure = 0.18 / max(float(np.mean(data["reference"])), 1e-12)
    for ax, name in zip(axes, names, strict=False):
        ax.imshow(_display(data["images"][name], exposure), interpolation="nearest")
        ax.set_title(
            f"{name}: {data['spp'][name]} spp, {data['seconds'][name]:.2f} s\n"
            f"relMSE {data['rel_mse'][name]:.3g}",
            fontsize=9,
        )
    axes[-1].imshow(_display(data["reference"], exposure), interpolation="nearest")
    axes[-1].set_title(f"reference: path, {data['ref_spp']} spp", fontsize=9)
    for ax in axes:
        ax.set_axis_off()
    fig.suptitle(
        f"Light behind a thin glass panel, {data['size']} x {data['size']} px, max_depth "
        f"{DEPTH}, about equal time (pssmlt: mutations per pixel)",
        fontsize=10,
    )
    return save(fig, out_dir, "fig_9_bidirectional")


def strategies_data(*, smoke: bool = False, size: int | None = None, spp: int | None = None):
    """What fig. 9 (strategies) plots: the image of every strategy (s, t) of `BDPT` with
    `max_depth` `STRATEGY_DEPTH` on the Cornell box, MIS-weighted and unweighted
    (`radiometria.render.bdpt_strategy_images`), and the full `bdpt` image of the same
    samples. `size` 16 or 32 px, `spp` 4 or 32, seed 0, box filter. Returns `size`, `spp`,
    `weighted` and `unweighted` (dicts `(s, t) -> (size, size, 3)` linear sRGB) and `full`."""
    size = size if size is not None else (16 if smoke else 32)
    spp = spp if spp is not None else (4 if smoke else 32)
    kwargs = dict(width=size, height=size, seed=0, sampler=OwenSobol(), rfilter=BoxFilter(),
                  batch=size * size * spp)  # fmt: skip
    weighted = bdpt_strategy_images("cornell-box", max_depth=STRATEGY_DEPTH, spp=spp, **kwargs)
    unweighted = bdpt_strategy_images(
        "cornell-box", max_depth=STRATEGY_DEPTH, spp=spp, weighted=False, **kwargs
    )
    full = np.asarray(
        render("cornell-box", spp=spp, integrator=BDPT(max_depth=STRATEGY_DEPTH),
               progress=False, **kwargs)
    )  # fmt: skip
    return {"size": size, "spp": spp, "weighted": weighted, "unweighted": unweighted,
            "full": full}  # fmt: skip


@figure("fig_9_bdpt_strategies")
def fig_9_bdpt_strategies(out_dir, *, smoke: bool = False):
    """The strategies of bidirectional path tracing on the Cornell box: row k is the paths of
    k segments, column s the strategy with s light and t = k + 1 - s camera vertices (s = 0:
    the camera path hits the light; t = 1: light tracing). Left block: MIS-weighted (power
    heuristic; each row sums to that length's image); right block: unweighted (each an
    estimate of the whole row's image, with its own noise). The data are
    `strategies_data()`."""
    import matplotlib.pyplot as plt

    data = strategies_data(smoke=smoke)
    depth = STRATEGY_DEPTH
    cols = depth + 1
    fig, axes = plt.subplots(
        depth, 2 * cols, figsize=(2.0 * 2 * cols, 2.1 * depth), layout="constrained"
    )
    exposure = 0.18 / max(float(np.mean(data["full"])), 1e-12)
    for block, key in enumerate(("weighted", "unweighted")):
        images = data[key]
        for k in range(1, depth + 1):
            for s in range(cols):
                ax = axes[k - 1, block * cols + s]
                ax.set_axis_off()
                t = k + 1 - s
                if s > k:
                    continue
                ax.imshow(_display(images[(s, t)], exposure), interpolation="nearest")
                ax.set_title(f"{key[0]}: s={s}, t={t}", fontsize=8)
    fig.suptitle(
        f"bdpt strategies (s, t), rows: path segments k = s + t - 1 = 1..{depth}; "
        f"left MIS-weighted, right unweighted; {data['size']} px, {data['spp']} spp",
        fontsize=10,
    )
    return save(fig, out_dir, "fig_9_bdpt_strategies")
