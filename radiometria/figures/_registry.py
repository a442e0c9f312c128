"""Registry of thesis figures: each figure is a function `fn(out_dir, *, smoke) -> list[Path]`."""

from collections.abc import Callable
from pathlib import Path

from .._io import atomic_write_path

FigureFn = Callable[..., list[Path]]
FIGURES: dict[str, FigureFn] = {}


def figure(name: str) -> Callable[[FigureFn], FigureFn]:
    """Register a figure function under `name` (a file stem such as ``"fig_1_planck"``)."""

    def register(fn: FigureFn) -> FigureFn:
        if name in FIGURES:
            raise ValueError(f"Figure {name!r} is registered twice.")
        FIGURES[name] = fn
        return fn

    return register


def save(fig, out_dir: Path | str, stem: str, *, dpi: int = 150) -> list[Path]:
    """Write a matplotlib figure as `stem.png` and `stem.pdf` atomically; close it; return paths."""
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for ext in ("png", "pdf"):
        path = out_dir / f"{stem}.{ext}"
        atomic_write_path(path, lambda tmp: fig.savefig(tmp, dpi=dpi, bbox_inches="tight"))
        paths.append(path)
    plt.close(fig)
    return paths
