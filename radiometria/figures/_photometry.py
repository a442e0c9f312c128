"""Figures for `radiometria.photometry`."""

from ._registry import figure, save  # noqa: F401
