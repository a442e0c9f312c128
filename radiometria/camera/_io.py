"""Image files (`radiometria._image_files`, NumPy-only so that the command line writes images
without importing JAX's modules), exported by `radiometria.camera`."""

from .._image_files import (
    read_exr as read_exr,
    read_hdr as read_hdr,
    read_spectral_exr as read_spectral_exr,
    spectral_channel_name as spectral_channel_name,
    write_exr as write_exr,
    write_png as write_png,
    write_spectral_exr as write_spectral_exr,
)
