"""Shapes, intersection and traversal back ends (thesis ch. 8), one concept per module."""
