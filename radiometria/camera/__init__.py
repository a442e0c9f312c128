"""Camera (thesis section 2.3): pinhole projection, reconstruction filters and film.

- `_pinhole`: coordinate spaces, `look_at`, the projection matrices of eq. 2.28-2.30,
  `PinholeCamera`, `generate_ray` and its inverse `project` (section 2.3.1);
- `_filters`: box, tent, Gaussian, Mitchell-Netravali and Lanczos filters with filter
  importance sampling (section 2.3.2, eq. 2.31-2.35);
- `_film`: spectral samples to XYZ, per-pixel accumulation (eq. 2.35) and splatting (eq. 2.34),
  development to linear RGB;
- `_io`: OpenEXR (RGB and spectral) and sRGB PNG files, written atomically.
"""

from ._film import (
    Film as Film,
    film_add_samples as film_add_samples,
    film_add_XYZ as film_add_XYZ,
    film_develop as film_develop,
    film_merge as film_merge,
    film_samples_to_XYZ as film_samples_to_XYZ,
    film_to_rgb as film_to_rgb,
    splat_samples as splat_samples,
)
from ._filters import (
    AbstractFilter as AbstractFilter,
    BoxFilter as BoxFilter,
    GaussianFilter as GaussianFilter,
    LanczosFilter as LanczosFilter,
    MitchellFilter as MitchellFilter,
    TentFilter as TentFilter,
)
from ._io import (
    read_exr as read_exr,
    read_spectral_exr as read_spectral_exr,
    spectral_channel_name as spectral_channel_name,
    write_exr as write_exr,
    write_png as write_png,
    write_spectral_exr as write_spectral_exr,
)
from ._pinhole import (
    PinholeCamera as PinholeCamera,
    fov_x_deg as fov_x_deg,
    generate_ray as generate_ray,
    look_at as look_at,
    perspective as perspective,
    perspective_frustum as perspective_frustum,
    project as project,
)
