"""mkdocs hook: regenerate the figures that the site shows, with the library itself."""

from pathlib import Path

SHOWN = ["fig_9_cornell_box", "fig_2_2_chromaticity"]


def on_pre_build(config, **kwargs):
    from radiometria.figures import make_figures

    out = Path(config["docs_dir"]) / "figures"
    make_figures(out, SHOWN, smoke=False)
