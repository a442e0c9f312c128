"""Figures for `radiometria.render`."""

from ._registry import figure, save  # noqa: F401
