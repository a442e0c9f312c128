"""Figures for `radiometria.colorimetry`."""

from ._registry import figure, save  # noqa: F401
