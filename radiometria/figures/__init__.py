"""Every figure of the thesis, regenerated from code (`radiometria figures --out DIR`).

One private module per chapter registers its figures in `FIGURES`; `make_figures` writes them.
Figures are PNG and PDF, made with a fixed seed; `smoke=True` shrinks sample counts for CI.
Importing this package leaves matplotlib's backend alone; the `radiometria figures` command
selects the non-interactive Agg backend itself, and headless sessions fall back to Agg anyway.
"""

from pathlib import Path

from .._checks import check_choice
from . import (
    _bidirectional,
    _camera,
    _colorimetry,
    _media,
    _montecarlo,
    _photometry,
    _radiometry,
    _render,
    _scattering,
    _upsampling,
)
from ._registry import FIGURES as FIGURES, figure as figure, save as save

del (
    _bidirectional,
    _camera,
    _colorimetry,
    _media,
    _montecarlo,
    _photometry,
    _radiometry,
    _render,
    _scattering,
    _upsampling,
)


def make_figures(
    out_dir: Path | str, names: list[str] | None = None, *, smoke: bool = False, progress=None
) -> list[Path]:
    """Write the named figures (all by default) into `out_dir`; return the written paths.

    **Arguments:**

    - `out_dir`: directory to write into; created if missing.
    - `names`: figure names from `FIGURES`; `None` for all of them.
    - `smoke`: shrink sample counts (for CI); the figures keep their layout.
    - `progress`: optional callable `progress(name)` called before each figure.
    """
    names = sorted(FIGURES) if names is None else names
    for name in names:
        check_choice(name, "figure", sorted(FIGURES))
    paths: list[Path] = []
    for name in names:
        if progress is not None:
            progress(name)
        paths += FIGURES[name](Path(out_dir), smoke=smoke)
    return paths
