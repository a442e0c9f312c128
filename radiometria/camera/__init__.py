"""Camera (thesis section 2.3): pinhole projection, reconstruction filters and film."""
