"""Colorimetry (thesis section 2.2): CIE observers, tristimulus values, colour spaces."""
