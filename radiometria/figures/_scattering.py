"""Figures for `radiometria.scattering`."""

from ._registry import figure, save  # noqa: F401
