"""`radiometria lut build` and `radiometria lut check` (wired in `radiometria/cli.py`)."""

import argparse
import json
import os
import sys
import time
from pathlib import Path

import jax

from .._checks import check_positive_int
from ..colorimetry import get_colourspace
from ._fit_lut import fit_lut
from ._io import load_lut, save_lut
from ._roundtrip import (
    roundtrip_delta_E,
    roundtrip_grid_rgb,
    roundtrip_random_rgb,
    roundtrip_statistics,
)


def _use_all_cpu_cores() -> None:
    """Run a multi-core CPU as one JAX device per core (XLA runs the table's column blocks
    in parallel that way), if the JAX backend has not started yet; harmless otherwise."""
    try:
        if jax.config.jax_num_cpu_devices in (-1, None):
            jax.config.update("jax_num_cpu_devices", max(1, os.cpu_count() or 1))
    except Exception:  # noqa: BLE001  (backend already initialised: keep its devices)
        pass


def lut_build(args: argparse.Namespace) -> int:
    """`radiometria lut build --space NAME --res N --out FILE`: fit and write a table.

    Prints the per-entry convergence summary; exits 1 if an entry failed to converge (it
    is still written, with its best fit), 0 otherwise (entries that no sigmoid spectrum
    reaches, in wide-gamut spaces, are reported but are not failures).
    """
    from tqdm import tqdm

    res = check_positive_int(args.res, "--res", minimum=2)
    space = get_colourspace(args.space).name
    out = Path(args.out)
    if out.suffix.lower() not in (".npz", ".coeff"):
        raise ValueError(f"--out {str(out)!r}: the file name must end in .npz or .coeff.")
    if not out.parent.exists():
        raise ValueError(f"--out {str(out)!r}: directory {str(out.parent)!r} does not exist.")
    _use_all_cpu_cores()
    devices = jax.devices() if len(jax.devices()) > 1 else None
    bar = tqdm(total=3 * res * res, desc=f"lut {space} res {res}", unit="col", file=sys.stderr)

    def progress(stage: str, done: int, total: int) -> None:
        if stage == "sweep":
            bar.n = done
            bar.refresh()
        else:
            bar.set_postfix_str(stage)

    t0 = time.perf_counter()
    fit = fit_lut(space, res, devices=devices, progress=progress, throw=False)
    bar.close()
    save_lut(fit.lut, out, fit_settings=fit.settings)
    summary = fit.summary()
    summary["wall_seconds"] = round(time.perf_counter() - t0, 3)
    print(f"wrote {out} ({space}, res {res})")
    print(json.dumps(summary, indent=2))
    if summary["not_converged"]:
        print(
            f"radiometria: warning: {summary['not_converged']} entries did not converge "
            "(best fits written).",
            file=sys.stderr,
        )
        return 1
    return 0


def lut_check(args: argparse.Namespace) -> int:
    """`radiometria lut check FILE --grid 33 --random 100000`: round-trip statistics.

    Reads and validates the table, then prints the CIEDE2000 round-trip error (RGB ->
    coefficients -> spectrum -> XYZ under the space's illuminant -> Lab, against the input)
    on the grid of encoded values and on uniform random linear colours, computed in float64.
    """
    grid = check_positive_int(args.grid, "--grid", minimum=2)
    n_random = check_positive_int(args.random, "--random", minimum=0)
    lut, info = load_lut(args.file, with_info=True)
    print(f"{args.file}: {info['format']}, {lut.colourspace}, res {lut.resolution}")
    with jax.enable_x64(True):
        sets = [(f"grid {grid}^3 (encoded)", roundtrip_grid_rgb(grid, lut.colourspace))]
        if n_random:
            sets.append((f"random {n_random} (linear)", roundtrip_random_rgb(n_random)))
        for name, rgb in sets:
            de, _ = roundtrip_delta_E(lut, rgb)
            s = roundtrip_statistics(de, rgb)
            worst = ", ".join(f"{v:.6g}" for v in s["worst_rgb"])
            print(
                f"{name}: CIEDE2000 mean {s['mean']:.4f}  median {s['median']:.4f}  "
                f"p99 {s['p99']:.4f}  max {s['max']:.4f} at linear rgb ({worst})"
            )
    return 0
