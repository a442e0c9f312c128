"""Figures for `radiometria.montecarlo`."""

from ._registry import figure, save  # noqa: F401
