"""Surfaces (thesis ch. 3): reflection, refraction, Fresnel equations and BxDFs."""
