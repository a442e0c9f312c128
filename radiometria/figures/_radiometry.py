"""Figures for `radiometria.radiometry`."""

from ._registry import figure, save  # noqa: F401
