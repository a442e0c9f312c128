"""Figures for `radiometria.upsampling`."""

from ._registry import figure, save  # noqa: F401
