"""Radiometry (thesis ch. 1, sections 1.4-1.5): Planck's law, spectra and radiometric quantities."""
