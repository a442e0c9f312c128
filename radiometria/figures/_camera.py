"""Figures for `radiometria.camera`."""

from ._registry import figure, save  # noqa: F401
