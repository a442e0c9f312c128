"""RGB to spectrum (thesis section 2.2.3): sigmoid-polynomial spectra and coefficient tables."""
