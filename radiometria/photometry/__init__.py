"""Photometry (thesis section 2.1): luminous efficiency functions and luminous quantities."""
